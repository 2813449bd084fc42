"""The one serializer outside the nodes (rosbags' typestore) writes rclpy's bytes.

Every hrc_msgs type and the std/geometry types the bags carry, with seeded random values
(string and sequence lengths vary, so every alignment case occurs), serialized by
:func:`hrc_bag.serializer.encode` and by ``rclpy.serialization.serialize_message``.
"""

import importlib
import random

from hrc_bag import msgdefs, serializer
from hrc_bag.format import plain_values
import numpy
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.interfaces import Nodetype

# The types of the bags' topics (hrc_common.topics) and the types they are made of.
CARRIED_TYPES = ('builtin_interfaces/msg/Time', 'std_msgs/msg/Header', 'geometry_msgs/msg/Vector3',
                 'geometry_msgs/msg/Wrench', 'geometry_msgs/msg/WrenchStamped')
HRC_TYPES = tuple(f'hrc_msgs/msg/{path.stem}' for path in
                  sorted((msgdefs.share_directory('hrc_msgs') / 'msg').glob('*.msg')))
INTEGER_BITS = {'byte': (8, False), 'char': (8, False), 'uint8': (8, False), 'int8': (8, True),
                'uint16': (16, False), 'int16': (16, True), 'uint32': (32, False),
                'int32': (32, True), 'uint64': (64, False), 'int64': (64, True)}
SAMPLES = 40                                # random messages of each type


def random_value(rng: random.Random, description):
    """Return a random plain value for one field's rosbags description."""
    node, detail = description
    if node == Nodetype.NAME:
        return random_message(rng, detail)
    if node == Nodetype.BASE:
        return random_primitive(rng, detail[0])
    element, _ = detail
    if element[0] != Nodetype.BASE:
        raise NotImplementedError('a sequence of messages: teach random_value to make one')
    return [random_primitive(rng, element[1][0]) for _ in range(rng.randrange(5))]


def random_primitive(rng: random.Random, kind: str):
    if kind == 'bool':
        return rng.random() < 0.5
    if kind == 'string':
        return ''.join(rng.choice('abcxyz_/0123') for _ in range(rng.randrange(13)))
    if kind in INTEGER_BITS:
        bits, signed = INTEGER_BITS[kind]
        low = -(1 << (bits - 1)) if signed else 0
        return rng.randrange(low, low + (1 << bits))
    value = rng.uniform(-1e3, 1e3) * 10 ** rng.randrange(-6, 4)
    # a float32 field holds a float32: give one, so that neither side rounds
    return float(numpy.float32(value)) if kind == 'float32' else value


def random_message(rng: random.Random, type_name: str) -> dict:
    fields = serializer.typestore().fielddefs[type_name][1]
    return {name: random_value(rng, description) for name, description in fields}


def rclpy_message(type_name: str, values: dict):
    """Return the rclpy message of ``type_name`` holding ``values``."""
    package, _, name = type_name.split('/')
    return filled(getattr(importlib.import_module(f'{package}.msg'), name)(), values)


def filled(message, values: dict):
    for field, value in values.items():
        if isinstance(value, dict):
            filled(getattr(message, field), value)
        else:
            setattr(message, field, value)
    return message


def unwritten_positions(type_name: str, values: dict) -> set:
    """Return the byte positions the library does not write (its alignment padding)."""
    store = serializer.typestore()
    message = serializer._message_converter(type_name)(values)
    zeros = bytes(store.serialize_cdr(message, type_name))
    ones = memoryview(bytearray(b'\xff' * len(zeros)))
    ones[:4] = zeros[:4]
    store.get_msgdef(type_name).serialize_cdr_le(ones[4:], 0, message, store)
    return {index for index, (zero, one) in enumerate(zip(zeros, bytes(ones))) if zero != one}


@pytest.mark.parametrize('type_name', HRC_TYPES + CARRIED_TYPES)
def test_the_library_writes_rclpys_bytes_but_for_the_padding(type_name):
    """Equal length, equal bytes wherever the library writes, and rclpy reads them back.

    rclpy (Fast CDR) leaves the alignment padding as it finds the buffer (bytes of earlier
    allocations), the library writes zeros there: those bytes are the only ones allowed to
    differ, and reading the library's bytes with rclpy gives the message back.
    """
    assert len(HRC_TYPES) == 5
    rng = random.Random(f'serializer {type_name}')
    differing_padding = 0
    for sample in range(SAMPLES):
        values = random_message(rng, type_name)
        message = rclpy_message(type_name, values)
        theirs = serialize_message(message)
        ours = serializer.encode(type_name, values)
        assert len(ours) == len(theirs), (type_name, sample)
        padding = unwritten_positions(type_name, values)
        assert all(ours[index] == 0 for index in padding)
        assert [index for index in range(len(ours))
                if ours[index] != theirs[index] and index not in padding] == [], (type_name,
                                                                                  values)
        assert deserialize_message(ours, type(message)) == message, (type_name, values)
        # an rclpy message, a rosbags message and CDR bytes give the same bytes
        assert serializer.encode(type_name, message) == ours
        as_rosbags = serializer.typestore().deserialize_cdr(ours, type_name)
        assert serializer.encode(type_name, as_rosbags) == ours
        assert serializer.encode(type_name, theirs) == theirs
        differing_padding += sum(ours[index] != theirs[index] for index in padding)
    print(type_name, 'padding bytes rclpy left non-zero:', differing_padding)


def test_fields_left_out_are_zero():
    full = {'header': {'stamp': {'sec': 0, 'nanosec': 0}, 'frame_id': ''},
            'wrench': {'force': {'x': 0.0, 'y': 0.0, 'z': 0.0},
                       'torque': {'x': 0.0, 'y': 0.0, 'z': 0.0}}}
    from geometry_msgs.msg import WrenchStamped
    empty = serializer.encode('geometry_msgs/msg/WrenchStamped', {})
    assert deserialize_message(empty, WrenchStamped) == WrenchStamped()
    assert serializer.encode('geometry_msgs/msg/WrenchStamped', full) == empty
    assert serializer.encode('geometry_msgs/WrenchStamped', {'header': None}) == empty


def test_unknown_fields_are_named_with_their_path():
    with pytest.raises(ValueError, match=r'no field header\.stamp\.secs \(fields: sec, nanosec'):
        serializer.encode('hrc_msgs/msg/HumanAction',
                          {'header': {'stamp': {'secs': 1}}, 'episode': 1})
    with pytest.raises(ValueError, match='no field epsiode, stpe'):
        serializer.encode('hrc_msgs/msg/HumanAction', {'epsiode': 1, 'stpe': 2})
    with pytest.raises(ValueError, match='not a message type name'):
        serializer.encode('TaskState', {})


def test_plain_values_of_an_rclpy_message_encode_alike():
    from hrc_msgs.msg import SessionStatus
    status = SessionStatus(episode=4, session_id='x', robot_subtasks=['slider'])
    assert serializer.encode('hrc_msgs/msg/SessionStatus', plain_values(status)) == (
        serializer.encode('hrc_msgs/msg/SessionStatus', status))
