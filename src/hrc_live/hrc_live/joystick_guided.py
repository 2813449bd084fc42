"""The guided joystick set-up at a terminal: live values, one step at a time, a redo, a check.

A refreshed line shows every axis and button at every step; the operator pushes the chosen
stick in the direction that should mean "+" (slider up, right end of the pendulum up), lets go
(the largest deviation at rest gives the deadzone), and presses the deadman button if one is
wanted. Each step can be kept or redone; a last step shows the command the human node would
send while the operator moves the stick, and any one step can be redone from there before the
file is written (:class:`GuidedSetup`).
"""

import select
import sys
import time

from hrc_joystick_node.js_event import shape_axis
from hrc_live.joystick_watch import (chosen_axis, chosen_button, deadzone_from_rest, inversion,
                                     JoystickWatcher, MIN_DEFLECTION)

REFRESH_S = 0.1  # s between two refreshes of the live line (5x that when not a terminal)
# Seconds the released stick is watched for its rest noise.
REST_WATCH_S = 1.5


class Console:
    """Terminal output: a refreshed line on a terminal, plain lines otherwise."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stdout
        self.tty = self.stream.isatty()
        self._live = False

    def live(self, text: str) -> None:
        """Show ``text`` as the refreshed line (a new line each time when not a terminal)."""
        if self.tty:
            self.stream.write('\r\x1b[2K' + text)
            self._live = True
        else:
            self.stream.write(text + '\n')
        self.stream.flush()

    def say(self, text: str) -> None:
        """Print a message (ending a refreshed line first)."""
        if self._live:
            self.stream.write('\n')
            self._live = False
        self.stream.write(text + '\n')
        self.stream.flush()


def watch_until(watcher: JoystickWatcher, console: Console, seconds: float = None,
                until_enter: bool = False, show: bool = True, line=None) -> None:
    """Read the device, refreshing the live line, for ``seconds`` or until Enter is pressed.

    ``line`` returns the live line (default: every axis and button).
    """
    line = line or watcher.live_line
    deadline = None if seconds is None else watcher.clock() + seconds
    last_shown = 0.0
    while True:
        watcher.poll()
        if not watcher.device.present:
            raise RuntimeError(f'the joystick went away: {watcher.device.status}')
        now = watcher.clock()
        if show and now - last_shown >= (REFRESH_S if console.tty else 5 * REFRESH_S):
            console.live(line())
            last_shown = now
        if deadline is not None and now >= deadline:
            break
        if until_enter:
            ready, _, _ = select.select([sys.stdin], [], [], REFRESH_S)
            if ready:
                sys.stdin.readline()
                break
        else:
            time.sleep(min(REFRESH_S, max(0.0, deadline - now)) if deadline else REFRESH_S)
    watcher.poll()  # what came with the Enter key counts too
    if show:
        console.live(line())
        console.say('')


def read_answer() -> str:
    """Return the operator's next line, stripped and lower case."""
    return sys.stdin.readline().strip().lower()


def command_line(watcher: JoystickWatcher, chosen: dict) -> str:
    """Return the live check line: the raw axis and the command the human node would send."""
    axis = chosen['axis']
    raw = watcher.device.axis(axis)
    command = shape_axis(raw, chosen['deadzone'], chosen['invert'])
    button = chosen['enable_button']
    held = button < 0 or bool(watcher.device.buttons.get(button))
    if not held:
        command = 0.0
    bar = int(round(10 * command))
    gauge = ('-' * (10 + min(bar, 0)) + '#' * -min(bar, 0) + '|' + '#' * max(bar, 0)
             + '-' * (10 - max(bar, 0)))
    deadman = '' if button < 0 else (' deadman held' if held else ' deadman UP: zero')
    return f'axis {axis} reads {raw:+.2f} -> command {command:+.2f} [{gauge}]{deadman}'


