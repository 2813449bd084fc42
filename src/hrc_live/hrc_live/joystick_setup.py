"""Joystick set-up helper: find the device, watch it live, pick the axis, write the human's YAML.

    hrc joystick setup --list
    hrc joystick setup /dev/input/js0 --output joystick.yaml      # guided
    hrc joystick setup /dev/input/js0 --non-interactive --detect 5

Guided (a terminal): a refreshed line shows every axis and button at every step; the operator
pushes the chosen stick in the direction that should mean "+" (slider up, right end of the
pendulum up), lets go (the largest deviation at rest gives the deadzone), and presses the
deadman button if one is wanted. Each step can be kept or redone; a last step shows the command
the human node would send while the operator moves the stick, and any one step can be redone
from there before the file is written.
``--non-interactive`` does the same from what the device reports during ``--detect`` seconds:
the axis moved most, its direction (inversion), its first value (the rest), the button held.
Flags (``--axis``, ``--invert``, ``--deadzone``, ``--enable-button``) override any detection.

The result is a parameter file for the human node (``human:`` / ``ros__parameters:`` with
``input: device``, ``device``, ``axis``, ``invert``, ``deadzone``, ``enable_button``), checked
against the human node's own parameter rules. The device is read with the human node's reader
(:mod:`hrc_joystick_node.js_event`), so a FIFO or a file carrying js_event records works too.
"""

import argparse
from dataclasses import dataclass, field
import fcntl
import glob
import os
import select
import sys
import time
import typing

import yaml

from hrc_common.contract import atomic_write
from hrc_common.params import as_dict, from_dict, ParameterError
from hrc_joystick_node.js_event import device_axis, JoystickDevice, shape_axis

DEVICE_PATTERN = '/dev/input/js*'
# Linux joystick ioctls (linux/joystick.h): _IOR('j', 0x11, __u8), _IOR('j', 0x12, __u8),
# _IOC(_IOC_READ, 'j', 0x13, len).
_IOC_READ = 2
JSIOCGAXES = (_IOC_READ << 30) | (1 << 16) | (ord('j') << 8) | 0x11
JSIOCGBUTTONS = (_IOC_READ << 30) | (1 << 16) | (ord('j') << 8) | 0x12
NAME_LENGTH = 128


def jsiocgname(length: int = NAME_LENGTH) -> int:
    """Return the JSIOCGNAME(len) request number."""
    return (_IOC_READ << 30) | (length << 16) | (ord('j') << 8) | 0x13


# Deadzone from the rest noise: this factor times the largest reading at rest, plus a margin,
# never below the human node's default nor above half the travel.
DEADZONE_FACTOR = 1.5
DEADZONE_MARGIN = 0.02
DEADZONE_DEFAULT = 0.05
DEADZONE_MAX = 0.5
# A stick counts as moved when it left its rest by at least this much (normalized).
MIN_DEFLECTION = 0.3
REFRESH_S = 0.1
# Seconds the released stick is watched for its rest noise.
REST_WATCH_S = 1.5


@dataclass
class DeviceInfo:
    """A joystick device found on this machine."""

    path: str
    name: str = ''
    axes: typing.Optional[int] = None
    buttons: typing.Optional[int] = None
    problem: str = ''

    def describe(self) -> str:
        """Return one line for the device list."""
        if self.problem:
            return f'{self.path}: {self.problem}'
        counts = ''
        if self.axes is not None:
            counts = f', {self.axes} axes, {self.buttons} buttons'
        return f'{self.path}: {self.name or "(no name: not a joystick device)"}{counts}'


