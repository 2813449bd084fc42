"""Which input drives the human's command, and the sensor_msgs/Joy adapter; pure, no rclpy.

Inputs (parameter ``input``):

* ``device``: a Linux joystick device (see :mod:`hrc_joystick_node.js_event`);
* ``joy``: ``sensor_msgs/Joy`` on ``/joy`` as a stock ``joy``/``joy_linux`` node publishes it;
* ``sim``: the simulated human (:mod:`hrc_joystick_node.sim_human`);
* ``model``: a human model cloned from recordings (:mod:`hrc_joystick_node.human_model`);
* ``script``: a scripted stick, a stick trajectory in simulation time read from a file
  (:mod:`hrc_joystick_node.stick_script`): the joystick path without a person or wall time;
* ``auto``: the device if it opens, else ``/joy`` if a publisher is seen; re-evaluated
  continuously, so a device that appears later takes over.

When the joystick (device or ``/joy``) is missing (never seen) or lost (the device vanishes,
``/joy`` falls silent past its deadline), the policy ``on_input_lost`` holds: ``pause`` (the
default: a held zero, and the input status asks the session to pause), ``zero`` (a held zero)
or ``sim`` (the simulated human stands in: only when asked for, never silently). The input
returns as soon as it is back. :class:`InputSelector` keeps that logic in one place, words each
change for the log and says what state the input is in (``ok``, ``missing``, ``lost``).
"""

import typing

from hrc_joystick_node.js_event import shape_axis

DEVICE = 'device'
JOY = 'joy'
SIM = 'sim'
AUTO = 'auto'
ZERO = 'zero'
PAUSE = 'pause'
MODEL = 'model'
SCRIPT = 'script'
INPUT_MODES = (AUTO, DEVICE, JOY, SIM, MODEL, SCRIPT)
# Inputs that are always there (no device to open, no stream to lose).
ALWAYS_PRESENT = (SIM, MODEL, SCRIPT)
FALLBACKS = (PAUSE, ZERO, SIM)
OK, MISSING, LOST = 'ok', 'missing', 'lost'


class StickReading(typing.NamedTuple):
    """One joystick input read now: its axis, its enable button, and its name for the log."""

    axis: typing.Optional[float]  # [-1, 1] in the Joy convention, None = not reported yet
    enable: typing.Optional[bool]  # enable (deadman) button held, None = not reported
    name: str  # device path or /joy topic


class JoyInput:
    """The latest ``sensor_msgs/Joy`` values and whether the stream is alive.

    Alive means: a message arrived less than ``timeout`` s ago, or a publisher exists and was
    first seen less than ``timeout`` s ago (a grace period before its first message). So a
    stock joy node must publish at least every ``timeout`` s (its ``autorepeat_rate``).
    """

    def __init__(self, timeout: float):
        self.timeout = timeout
        self.axes: typing.List[float] = []
        self.buttons: typing.List[int] = []
        self.last_message_time = None  # monotonic s
        self.publisher_seen_time = None  # monotonic s when a publisher was first seen
        self.messages = 0

    def on_message(self, axes, buttons, now: float) -> None:
        """Store one Joy message received at ``now`` (monotonic s)."""
        self.axes = [float(value) for value in axes]
        self.buttons = [int(value) for value in buttons]
        self.last_message_time = now
        self.messages += 1

    def on_publisher_count(self, count: int, now: float) -> None:
        """Record how many publishers ``/joy`` has now (the grace period starts at the first)."""
        if count > 0 and self.publisher_seen_time is None:
            self.publisher_seen_time = now
        elif count == 0:
            self.publisher_seen_time = None

    def alive(self, now: float) -> bool:
        """Return True when /joy is usable now (see the class docstring)."""
        if self.last_message_time is not None and now - self.last_message_time <= self.timeout:
            return True
        if self.publisher_seen_time is None:
            return False
        waiting_for_first = (self.last_message_time is None
                             or self.last_message_time < self.publisher_seen_time)
        return waiting_for_first and now - self.publisher_seen_time <= self.timeout

    def status(self, now: float) -> str:
        """Say why /joy is or is not alive."""
        if self.last_message_time is not None:
            age = now - self.last_message_time
            state = 'alive' if age <= self.timeout else 'silent'
            return f'/joy {state}: last message {age:.2f} s ago (deadline {self.timeout} s)'
        if self.publisher_seen_time is not None:
            return f'/joy has a publisher, no message for {now - self.publisher_seen_time:.2f} s'
        return '/joy has no publisher'

    def axis(self, number: int) -> typing.Optional[float]:
        """Return axis ``number`` of the latest message, or None if it has no such axis."""
        return self.axes[number] if 0 <= number < len(self.axes) else None

    def button(self, number: int) -> typing.Optional[bool]:
        """Return whether button ``number`` is pressed, or None if the message has none."""
        return bool(self.buttons[number]) if 0 <= number < len(self.buttons) else None