class GuidedSetup:
    """Ask the operator step by step (:meth:`run`); the chosen settings are in ``chosen``.

    Live values show at every step. After each step the operator keeps it (Enter) or redoes it
    (r); a final step shows the command the human node would send while the operator moves the
    stick, and any step can be redone from there (its number) before the file is written.
    Flags given on the command line (``options``) skip their step.
    """

    def __init__(self, watcher: JoystickWatcher, options, console: Console):
        self.watcher, self.options, self.console = watcher, options, console
        self.chosen = {'axis': options.axis, 'invert': options.invert,
                       'deadzone': options.deadzone, 'enable_button': options.enable_button}
        steps = [('the axis and its direction', self.axis_step,
                  options.axis is None or options.invert is None),
                 ('the rest (deadzone)', self.rest_step, options.deadzone is None),
                 ('the deadman button', self.button_step, options.enable_button is None)]
        self.steps = [(name, step) for name, step, wanted in steps if wanted]

    def run(self) -> tuple:
        """Return (axis, invert, deadzone, enable_button, notes) once the operator is done."""
        self.console.say('Move the sticks and press the buttons: their values show below. '
                         'Press Enter to continue.')
        watch_until(self.watcher, self.console, until_enter=True)
        if self.chosen['axis'] is None and not any(step == self.axis_step
                                                   for _, step in self.steps):
            raise RuntimeError('no axis given')
        for index in range(len(self.steps)):
            self.run_step(index)
        while not self.checked():
            pass
        chosen = self.chosen
        return (chosen['axis'], chosen['invert'], chosen['deadzone'], chosen['enable_button'],
                'chosen with the guided set-up')

    def run_step(self, index: int) -> None:
        """Run step ``index`` until it succeeds and the operator keeps it."""
        name, step = self.steps[index]
        count = len(self.steps)
        while True:
            done = step()
            self.console.say(f'Step {index + 1} of {count} ({name}): press Enter to keep it, '
                             f'or r and Enter to redo it.' if done else
                             f'Step {index + 1} of {count} ({name}) failed: press Enter to '
                             f'redo it.')
            answer = read_answer()
            if done and answer != 'r':
                return

    def checked(self) -> bool:
        """Show the live command; return True when the operator writes the file."""
        self.console.say('Check: move the stick through its whole range (and release the '
                         'deadman button, if any); the command the person would send shows '
                         'live. Press Enter when done.')
        watch_until(self.watcher, self.console, until_enter=True,
                    line=lambda: command_line(self.watcher, self.chosen))
        redo = ' or a step number (' + ', '.join(
            f'{index + 1} = {name}' for index, (name, _) in enumerate(self.steps)) \
            + ') to redo it' if self.steps else ''
        self.console.say(f'Press Enter to write the file, c to check again{redo}.')
        answer = read_answer()
        if answer == '':
            return True
        if answer.isdigit() and 1 <= int(answer) <= len(self.steps):
            self.run_step(int(answer) - 1)
        return False

    def axis_step(self) -> bool:
        """Watch the operator push the stick to "+"; choose the axis and its direction."""
        watcher, console, chosen = self.watcher, self.console, self.chosen
        watcher.start()  # before asking: what the operator does next is all in the window
        console.say('Push the stick the person will use all the way in the direction that '
                    'should mean "+" (slider up, right end of the pendulum up), hold it there, '
                    'and press Enter.')
        watch_until(watcher, console, until_enter=True)
        detected = chosen_axis(watcher.watch) if self.options.axis is None else self.options.axis
        if detected is None or detected not in watcher.watch.axes:
            console.say(f'no axis moved by {MIN_DEFLECTION} or more: push the stick fully')
            return False
        chosen['axis'] = detected
        if self.options.invert is None:
            chosen['invert'] = inversion(watcher.watch.axes[detected])
        console.say(f'axis {detected}' + (' (inverted)' if chosen['invert'] else ''))
        return True

    def rest_step(self) -> bool:
        """Watch the released stick for REST_WATCH_S s; its largest deviation sets the deadzone."""
        watcher, console, chosen = self.watcher, self.console, self.chosen
        console.say('Let go of the stick and press Enter; then keep your hands off for '
                    f'{REST_WATCH_S:.1f} s (its rest position gives the deadzone).')
        watch_until(watcher, console, until_enter=True)
        watcher.start()
        watch_until(watcher, console, seconds=REST_WATCH_S, line=self._rest_line)
        rest = self._rest_largest()
        chosen['deadzone'] = deadzone_from_rest(rest)
        console.say(f'at rest the axis reads up to {rest:.3f} (the largest deviation seen): '
                    f'deadzone {chosen["deadzone"]}')
        return True

    def _rest_largest(self) -> float:
        trace = self.watcher.watch.axes.get(self.chosen['axis'])
        return trace.largest if trace is not None else 0.0

    def _rest_line(self) -> str:
        axis = self.chosen['axis']
        return (f'rest watch: axis {axis} reads {self.watcher.device.axis(axis):+.3f}, '
                f'largest so far {self._rest_largest():.3f}')

    def button_step(self) -> bool:
        """Watch the operator hold the deadman button (or none)."""
        watcher, console, chosen = self.watcher, self.console, self.chosen
        watcher.start()
        console.say('Press and hold the button that must be held to act (a deadman button) '
                    'and press Enter; or press Enter alone for none.')
        watch_until(watcher, console, until_enter=True)
        chosen['enable_button'] = chosen_button(watcher.held_buttons())
        console.say(f'enable button {chosen["enable_button"]}' if chosen['enable_button'] >= 0
                    else 'no enable button')
        return True