def device_info(path: str) -> DeviceInfo:
    """Open ``path`` and ask the joystick driver for its name and counts (if it is one)."""
    info = DeviceInfo(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as error:
        info.problem = f'cannot open: {os.strerror(error.errno)}'
        return info
    try:
        buffer = bytearray(NAME_LENGTH)
        fcntl.ioctl(fd, jsiocgname(), buffer)
        info.name = buffer.split(b'\0', 1)[0].decode(errors='replace')
        count = bytearray(1)
        fcntl.ioctl(fd, JSIOCGAXES, count)
        info.axes = count[0]
        fcntl.ioctl(fd, JSIOCGBUTTONS, count)
        info.buttons = count[0]
    except OSError:
        pass  # a FIFO or a file: no driver to ask
    finally:
        os.close(fd)
    return info


def list_devices(pattern: str = DEVICE_PATTERN) -> list:
    """Return the joystick devices matching ``pattern``, sorted by path."""
    return [device_info(path) for path in sorted(glob.glob(pattern))]


@dataclass
class AxisTrace:
    """What one axis did while watched (normalized, Joy convention: stick up/left = +)."""

    first: float
    last: float
    peak: float                 # the value farthest from ``first``
    largest: float = 0.0        # the largest |value| seen in the window (the rest: its noise)

    def __post_init__(self):
        self.largest = max(self.largest, abs(self.first), abs(self.peak), abs(self.last))

    @property
    def deflection(self) -> float:
        """Return how far the axis went from its first value."""
        return abs(self.peak - self.first)


@dataclass
class Watch:
    """Axes and buttons of a device as reported during a watch window."""

    axes: typing.Dict[int, AxisTrace] = field(default_factory=dict)
    pressed: typing.Dict[int, float] = field(default_factory=dict)  # button -> s held
    events: int = 0


class JoystickWatcher:
    """Reads a device without blocking and keeps what the axes and buttons did."""

    def __init__(self, path: str, clock=time.monotonic):
        self.device = JoystickDevice(path, clock)
        self.clock = clock
        self.watch = Watch()
        self._pressed_since = {}

    def open(self, timeout: float) -> bool:
        """Open the device, retrying until ``timeout`` s (a FIFO waits for its writer)."""
        deadline = self.clock() + timeout
        while not self.device.open():
            if self.clock() >= deadline:
                return False
            time.sleep(0.05)
        return True

    def start(self) -> None:
        """Start a new watch window (axes' first values = their current values)."""
        self.poll()
        now = self.clock()
        self.watch = Watch()
        for number in self.device.axes:
            value = self.device.axis(number)
            self.watch.axes[number] = AxisTrace(value, value, value)
        self._pressed_since = {number: now for number, value in self.device.buttons.items()
                               if value}

    def poll(self) -> int:
        """Read what is available; return the number of events read."""
        events = self.device.poll()
        now = self.clock()
        for event in events:
            if event.is_axis:
                value = device_axis(event.value)
                trace = self.watch.axes.get(event.number)
                if trace is None:
                    self.watch.axes[event.number] = AxisTrace(value, value, value)
                    continue
                trace.last = value
                trace.largest = max(trace.largest, abs(value))
                if abs(value - trace.first) > abs(trace.peak - trace.first):
                    trace.peak = value
            elif event.value:
                self._pressed_since.setdefault(event.number, now)
            elif event.number in self._pressed_since:
                held = now - self._pressed_since.pop(event.number)
                self.watch.pressed[event.number] = self.watch.pressed.get(event.number, 0) + held
        self.watch.events += len(events)
        return len(events)

    def held_buttons(self) -> typing.Dict[int, float]:
        """Return button -> seconds held in this window (including those still held)."""
        now = self.clock()
        held = dict(self.watch.pressed)
        for number, since in self._pressed_since.items():
            held[number] = held.get(number, 0.0) + max(now - since, 1e-6)
        return held

    def live_line(self) -> str:
        """Return the current axes and buttons as one line."""
        axes = ' '.join(f'{number}:{self.device.axis(number):+.2f}'
                        for number in sorted(self.device.axes))
        buttons = ' '.join(f'{number}:{self.device.buttons[number]}'
                           for number in sorted(self.device.buttons))
        return f'axes {axes or "-"} | buttons {buttons or "-"}'

    def close(self) -> None:
        """Close the device."""
        self.device.close()


@dataclass
class JoystickSettings:
    """What the human node needs to read the joystick."""

    device: str
    axis: int
    invert: bool
    deadzone: float
    enable_button: int

    def parameters(self) -> dict:
        """Return the human node's parameters (``input: device`` and the five settings)."""
        return {'input': 'device', 'device': self.device, 'axis': self.axis,
                'invert': self.invert, 'deadzone': self.deadzone,
                'enable_button': self.enable_button}


def chosen_axis(watch: Watch) -> typing.Optional[int]:
    """Return the axis moved most (at least MIN_DEFLECTION), or None."""
    moved = [(trace.deflection, number) for number, trace in watch.axes.items()
             if trace.deflection >= MIN_DEFLECTION]
    return max(moved)[1] if moved else None


def inversion(trace: AxisTrace) -> bool:
    """Return True when the operator's "+" direction reads negative on this axis."""
    return trace.peak - trace.first < 0


def deadzone_from_rest(rest: float) -> float:
    """Return a deadzone that hides ``rest`` (largest |value| of the released stick)."""
    return round(min(DEADZONE_MAX, max(DEADZONE_DEFAULT,
                                       DEADZONE_FACTOR * abs(rest) + DEADZONE_MARGIN)), 3)


def chosen_button(held: dict) -> int:
    """Return the button held longest, or -1 (no enable button)."""
    return max(held, key=lambda number: (held[number], -number)) if held else -1


def settings_yaml(settings: JoystickSettings, detected: str = '') -> str:
    """Return the parameter file text for the human node."""
    document = {'human': {'ros__parameters': settings.parameters()}}
    header = ['# Joystick settings for the human node (written by hrc_live joystick_setup).',
              '# Use: session --human device --params <this file>, or',
              '#      ros2 run hrc_joystick_node human_node --ros-args --params-file <this file>']
    if detected:
        header.append(f'# {detected}')
    return '\n'.join(header) + '\n' + yaml.safe_dump(document, sort_keys=False)


def check_settings(settings: JoystickSettings) -> None:
    """Raise ParameterError if the human node would refuse these settings."""
    from hrc_joystick_node.human_core import HumanParams  # lazy: numpy (0.1 s), not for --help
    from_dict(HumanParams, {**as_dict(HumanParams()), **settings.parameters()})


def write_settings(path: str, settings: JoystickSettings, detected: str = '') -> None:
    """Check the settings and write them (atomically) to ``path``."""
    check_settings(settings)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    atomic_write(path, settings_yaml(settings, detected))


# ---------------------------------------------------------------------------- the command

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


def guided(watcher: JoystickWatcher, options, console: Console) -> tuple:
    """Ask the operator step by step; return (axis, invert, deadzone, enable_button, notes).

    Live values show at every step. After each step the operator keeps it (Enter) or redoes it
    (r); a final step shows the command the human node would send while the operator moves the
    stick, and any step can be redone from there (its number) before the file is written.
    """
    console.say('Move the sticks and press the buttons: their values show below. '
                'Press Enter to continue.')
    watch_until(watcher, console, until_enter=True)
    chosen = {'axis': options.axis, 'invert': options.invert, 'deadzone': options.deadzone,
              'enable_button': options.enable_button}

    def axis_step():
        watcher.start()  # before asking: what the operator does next is all in the window
        console.say('Push the stick the person will use all the way in the direction that '
                    'should mean "+" (slider up, right end of the pendulum up), hold it there, '
                    'and press Enter.')
        watch_until(watcher, console, until_enter=True)
        detected = chosen_axis(watcher.watch) if options.axis is None else options.axis
        if detected is None or detected not in watcher.watch.axes:
            console.say(f'no axis moved by {MIN_DEFLECTION} or more: push the stick fully')
            return False
        chosen['axis'] = detected
        if options.invert is None:
            chosen['invert'] = inversion(watcher.watch.axes[detected])
        console.say(f'axis {detected}' + (' (inverted)' if chosen['invert'] else ''))
        return True

    def rest_step():
        console.say('Let go of the stick and press Enter; then keep your hands off for '
                    f'{REST_WATCH_S:.1f} s (its rest position gives the deadzone).')
        watch_until(watcher, console, until_enter=True)
        watcher.start()

        def rest_line():
            trace = watcher.watch.axes.get(chosen['axis'])
            largest = trace.largest if trace is not None else 0.0
            return (f'rest watch: axis {chosen["axis"]} reads '
                    f'{watcher.device.axis(chosen["axis"]):+.3f}, largest so far {largest:.3f}')
        watch_until(watcher, console, seconds=REST_WATCH_S, line=rest_line)
        trace = watcher.watch.axes.get(chosen['axis'])
        rest = trace.largest if trace is not None else 0.0
        chosen['deadzone'] = deadzone_from_rest(rest)
        console.say(f'at rest the axis reads up to {rest:.3f} (the largest deviation seen): '
                    f'deadzone {chosen["deadzone"]}')
        return True

    def button_step():
        watcher.start()
        console.say('Press and hold the button that must be held to act (a deadman button) '
                    'and press Enter; or press Enter alone for none.')
        watch_until(watcher, console, until_enter=True)
        chosen['enable_button'] = chosen_button(watcher.held_buttons())
        console.say(f'enable button {chosen["enable_button"]}' if chosen['enable_button'] >= 0
                    else 'no enable button')
        return True

    steps = [('the axis and its direction', axis_step, options.axis is None
              or options.invert is None),
             ('the rest (deadzone)', rest_step, options.deadzone is None),
             ('the deadman button', button_step, options.enable_button is None)]
    steps = [(name, step) for name, step, wanted in steps if wanted]
    if chosen['axis'] is None and not any(step is axis_step for _, step in steps):
        raise RuntimeError('no axis given')

    def run(index):
        name, step = steps[index]
        while True:
            done = step()
            console.say(f'Step {index + 1} of {len(steps)} ({name}): press Enter to keep it, '
                        f'or r and Enter to redo it.' if done else
                        f'Step {index + 1} of {len(steps)} ({name}) failed: press Enter to '
                        f'redo it.')
            answer = read_answer()
            if done and answer != 'r':
                return

    for index in range(len(steps)):
        run(index)
    while True:
        console.say('Check: move the stick through its whole range (and release the deadman '
                    'button, if any); the command the person would send shows live. Press '
                    'Enter when done.')
        watch_until(watcher, console, until_enter=True,
                    line=lambda: command_line(watcher, chosen))
        redo = ' or a step number (' + ', '.join(
            f'{index + 1} = {name}' for index, (name, _) in enumerate(steps)) + ') to redo it' \
            if steps else ''
        console.say(f'Press Enter to write the file, c to check again{redo}.')
        answer = read_answer()
        if answer == '':
            break
        if answer.isdigit() and 1 <= int(answer) <= len(steps):
            run(int(answer) - 1)
    return (chosen['axis'], chosen['invert'], chosen['deadzone'], chosen['enable_button'],
            'chosen with the guided set-up')


def detect(watcher: JoystickWatcher, options, console: Console) -> tuple:
    """Non-interactive: detect from ``--detect`` seconds of events; flags override."""
    watcher.start()
    console.say(f'watching {watcher.device.path} for {options.detect} s: push the stick in '
                f'its "+" direction (and hold the enable button, if one is wanted)')
    watch_until(watcher, console, seconds=options.detect, show=options.show_values)
    watch = watcher.watch
    axis = options.axis if options.axis is not None else chosen_axis(watch)
    if axis is None:
        moved = ', '.join(f'{number}: {trace.deflection:.2f}'
                          for number, trace in sorted(watch.axes.items())) or 'none reported'
        raise RuntimeError(f'no axis moved by {MIN_DEFLECTION} or more within '
                           f'{options.detect} s (deflections {moved}): give --axis, or move '
                           f'the stick during the detection')
    trace = watch.axes.get(axis)
    invert = options.invert
    if invert is None:
        invert = inversion(trace) if trace is not None and trace.deflection > 0 else False
    deadzone = options.deadzone
    if deadzone is None:
        deadzone = deadzone_from_rest(trace.first if trace is not None else 0.0)
    enable_button = options.enable_button
    if enable_button is None:
        enable_button = chosen_button(watcher.held_buttons())
    notes = (f'detected from {watch.events} events in {options.detect} s: axis {axis} moved '
             f'{trace.deflection if trace else 0:.2f} from {trace.first if trace else 0:+.2f}')
    return axis, invert, deadzone, enable_button, notes


def parse_args(argv=None):
    """Parse the command line."""
    parser = argparse.ArgumentParser(
        prog='hrc joystick setup', description='Set up the joystick for the human node: list '
        'devices, watch axes and buttons live, pick the axis, inversion, deadzone and enable '
        'button, and write the parameter file the human node reads.')
    parser.add_argument('device', nargs='?', default=None,
                        help='joystick device, or a FIFO/file with its js_event stream '
                        '(default: the first of /dev/input/js*)')
    parser.add_argument('--list', action='store_true', help='list the joystick devices, exit')
    parser.add_argument('--devices', default=DEVICE_PATTERN,
                        help=f'where to look for devices (default {DEVICE_PATTERN})')
    parser.add_argument('--output', '-o', default='joystick.yaml',
                        help='parameter file to write (default ./joystick.yaml)')
    parser.add_argument('--axis', type=int, default=None, help='use this axis (no detection)')
    inversion_group = parser.add_mutually_exclusive_group()
    inversion_group.add_argument('--invert', dest='invert', action='store_true', default=None,
                                 help='invert the axis')
    inversion_group.add_argument('--no-invert', dest='invert', action='store_false',
                                 help='do not invert the axis')
    parser.add_argument('--deadzone', type=float, default=None,
                        help='deadzone in [0, 0.9) (default: from the rest position)')
    parser.add_argument('--enable-button', type=int, default=None,
                        help='deadman button index, -1 = none (default: the button held)')
    parser.add_argument('--non-interactive', action='store_true',
                        help='no questions: detect from --detect seconds of events')
    parser.add_argument('--detect', type=float, default=5.0,
                        help='seconds to watch in non-interactive mode (default 5)')
    parser.add_argument('--show', dest='show_values', action='store_true',
                        help='non-interactive: print the live values while detecting')
    parser.add_argument('--open-timeout', type=float, default=5.0,
                        help='seconds to wait for the device (a FIFO: for its writer)')
    options = parser.parse_args(argv)
    if options.deadzone is not None and not 0.0 <= options.deadzone < 0.9:
        parser.error(f'--deadzone must be in [0, 0.9), got {options.deadzone}')
    if options.detect <= 0:
        parser.error('--detect must be > 0')
    return options


def main(argv=None) -> int:
    """Entry point of ``hrc joystick setup``; 0 = file written, 1 = failed."""
    options = parse_args(argv)
    console = Console()
    if options.list:
        devices = list_devices(options.devices)
        if not devices:
            console.say(f'no joystick devices ({options.devices}); a FIFO or a file carrying '
                        f'js_event records can be given as the device')
            return 1
        for info in devices:
            console.say(info.describe())
        return 0
    path = options.device
    if path is None:
        devices = [info for info in list_devices(options.devices) if not info.problem]
        if not devices:
            console.say(f'no usable joystick device ({options.devices}): plug one in or give '
                        f'the device path')
            return 1
        path = devices[0].path
    info = device_info(path)
    console.say(f'device {info.describe()}')
    watcher = JoystickWatcher(path)
    if not watcher.open(options.open_timeout):
        console.say(f'cannot use {path}: {watcher.device.status}')
        return 1
    interactive = not options.non_interactive and sys.stdin.isatty()
    try:
        chooser = guided if interactive else detect
        axis, invert, deadzone, enable_button, notes = chooser(watcher, options, console)
    except RuntimeError as error:
        console.say(f'set-up failed: {error}')
        return 1
    except KeyboardInterrupt:
        console.say('set-up cancelled: nothing written')
        return 130
    finally:
        watcher.close()
    # The human node may run in another directory: write the absolute path.
    settings = JoystickSettings(os.path.abspath(path), int(axis), bool(invert), float(deadzone),
                                int(enable_button))
    try:
        write_settings(options.output, settings, notes)
    except (ParameterError, OSError) as error:
        console.say(f'not written: {error}')
        return 1
    console.say(f'wrote {options.output}: device {path}, axis {settings.axis}'
                f'{" inverted" if settings.invert else ""}, deadzone {settings.deadzone}, '
                f'enable button {settings.enable_button} ({notes})')
    console.say(f'use it: session --mode realtime --human device --params {options.output}')
    return 0


if __name__ == '__main__':
    sys.exit(main())