def stick_command(raw_axis: typing.Optional[float], enable_pressed: typing.Optional[bool],
                  use_enable_button: bool, deadzone: float, invert: bool) -> tuple:
    """Return (command in [-1, 1], engaged, why) from an axis and the enable button.

    A missing axis reads as 0 (the device has not reported it yet). With an enable (deadman)
    button configured, the command is 0 and not engaged unless the button is held.
    """
    if use_enable_button and not enable_pressed:
        return 0.0, False, 'enable button released'
    if raw_axis is None:
        return 0.0, True, 'axis not reported yet'
    return shape_axis(raw_axis, deadzone, invert), True, ''


class InputSelector:
    """Choose the active input from the mode, what is available, and the fallback policy."""

    def __init__(self, mode: str, on_input_lost: str):
        if mode not in INPUT_MODES:
            raise ValueError(f'input must be one of {INPUT_MODES}, got {mode!r}')
        if on_input_lost not in FALLBACKS:
            raise ValueError(f'on_input_lost must be one of {FALLBACKS}, got {on_input_lost!r}')
        self.mode = mode
        self.on_input_lost = on_input_lost
        self.active = None  # DEVICE, JOY, SIM, MODEL, SCRIPT or ZERO
        self.state = OK if mode in ALWAYS_PRESENT else MISSING  # OK, MISSING or LOST
        self.reason = ''
        self.lost_count = 0  # times a joystick input went away
        self._had_real_input = False

    @property
    def pause_requested(self) -> bool:
        """True when the joystick is missing or lost and the policy is ``pause``."""
        return self.state != OK and self.on_input_lost == PAUSE

    def status_line(self) -> str:
        """One line a person can read: what drives the human now and why."""
        if self.state == OK:
            return f'{self.active}: {self.reason}'
        what = 'joystick disconnected' if self.state == LOST else 'no joystick yet'
        holds = {PAUSE: 'zero held, session should pause', ZERO: 'zero held',
                 SIM: 'the simulated human stands in (on_input_lost: sim)'}[self.on_input_lost]
        return f'{what} ({holds}): {self.reason}'

    def update(self, device_present: bool, device_status: str, joy_alive: bool,
               joy_status: str) -> typing.Optional[str]:
        """Re-evaluate; return a log line when the active input or its state changed."""
        if self.mode in ALWAYS_PRESENT:
            choice, reason = self.mode, f'input is {self.mode}'
        elif self.mode == DEVICE:
            choice, reason = (DEVICE, device_status) if device_present else (None,
                                                                            device_status)
        elif self.mode == JOY:
            choice, reason = (JOY, joy_status) if joy_alive else (None, joy_status)
        elif device_present:
            choice, reason = DEVICE, f'auto: the device opened ({device_status})'
        elif joy_alive:
            choice, reason = JOY, f'auto: no device ({device_status}); {joy_status}'
        else:
            choice, reason = None, f'auto: {device_status}; {joy_status}'
        if choice is None:  # the joystick is missing or lost: the policy, never silently
            state = LOST if self._had_real_input else MISSING
            choice = ZERO if self.on_input_lost in (PAUSE, ZERO) else SIM
        else:
            state = OK
        if choice in (DEVICE, JOY):
            self._had_real_input = True
        if choice == self.active and state == self.state:
            self.reason = reason  # the wording may change (e.g. an age), not the decision
            return None
        if state == LOST and self.state != LOST:
            self.lost_count += 1
        previous = self.active
        self.active, self.state, self.reason = choice, state, reason
        return f'input: {previous or "none"} -> {choice} ({self.status_line()})'
