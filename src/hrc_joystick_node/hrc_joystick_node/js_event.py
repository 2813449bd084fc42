"""The Linux joystick API (``/dev/input/jsN``) read without blocking; pure Python, no rclpy.

The kernel's joydev driver (Documentation/input/joydev/joystick-api.rst) delivers a stream of
8-byte records in native byte order::

    struct js_event {
        __u32 time;     /* event timestamp in milliseconds */
        __s16 value;    /* axis: -32767..32767, button: 0 released / 1 pressed */
        __u8 type;      /* JS_EVENT_BUTTON 0x01, JS_EVENT_AXIS 0x02, | JS_EVENT_INIT 0x80 */
        __u8 number;    /* axis or button index */
    };

Right after ``open()`` the driver sends one synthetic event per axis and button with the INIT
flag set: the initial state. Unplugging the device makes ``read()`` fail with ENODEV.

Here:

* :class:`JsEventParser` turns arbitrary chunks of bytes into events: a partial record is kept
  until the rest arrives; a record that cannot be a js_event (unknown type bits, a button value
  other than 0/1, an axis index beyond the kernel's 64) is garbage: the parser drops one byte
  and tries again (resynchronization), counting the bytes it dropped so the caller can report.
  A record that merely looks valid is not trusted when its timestamp is implausible (running
  backwards, or ahead of the time that passed): a misaligned read can turn a stick value into
  "button 128 released". Right after garbage it must also be followed by another valid record
  when that one is already there; otherwise the parser slides on.
* :class:`StreamPlausibility` decides whether a stream is a joystick at all: over the last
  second, too large a share of garbage bytes (wrong layout, event type or timestamp) or more
  events than any device sends mean it is not (``/dev/urandom``, a wrong file), and the device
  is closed as lost with that reason before the chunk's events are used.
* :class:`JoystickDevice` opens the device with ``O_NONBLOCK`` and drains whatever is readable
  on each :meth:`JoystickDevice.poll` call (never blocks, never spins); it notices the device
  vanishing (ENODEV/EIO, or the writer of a FIFO closing it) and can be reopened (hot-plug).
  Tests use a FIFO (``os.mkfifo``) or a regular file in place of the device.
* :func:`device_axis` converts a raw axis value to the ROS ``sensor_msgs/Joy`` convention
  (stick up or left = +1), exactly as the stock ``joy`` and ``joy_linux`` drivers do, so one set
  of axis/inversion/deadzone parameters means the same on both inputs.
"""

import errno
import os
import stat
import struct
import time
import typing

JS_EVENT_BUTTON = 0x01
JS_EVENT_AXIS = 0x02
JS_EVENT_INIT = 0x80
EVENT_FORMAT = '=IhBB'  # native byte order, standard sizes, no padding: 4 + 2 + 1 + 1 bytes
EVENT_SIZE = struct.calcsize(EVENT_FORMAT)
AXIS_MAX = 32767
# joydev reports at most ABS_CNT (64) axes; the button index is a __u8, so any value is valid.
MAX_AXES = 64
# Upper bound of bytes taken per poll: 4096 records, far more than a joystick sends in 0.2 s.
READ_LIMIT = 4096 * EVENT_SIZE
# A joystick stamps its events with the kernel's clock (ms): an event's time may advance past
# the last event's by at most the time that passed since that one was read plus this slack
# (the reader's latency), or RESYNC_SLACK_MS right after garbage; it never runs backwards.
LATENCY_SLACK_MS = 10_000
RESYNC_SLACK_MS = 2_000
# Plausibility of a stream, over a sliding window of PLAUSIBILITY_WINDOW s (wall time):
PLAUSIBILITY_WINDOW = 1.0
MAX_EVENT_RATE = 10_000  # events/s: a USB gamepad polled at 1 kHz with every axis moving
MAX_GARBAGE_SHARE = 0.25  # of the bytes read, once at least MIN_GARBAGE_BYTES were garbage
MIN_GARBAGE_BYTES = 64


class JsEvent(typing.NamedTuple):
    """One js_event record."""

    time_ms: int  # driver timestamp, ms (wraps at 2**32)
    value: int  # axis position -32767..32767, or button 0/1
    type: int  # JS_EVENT_BUTTON or JS_EVENT_AXIS, possibly | JS_EVENT_INIT
    number: int  # axis or button index

    @property
    def is_init(self) -> bool:
        """Return True for the synthetic initial-state events sent after open()."""
        return bool(self.type & JS_EVENT_INIT)

    @property
    def is_axis(self) -> bool:
        """Return True for an axis event (initial or not)."""
        return self.type & ~JS_EVENT_INIT == JS_EVENT_AXIS

    @property
    def is_button(self) -> bool:
        """Return True for a button event (initial or not)."""
        return self.type & ~JS_EVENT_INIT == JS_EVENT_BUTTON


