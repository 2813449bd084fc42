"""The one CDR serializer outside the nodes: plain values to the bytes rclpy publishes.

The nodes publish with rclpy. Everything else that writes messages (the in-process engine
through :class:`hrc_bag.session_writer.SessionWriter`, the bag tools, the tests' synthetic
sessions) encodes them here, with rosbags' typestore: ROS 2 Jazzy's types plus the
``hrc_msgs`` definitions of the installed ``.msg`` files (and any other installed type on
first use). ``typestore().serialize_cdr`` writes XCDR1 little endian with zero padding,
byte for byte what ``rclpy.serialization.serialize_message`` returns (a test compares every
type the bags carry with seeded random values).

``encode(type_name, message)`` takes a mapping (``{'header': {'stamp': {'sec': 1,
'nanosec': 0}, 'frame_id': 'world'}, 'episode': 3, ...}``), a dataclass, an rclpy message or
a rosbags message. Fields left out take their zero value; a key that is not a field of the
type (a typo) raises ValueError naming every such key. CDR bytes are passed through.

Cost (``bench/serializer.py``): the engine's step with this serializer against the
hand-written ``struct`` encoder it replaced, alternating in one run.
"""

import functools
import typing

from hrc_bag import msgdefs
from hrc_bag.format import plain_values
import numpy
from rosbags.interfaces import Nodetype
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

# The package whose types the Jazzy store does not know: registered from its installed files.
HRC_MESSAGES = 'hrc_msgs'
# numpy element types of primitive sequences (rosbags writes their buffer as it is)
ELEMENT_TYPES = {'bool': numpy.bool_, 'byte': numpy.uint8, 'char': numpy.uint8,
                 'int8': numpy.int8, 'uint8': numpy.uint8, 'int16': numpy.int16,
                 'uint16': numpy.uint16, 'int32': numpy.int32, 'uint32': numpy.uint32,
                 'int64': numpy.int64, 'uint64': numpy.uint64, 'float32': numpy.float32,
                 'float64': numpy.float64}
ZERO = {'bool': False, 'string': '', 'wstring': '', 'float32': 0.0, 'float64': 0.0}


@functools.lru_cache(maxsize=None)
def typestore():
    """Return the typestore: ROS 2 Jazzy plus the installed hrc_msgs types."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    folder = msgdefs.share_directory(HRC_MESSAGES) / 'msg'
    for path in sorted(folder.glob('*.msg')):
        types.update(get_types_from_msg(path.read_text(), f'{HRC_MESSAGES}/msg/{path.stem}'))
    store.register(types)
    return store


def full_name(type_name: str) -> str:
    """Return ``pkg/msg/Type`` of ``pkg/msg/Type`` or ``pkg/Type``."""
    package, name = msgdefs.split_type_name(type_name)
    return f'{package}/msg/{name}'


def known_type(type_name: str) -> str:
    """Return the full name of a type, registering it from its installed files if new."""
    name = full_name(type_name)
    store = typestore()
    if name not in store.fielddefs:
        store.register(get_types_from_msg(msgdefs.full_definition(name), name))
    return name


def _field_converter(description) -> typing.Callable:
    """Return convert(value) -> what rosbags serializes, for one field's description."""
    node, detail = description
    if node == Nodetype.NAME:
        return _message_converter(detail)
    if node == Nodetype.BASE:
        zero = ZERO.get(detail[0], 0)
        return lambda value: zero if value is None else value
    element, _ = detail
    if element[0] == Nodetype.BASE and element[1][0] in ELEMENT_TYPES:
        dtype = ELEMENT_TYPES[element[1][0]]
        return lambda values: numpy.asarray(() if values is None else values, dtype=dtype)
    convert = _field_converter(element)
    return lambda values: [convert(value) for value in (values or ())]


@functools.lru_cache(maxsize=None)
def _message_converter(type_name: str) -> typing.Callable:
    """Return convert(message) -> the typestore's message object, compiled once per type."""
    store = typestore()
    message_class = store.types[type_name]
    names = [name for name, _ in store.fielddefs[type_name][1]]
    field_names = frozenset(names)
    # built on first use: a type's fields may name types compiled later
    converters = []

    def convert(message):
        if isinstance(message, message_class):
            return message
        if message is None:
            message = {}
        elif not isinstance(message, dict):
            message = plain_values(message)
        if not field_names.issuperset(message):
            raise UnknownFields(type_name, sorted(set(message) - field_names), names)
        if not converters:
            converters.extend(_field_converter(description)
                              for _, description in store.fielddefs[type_name][1])
        get = message.get
        try:
            return message_class(*[field(get(name)) for name, field in zip(names, converters)])
        except UnknownFields as error:
            # a nested mapping's typo: name the field it is in (the error path only)
            for name, field in zip(names, converters):
                try:
                    field(get(name))
                except UnknownFields:
                    error.prefix = f'{name}.{error.prefix}'
                    raise error from None
            raise
    return convert


class UnknownFields(ValueError):
    """Keys of a mapping that are not fields of its message type."""

    def __init__(self, type_name: str, unknown: list, fields: list):
        super().__init__(type_name, unknown, fields)
        self.type_name, self.unknown, self.fields = type_name, unknown, fields
        self.prefix = ''                    # the path of the nested mapping ('header.stamp.')

    def __str__(self) -> str:
        unknown = ', '.join(self.prefix + name for name in self.unknown)
        return f'{self.type_name}: no field {unknown} (fields: {", ".join(self.fields)})'


def encode(type_name: str, message) -> bytes:
    """Return the CDR bytes of ``message`` of ``type_name`` (see the module doc)."""
    if isinstance(message, (bytes, bytearray, memoryview)):
        return bytes(message)
    name = known_type(type_name)
    return bytes(typestore().serialize_cdr(_message_converter(name)(message), name))
