"""Joystick devices for the set-up helper: find them, watch them, read what the operator did.

Pure reading of a Linux joystick device (or a FIFO or file carrying js_event records, read with
the human node's reader :mod:`hrc_joystick_node.js_event`): the driver's name and counts
(ioctls), a watch window of every axis and button, and the rules that turn a window into
settings (the axis moved most, its direction, a deadzone from the rest noise, the button held).
"""

from dataclasses import dataclass, field
import fcntl
import glob
import os
import time
import typing

from hrc_joystick_node.js_event import device_axis, JoystickDevice

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