def pack_event(time_ms: int, value: int, event_type: int, number: int) -> bytes:
    """Return the 8 bytes of one js_event record (what the kernel writes)."""
    return struct.pack(EVENT_FORMAT, time_ms & 0xFFFFFFFF, value, event_type, number)


def is_valid_record(event: JsEvent) -> bool:
    """Return True when a decoded record can be a js_event the joydev driver sends."""
    if event.type & ~(JS_EVENT_INIT | JS_EVENT_AXIS | JS_EVENT_BUTTON):
        return False
    if event.is_button:
        return event.value in (0, 1)
    if event.is_axis:
        return event.number < MAX_AXES
    return False  # neither axis nor button (type 0x00 or 0x03)


def _time_advance(time_ms: int, reference_ms: int) -> int:
    """Return ``time_ms - reference_ms`` in ms, across the 2**32 wrap (negative = backwards)."""
    difference = (time_ms - reference_ms) & 0xFFFFFFFF
    return difference - 0x100000000 if difference >= 0x80000000 else difference


class JsEventParser:
    """Turn a byte stream into js_events: buffers partial records, skips garbage.

    ``clock`` (monotonic s), when given, lets the parser check timestamps against the time
    that passed: a joystick's event times never run backwards and never advance faster than
    real time (plus a slack for the reader's latency); a record that does is no event but a
    misaligned read, and is skipped like garbage. Without a clock (a regular file replaying a
    recording) only the record's fields are checked.
    """

    def __init__(self, clock=None):
        self._buffer = bytearray()
        self._clock = clock
        self.garbage_bytes = 0  # bytes dropped to resynchronize, since creation
        self.events_parsed = 0
        self.last_time_ms = None  # timestamp of the last good event
        self._last_wall = None  # clock reading when it was read
        self._after_garbage = False  # bytes were dropped since the last good event

    @property
    def pending_bytes(self) -> int:
        """Bytes of an incomplete record waiting for the rest."""
        return len(self._buffer)

    def reset(self, clock=None) -> None:
        """Forget a partial record and the last event (the stream was closed and reopened).

        ``clock``: the clock for the new stream (None: timestamps are not checked).
        """
        self._clock = clock
        self._buffer.clear()
        self.last_time_ms = None
        self._last_wall = None
        self._after_garbage = False

    def _time_plausible(self, time_ms: int, now) -> bool:
        if self.last_time_ms is None or now is None:
            return True
        advance = _time_advance(time_ms, self.last_time_ms)
        slack = RESYNC_SLACK_MS if self._after_garbage else LATENCY_SLACK_MS
        return 0 <= advance <= (now - self._last_wall) * 1000.0 + slack

    def _trusted(self, event: JsEvent, offset: int, now) -> typing.Optional[bool]:
        """Return whether a valid-looking record can be taken as an event.

        None: cannot tell yet (right after garbage, with nothing to check it against, the
        confirming next record has not arrived).
        """
        if not self._time_plausible(event.time_ms, now):
            return False
        if not self._after_garbage:
            return True
        following = offset + EVENT_SIZE
        if len(self._buffer) - following >= EVENT_SIZE:
            after = JsEvent(*struct.unpack_from(EVENT_FORMAT, self._buffer, following))
            return is_valid_record(after) and 0 <= _time_advance(after.time_ms,
                                                                 event.time_ms) <= \
                RESYNC_SLACK_MS
        return None if self.last_time_ms is None or now is None else True

    def feed(self, data: bytes) -> typing.List[JsEvent]:
        """Add bytes read from the device and return the complete, valid events they hold."""
        self._buffer += data
        now = self._clock() if self._clock is not None else None
        events = []
        offset = 0
        while len(self._buffer) - offset >= EVENT_SIZE:
            event = JsEvent(*struct.unpack_from(EVENT_FORMAT, self._buffer, offset))
            valid = is_valid_record(event)
            if valid:
                valid = self._trusted(event, offset, now)
                if valid is None:
                    break  # wait for the next record to confirm the alignment
            if valid:
                events.append(event)
                offset += EVENT_SIZE
                self.last_time_ms, self._last_wall = event.time_ms, now
                self._after_garbage = False
            else:
                # Not a js_event here: assume we are misaligned, slide by one byte.
                offset += 1
                self.garbage_bytes += 1
                self._after_garbage = True
        del self._buffer[:offset]
        self.events_parsed += len(events)
        return events


