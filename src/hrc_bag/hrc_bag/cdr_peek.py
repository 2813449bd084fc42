"""Read the header stamp and the episode of a CDR message without deserializing it (pure).

The recorder routes every message to the file of its episode. TaskState, HumanAction and
AgentStep start with ``std_msgs/Header header`` then ``uint32 episode``; WrenchStamped (the
commands) starts with the header, whose stamp is the stamp of the state it answers. Both are
read straight from the CDR bytes (a few microseconds, against ~25 us for a deserialization).
Which types have which layout is read from their installed .msg definition, so a type whose
fields change is simply no longer peeked at.

CDR (XCDR1, as ROS 2 middlewares write it): 4 bytes of encapsulation header (byte 1: 0x01 =
little endian, 0x00 = big endian), then the fields, each aligned to its size relative to the
end of the encapsulation header: int32 sec, uint32 nanosec, uint32 length of frame_id
(including its NUL), the characters, padding to 4, then the next field.
"""

import functools
import struct
import typing

from hrc_common.contract import HUMAN_ACTION_TYPE, NS_PER_S, TASK_STATE_TYPE

from hrc_bag import msgdefs

ENCAPSULATION = 4


@functools.lru_cache(maxsize=None)
def layout(type_name: str) -> tuple:
    """Return (has_header, has_episode): whether the type starts with a header (+ episode)."""
    try:
        found = msgdefs.fields(type_name)
    except (msgdefs.DefinitionNotFound, ValueError):
        return False, False
    has_header = bool(found) and found[0] == ('std_msgs/Header', 'header')
    has_episode = has_header and len(found) > 1 and found[1] == ('uint32', 'episode')
    return has_header, has_episode


def peek(type_name: str, data: bytes) -> tuple:
    """Return (stamp in ns or None, episode or None) of a CDR message of ``type_name``."""
    has_header, has_episode = layout(type_name)
    if not has_header or len(data) < ENCAPSULATION + 12:
        return None, None
    order = '<' if data[1] == 1 else '>'
    try:
        seconds, nanoseconds, length = struct.unpack_from(order + 'iII', data, ENCAPSULATION)
        stamp = seconds * NS_PER_S + nanoseconds
        episode: typing.Optional[int] = None
        if has_episode:
            position = 12 + length                          # relative to the payload start
            position += -position % 4
            (episode,) = struct.unpack_from(order + 'I', data, ENCAPSULATION + position)
    except struct.error:
        return None, None
    return stamp, episode


# the fields human_action() reads, in the order of the .msg (checked against it at run time)
_HUMAN_ACTION_LAYOUT = [('std_msgs/Header', 'header'), ('uint32', 'episode'),
                        ('uint32', 'step'), ('float64', 'command'), ('uint8', 'dof'),
                        ('uint8', 'source'), ('string', 'source_detail'), ('bool', 'engaged')]


@functools.lru_cache(maxsize=None)
def _human_action_readable() -> bool:
    try:
        return msgdefs.fields(HUMAN_ACTION_TYPE) == _HUMAN_ACTION_LAYOUT
    except (msgdefs.DefinitionNotFound, ValueError):
        return False


def human_action(data: bytes) -> typing.Optional[tuple]:
    """Return (stamp ns, episode, step, source, engaged) of a CDR HumanAction, or None.

    None when the installed HumanAction has other fields than this reader knows, or the bytes
    are cut. Offsets are aligned to each field's size from the payload start (XCDR1).
    """
    if not _human_action_readable() or len(data) < ENCAPSULATION + 12:
        return None
    order = '<' if data[1] == 1 else '>'
    try:
        seconds, nanoseconds, length = struct.unpack_from(order + 'iII', data, ENCAPSULATION)
        position = 12 + length
        position += -position % 4
        episode, step = struct.unpack_from(order + 'II', data, ENCAPSULATION + position)
        position += 8
        position += -position % 8                   # float64 command
        position += 8
        _, source = struct.unpack_from('BB', data, ENCAPSULATION + position)
        position += 2
        position += -position % 4                   # string source_detail
        (length,) = struct.unpack_from(order + 'I', data, ENCAPSULATION + position)
        position += 4 + length
        (engaged,) = struct.unpack_from('B', data, ENCAPSULATION + position)
    except struct.error:
        return None
    return seconds * NS_PER_S + nanoseconds, episode, step, source, bool(engaged)


# the fields task_state() reads or steps over, in the order of the .msg (checked at run time)
_TASK_STATE_LAYOUT = ([('std_msgs/Header', 'header'), ('uint32', 'episode'), ('uint32', 'step')]
                      + [('float64', name) for name in (
                          'slider_position', 'slider_velocity', 'pendulum_angle',
                          'pendulum_angular_velocity', 'ball_position', 'ball_velocity',
                          'applied_force', 'applied_torque')]
                      + [('bool', 'robot_command_missing'), ('bool', 'human_command_missing'),
                         ('uint16', 'slice'), ('float64[]', 'human_applied'),
                         ('bool', 'terminated'), ('bool', 'truncated')])


@functools.lru_cache(maxsize=None)
def _task_state_readable() -> bool:
    try:
        return msgdefs.fields(TASK_STATE_TYPE) == _TASK_STATE_LAYOUT
    except (msgdefs.DefinitionNotFound, ValueError):
        return False


def _task_state_fields(data: bytes) -> typing.Optional[tuple]:
    """Return (episode, step, robot missing, human missing, final) of a CDR TaskState, or None.

    One walk over the payload for both readers below; None when the installed TaskState has
    other fields than this reader knows or the bytes do not add up (the two end bools are the
    last bytes of the payload, up to 3 bytes of end padding).
    """
    if not _task_state_readable() or len(data) < ENCAPSULATION + 12:
        return None
    order = '<' if data[1] == 1 else '>'
    size = len(data) - ENCAPSULATION
    try:
        (length,) = struct.unpack_from(order + 'I', data, ENCAPSULATION + 8)   # frame_id
        position = 12 + length
        position += -position % 4
        episode, step = struct.unpack_from(order + 'II', data, ENCAPSULATION + position)
        position += 8
        position += -position % 8 + 8 * 8           # the eight float64
        robot, human = struct.unpack_from('BB', data, ENCAPSULATION + position)
        position += 2                               # the two command_missing bools
        position += -position % 2 + 2               # uint16 slice
        position += -position % 4
        (count,) = struct.unpack_from(order + 'I', data, ENCAPSULATION + position)
        position += 4
        if count:
            position += -position % 8 + 8 * count   # float64[] human_applied
        if not 0 <= size - (position + 2) < 4:
            return None
        terminated, truncated = struct.unpack_from('BB', data, ENCAPSULATION + position)
    except struct.error:
        return None
    return episode, step, bool(robot), bool(human), bool(terminated or truncated)


def task_state(data: bytes) -> typing.Optional[tuple]:
    """Return (episode, step, final) of a CDR TaskState (final: terminated or truncated).

    What the recorder needs of every state to find the episode boundaries, without a
    deserialization (which costs ten times more). None as :func:`_task_state_fields` (the
    caller then deserializes).
    """
    fields = _task_state_fields(data)
    return None if fields is None else (fields[0], fields[1], fields[4])


def task_state_missing(data: bytes) -> typing.Optional[tuple]:
    """Return (robot_command_missing, human_command_missing) of a CDR TaskState, or None.

    The sim sets them on a state whose period went without that actor's command (applied as
    zero); the recorder counts them per episode. None as for :func:`task_state`.
    """
    fields = _task_state_fields(data)
    return None if fields is None else (fields[2], fields[3])
