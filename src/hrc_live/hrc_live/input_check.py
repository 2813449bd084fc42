"""Is the person's input there? Checks the session runner makes before and during a live session.

Pure (no rclpy). A joystick device counts as present when it opens for reading; a FIFO (the
tests' joystick, written in the kernel's js_event format) only while a writer holds it open. The
check reads nothing from the stream: it asks how many bytes wait (FIONREAD) and reads one byte
only when none wait, which then either fails with EAGAIN (a writer is there) or returns end of
file (nobody is).

The lost-input signal of the human node: with ``on_input_lost: zero`` it answers every state
while its input is lost with ``HumanAction.source == SOURCE_NONE`` and a ``source_detail``
giving the reason (src/hrc_joystick_node/README.md); an answer while the person is not involved
in the training step, or after the operator aborted the session, says so
(``hrc_common.contract.holds_on_purpose``) and is no loss. :func:`lost_reason` reads it: an
operator's abort is never taken for a lost joystick, whichever of the abort's status and the
human node's zero arrives first.
"""

import array
import errno
import fcntl
import glob
import os
import stat
import termios

from hrc_common import topics
from hrc_common.contract import holds_on_purpose, InputSource

SOURCE_NONE = int(InputSource.NONE)
# The session runner says on this topic (std_msgs/String, transient local) why the person's
# input is lost ('' = it is not); the display node shows it on both pages.
INPUT_LOST_TOPIC = topics.INPUT_LOST


def device_presence(path: str) -> tuple:
    """Return (present, why) for the joystick device or FIFO at ``path``."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as error:
        return False, f'cannot open {path}: {os.strerror(error.errno)}'
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISCHR(mode):
            return True, f'{path} opens (character device)'
        if not stat.S_ISFIFO(mode):
            return False, f'{path} is neither a joystick device nor a FIFO'
        waiting = array.array('i', [0])
        fcntl.ioctl(fd, termios.FIONREAD, waiting)
        if waiting[0] > 0:
            return True, f'{path} has a writer (FIFO, {waiting[0]} bytes waiting)'
        try:
            data = os.read(fd, 1)
        except OSError as error:
            if error.errno == errno.EAGAIN:
                return True, f'{path} has a writer (FIFO)'
            return False, f'reading {path} failed: {os.strerror(error.errno)}'
        if data:  # a writer wrote just now; one byte taken (the reader resynchronizes)
            return True, f'{path} has a writer (FIFO)'
        return False, f'{path} exists but no program writes to it (FIFO without a writer)'
    finally:
        os.close(fd)


def joystick_devices() -> list:
    """Return the joystick devices this machine shows (/dev/input/js*, by-id names)."""
    found = sorted(glob.glob('/dev/input/js*'))
    found += sorted(path for path in glob.glob('/dev/input/by-id/*')
                    if 'joystick' in path or path.endswith('-js'))
    return found


def device_missing_message(path: str, why: str, seen: list) -> str:
    """Return what the operator reads when the joystick is not there, and how to fix it."""
    listing = ', '.join(seen) if seen else 'none'
    return (f'the joystick {path} is not there: {why}. Joystick devices seen: {listing}. '
            f'Fix: plug the joystick in (ls -l /dev/input/js* lists it); if it is there but '
            f'cannot be opened, add yourself to its group (sudo usermod -aG input $USER, then '
            f'log in again); if it has another name, pass it with --set '
            f'human.device=/dev/input/jsN or the file hrc joystick setup writes (--params FILE); '
            f'to run with the simulated human instead, use --human sim.')


def joy_missing_message(publishers: int) -> str:
    """Return what the operator reads when /joy has no publisher."""
    return (f'/joy has {publishers} publishers: no joy node is running and no gamepad sends '
            f"from the person's page. Fix: start one (ros2 run joy joy_node) in the same "
            f"ROS_DOMAIN_ID; with --human gamepad, connect a gamepad to the person's computer "
            f'and move its stick on their page; or use --human device with the joystick '
            f'device, or --human sim for the simulated human.')


def lost_reason(source: int, detail: str, involved: bool) -> str:
    """Return why the person's input is lost according to one HumanAction ('' = it is not).

    Only while the person is involved: an answer outside their training steps, or after an
    abort, holds zero on purpose.
    """
    if not involved or source != SOURCE_NONE or holds_on_purpose(detail):
        return ''
    return detail or 'the human node holds zero (no input)'