class StreamPlausibility:
    """Whether a byte stream behaves like a joystick (see the module docstring).

    Fed after every chunk with what the chunk held; :meth:`add` says why the stream is not a
    joystick, or returns '' while it is plausible. ``clock``: monotonic seconds.
    """

    def __init__(self, clock=time.monotonic):
        self._clock = clock
        self._chunks = []  # (time, bytes, garbage bytes, events)

    def reset(self) -> None:
        """Forget the history (the stream was reopened)."""
        self._chunks.clear()

    def add(self, size: int, garbage: int, events: int) -> str:
        """Record one chunk; return the reason the stream is not a joystick, or ''."""
        now = self._clock()
        self._chunks.append((now, size, garbage, events))
        while self._chunks and now - self._chunks[0][0] > PLAUSIBILITY_WINDOW:
            self._chunks.pop(0)
        total = sum(chunk[1] for chunk in self._chunks)
        junk = sum(chunk[2] for chunk in self._chunks)
        count = sum(chunk[3] for chunk in self._chunks)
        reasons = []
        if junk >= MIN_GARBAGE_BYTES and junk > MAX_GARBAGE_SHARE * total:
            reasons.append(f'{junk} of {total} bytes in the last {PLAUSIBILITY_WINDOW:g} s are '
                           'no js_event (wrong record layout, event type or timestamp)')
        if count > MAX_EVENT_RATE * PLAUSIBILITY_WINDOW:
            reasons.append(f'{count} events in {PLAUSIBILITY_WINDOW:g} s, more than any '
                           f'joystick sends ({MAX_EVENT_RATE}/s)')
        return '; '.join(reasons)


def device_axis(raw: int) -> float:
    """Convert a raw axis value to [-1, 1] in the ROS Joy convention (up/left = +).

    The kernel reports stick up (or left) as negative; the ``joy`` and ``joy_linux`` drivers
    negate it, and so do we. -32768 (seen on some drivers) clamps to +1.
    """
    return max(-1.0, min(1.0, -raw / AXIS_MAX))


def shape_axis(value: float, deadzone: float, invert: bool) -> float:
    """Apply a scaled deadzone and an optional inversion to a normalized axis value.

    Inside ``|value| < deadzone`` the result is 0; outside it is rescaled so that it grows
    continuously from 0 at the deadzone edge to 1 at full deflection (no jump at the edge).
    """
    if not 0.0 <= deadzone < 1.0:
        raise ValueError(f'deadzone must be in [0, 1), got {deadzone}')
    value = max(-1.0, min(1.0, float(value)))
    magnitude = abs(value)
    if magnitude < deadzone:
        return 0.0
    shaped = (magnitude - deadzone) / (1.0 - deadzone)
    shaped = shaped if value > 0 else -shaped
    return -shaped if invert else shaped


