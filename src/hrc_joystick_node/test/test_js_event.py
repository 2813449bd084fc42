"""The js_event reader: parsing, partial reads, garbage, normalization, FIFO hot-plug."""

import os
import time

import pytest

from hrc_joystick_node.js_event import (device_axis, EVENT_SIZE, JoystickDevice, JS_EVENT_AXIS,
                                        JS_EVENT_BUTTON, JS_EVENT_INIT, JsEvent, JsEventParser,
                                        pack_event, shape_axis)


def axis(number, value, time_ms=0, init=False):
    return pack_event(time_ms, value, JS_EVENT_AXIS | (JS_EVENT_INIT if init else 0), number)


def button(number, value, time_ms=0, init=False):
    return pack_event(time_ms, value, JS_EVENT_BUTTON | (JS_EVENT_INIT if init else 0), number)


def test_record_layout_is_the_kernel_struct():
    assert EVENT_SIZE == 8
    data = pack_event(0x01020304, -2, JS_EVENT_AXIS, 5)
    # little-endian on x86/arm64: __u32 time, __s16 value, __u8 type, __u8 number
    assert data == bytes([0x04, 0x03, 0x02, 0x01, 0xFE, 0xFF, 0x02, 0x05])


def test_axes_buttons_and_init_events():
    parser = JsEventParser()
    stream = (axis(0, 0, init=True) + axis(1, -12000, init=True) + button(3, 0, init=True)
              + axis(1, 32767, time_ms=10) + button(3, 1, time_ms=12))
    events = parser.feed(stream)
    assert [(e.number, e.value, e.is_axis, e.is_button, e.is_init) for e in events] == [
        (0, 0, True, False, True), (1, -12000, True, False, True), (3, 0, False, True, True),
        (1, 32767, True, False, False), (3, 1, False, True, False)]
    assert events[3].time_ms == 10
    assert parser.garbage_bytes == 0 and parser.pending_bytes == 0


def test_partial_reads_are_buffered_until_the_record_completes():
    parser = JsEventParser()
    stream = axis(2, 1000, time_ms=7) + button(0, 1, time_ms=8)
    seen = []
    for index in range(len(stream)):  # one byte at a time, the worst split possible
        seen += parser.feed(stream[index:index + 1])
        if index < EVENT_SIZE - 1:
            assert seen == [] and parser.pending_bytes == index + 1
    assert seen == [JsEvent(7, 1000, JS_EVENT_AXIS, 2), JsEvent(8, 1, JS_EVENT_BUTTON, 0)]
    assert parser.pending_bytes == 0


@pytest.mark.parametrize('garbage', [
    b'\xff' * 5,  # misaligning junk
    b'\xff' * 8,  # a whole record of junk (type 0xff)
    pack_event(0, 0, 0x04, 0),  # unknown type
    pack_event(0, 7, JS_EVENT_BUTTON, 0),  # a button value other than 0/1
    pack_event(0, 5, JS_EVENT_AXIS, 200),  # an axis index beyond the kernel's 64
])
def test_garbage_is_skipped_counted_and_the_stream_resynchronizes(garbage):
    parser = JsEventParser()
    before = axis(1, 100)
    after = axis(1, -200) + button(4, 1)
    events = parser.feed(before + garbage + after)
    assert [(e.number, e.value) for e in events] == [(1, 100), (1, -200), (4, 1)]
    assert parser.garbage_bytes == len(garbage)


def test_normalization_follows_the_ros_joy_convention():
    assert device_axis(0) == 0.0
    assert device_axis(-32767) == 1.0  # the kernel's stick up is negative; Joy's up is +1
    assert device_axis(32767) == -1.0
    assert device_axis(-32768) == 1.0  # clamped
    assert device_axis(16384) == pytest.approx(-0.5, abs=1e-4)


def test_deadzone_is_scaled_and_continuous_and_inversion_flips():
    assert shape_axis(0.04, 0.05, False) == 0.0
    assert shape_axis(-0.049, 0.05, False) == 0.0
    assert shape_axis(0.05, 0.05, False) == pytest.approx(0.0)
    assert shape_axis(0.525, 0.05, False) == pytest.approx(0.5)
    assert shape_axis(-1.0, 0.05, False) == -1.0
    assert shape_axis(1.0, 0.05, True) == -1.0
    assert shape_axis(2.0, 0.0, False) == 1.0  # out of range input clamps
    assert shape_axis(-0.3, 0.0, True) == pytest.approx(0.3)
    with pytest.raises(ValueError):
        shape_axis(0.5, 1.0, False)


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / 'js0'
    os.mkfifo(path)
    return str(path)


def open_writer(path):
    # O_RDWR never blocks on Linux (a plain O_WRONLY would wait for a reader).
    return os.open(path, os.O_RDWR)


def test_missing_device_is_reported():
    device = JoystickDevice('/nonexistent/js0')
    assert not device.open()
    assert not device.present
    assert 'No such file' in device.status
    assert device.poll() == []


def test_fifo_reading_partial_records_and_hot_plug(fifo):
    device = JoystickDevice(fifo)
    assert not device.open(), 'a FIFO with no writer is not a present device'
    assert 'no writer' in device.status

    writer = open_writer(fifo)
    try:
        assert device.open() and device.present
        assert device.poll() == [], 'nothing written yet: poll returns at once'
        os.write(writer, axis(1, -32767, init=True) + button(2, 0, init=True) + axis(1, 0)[:3])
        events = device.poll()
        assert [e.is_init for e in events] == [True, True]
        assert device.axis(1) == 1.0 and device.button(2) is False
        assert device.parser.pending_bytes == 3
        os.write(writer, axis(1, 0)[3:] + button(2, 1))
        device.poll()
        assert device.axis(1) == 0.0 and device.button(2) is True
    finally:
        os.close(writer)

    # Unplugged: the writer closed the FIFO.
    device.poll()
    assert not device.present
    assert 'vanished' in device.status and device.vanished_count == 1
    assert not device.open(), 'still unplugged'

    # Plugged back in: the state starts empty and INIT events fill it again.
    writer = open_writer(fifo)
    try:
        assert device.open()
        assert device.axis(1) is None and device.button(2) is None
        os.write(writer, axis(1, 16384, init=True))
        device.poll()
        assert device.axis(1) == pytest.approx(-0.5, abs=1e-4)
        assert device.opened_count == 2
    finally:
        os.close(writer)
        device.close()


def test_poll_never_blocks_on_an_idle_device(fifo):
    writer = open_writer(fifo)
    device = JoystickDevice(fifo)
    try:
        assert device.open()
        start = time.monotonic()
        for _ in range(100):
            assert device.poll() == []
        assert time.monotonic() - start < 2.0, '100 polls of an idle FIFO must not wait'
        assert device.present
    finally:
        os.close(writer)
        device.close()


def test_regular_file_end_is_idle_not_unplugged(tmp_path):
    path = tmp_path / 'recording.js'
    path.write_bytes(axis(0, 100, init=True) + axis(0, 200))
    device = JoystickDevice(str(path))
    assert device.open()
    assert [e.value for e in device.poll()] == [100, 200]
    assert device.poll() == [] and device.present
    with open(path, 'ab') as stream:
        stream.write(axis(0, -300) + b'\x00\x01')
    assert [e.value for e in device.poll()] == [-300]
    assert device.parser.pending_bytes == 2
    device.close()
    assert not device.present