class JoystickDevice:
    """A Linux joystick device (or a FIFO/file carrying its event stream), read non-blocking.

    Call :meth:`open` to try to open it, then :meth:`poll` whenever the latest state is needed
    (for example when a sim state arrives) and periodically, to drain the stream and notice the
    device vanishing. ``poll`` reads only what is already there and returns at once.

    ``present`` tells whether the device is open and alive; ``status`` says why not.
    On every (re)open the axis and button state starts empty: the driver's INIT events fill it.
    """

    def __init__(self, path: str, clock=time.monotonic):
        self.path = path
        self._clock = clock
        self._fd = None
        self._kind = None  # 'char', 'fifo' or 'file'
        self.parser = JsEventParser()
        self.plausibility = StreamPlausibility(clock)
        self.rejected = False  # the last stream opened was not a joystick (status says why)
        self._unreported: typing.List[JsEvent] = []
        self.axes: typing.Dict[int, int] = {}
        self.buttons: typing.Dict[int, int] = {}
        self.status = 'not opened yet'
        self.last_event_time = None  # monotonic s of the newest event
        self.opened_count = 0
        self.vanished_count = 0

    @property
    def present(self) -> bool:
        """Return True when the device is open, has not vanished and is not on probation."""
        return self._fd is not None and not self.rejected

    def fileno(self) -> int:
        """Return the open file descriptor (for select/poll); -1 when closed."""
        return -1 if self._fd is None else self._fd

    def open(self) -> bool:
        """Try to open the device; return True if it is present now (``status`` says why not).

        A stream once found not to be a joystick (``rejected``) is on probation when it opens
        again: it counts as present only once it starts as a joystick does, with the driver's
        INIT events; until then each call reads on and checks.
        """
        if self._fd is not None and not self.rejected:
            return True
        if self._fd is None and not self._open_stream():
            return False
        if self._fd is not None and self.rejected:
            if not any(event.is_init for event in self._unreported):
                self._read_available(self._unreported)
            if self._fd is not None and any(event.is_init for event in self._unreported):
                self.rejected = False
        if self._fd is None:  # the first read failed, or the stream is not a joystick
            return False
        if self.rejected:
            self.status = (f'{self.path} was not a joystick: waiting for the initial (INIT) '
                           'events a joystick driver sends when opened')
            return False
        self.opened_count += 1
        self.status = f'{self.path} open ({self._kind})'
        return True

    def _open_stream(self) -> bool:
        """Open the path and read what is there; False when it is absent or without writer."""
        try:
            fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)
        except OSError as error:
            self.status = f'cannot open {self.path}: {os.strerror(error.errno)}'
            return False
        mode = os.fstat(fd).st_mode
        if stat.S_ISFIFO(mode):
            kind = 'fifo'
        elif stat.S_ISCHR(mode):
            kind = 'char'
        elif stat.S_ISREG(mode):
            kind = 'file'
        else:
            os.close(fd)
            self.status = f'{self.path} is neither a character device, a FIFO nor a file'
            return False
        self._fd, self._kind = fd, kind
        # A regular file replays a recording: its timestamps are not checked against the clock.
        self.parser.reset(clock=None if kind == 'file' else self._clock)
        self.plausibility.reset()
        self.axes.clear()
        self.buttons.clear()
        # Read what is there at once: the INIT events of a joystick, or the evidence that the
        # stream is not one (then it is never reported present). A FIFO opened without a
        # writer reads as end of file: nobody is there yet.
        self._unreported = []  # events read at open, returned by the next poll
        if not self._read_available(self._unreported, at_open=True) and kind == 'fifo' \
                and self._fd is not None:
            self._close('no writer has the FIFO open')
            return False
        return self._fd is not None

    def poll(self) -> typing.List[JsEvent]:
        """Read every complete event available now, update the state, return the events."""
        if not self.present:
            return []
        events, self._unreported = self._unreported, []
        self._read_available(events)
        return events

    def _read_available(self, events, at_open=False) -> bool:
        """Drain readable bytes into the parser, appending to ``events``; False if gone.

        ``at_open``: end of file of a FIFO just opened means no writer yet, not a vanishing.
        """
        taken = 0
        while taken < READ_LIMIT:
            try:
                data = os.read(self._fd, READ_LIMIT - taken)
            except BlockingIOError:
                return True  # nothing more for now (EAGAIN): the normal way out
            except OSError as error:
                if error.errno == errno.EINTR:
                    continue
                self._vanish(f'read failed: {os.strerror(error.errno)}')
                return False
            if not data:
                if self._kind == 'file':
                    return True  # a regular file: everything read, more may be appended
                if self._kind == 'fifo':
                    if at_open:
                        return False
                    self._vanish('the writer closed the FIFO')
                    return False
                self._vanish('end of file on the device')
                return False
            taken += len(data)
            garbage_before = self.parser.garbage_bytes
            new_events = self.parser.feed(data)
            problem = self.plausibility.add(len(data), self.parser.garbage_bytes
                                            - garbage_before, len(new_events))
            if problem:  # not a joystick: none of this chunk's events is used
                self._reject(problem)
                return False
            self._apply(new_events, events)
        return True

    def _apply(self, new_events, events) -> None:
        for event in new_events:
            if event.is_axis:
                self.axes[event.number] = event.value
            else:
                self.buttons[event.number] = event.value
        if new_events:
            self.last_event_time = self._clock()
        events.extend(new_events)

    def _reject(self, reason: str) -> None:
        self.vanished_count += 1
        self.rejected = True
        self.axes.clear()
        self.buttons.clear()
        self._close(f'{self.path} is not a joystick: {reason}')

    def _vanish(self, reason: str) -> None:
        self.vanished_count += 1
        self._close(f'{self.path} vanished: {reason}')

    def _close(self, status: str) -> None:
        if self._fd is not None:
            os.close(self._fd)
        self._fd = None
        self.status = status

    def axis(self, number: int) -> typing.Optional[float]:
        """Return axis ``number`` in [-1, 1] (Joy convention), or None if never reported."""
        raw = self.axes.get(number)
        return None if raw is None else device_axis(raw)

    def button(self, number: int) -> typing.Optional[bool]:
        """Return whether button ``number`` is pressed, or None if never reported."""
        value = self.buttons.get(number)
        return None if value is None else bool(value)

    def close(self) -> None:
        """Close the device (idempotent)."""
        self._close('closed')
