"""Message definitions for MCAP schemas, in the form rosbag2 writes them (pure, no rclpy).

An MCAP file with the ``ros2`` profile carries, for each message type, a schema of encoding
``ros2msg`` whose data is the type's ``.msg`` text followed by the text of every type it depends
on, each one introduced by a line of 80 ``=`` and a ``MSG: pkg/Type`` header::

    <text of hrc_msgs/msg/TaskState.msg>
    ================================================================================
    MSG: std_msgs/Header
    <text of std_msgs/msg/Header.msg>
    ================================================================================
    MSG: builtin_interfaces/Time
    <text of builtin_interfaces/msg/Time.msg>

The texts come from the installed ``share/<pkg>/msg/<Type>.msg`` files (found through the ament
index), so the schema is exactly what the running graph was built with. Readers (rosbags,
mcap-ros2-support, Foxglove, ``ros2 bag``) parse this layout.
"""

import functools
import pathlib
import re

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError

SEPARATOR = '=' * 80

# Field types that are not messages (ROS 2 .msg primitive types).
PRIMITIVE_TYPES = frozenset({
    'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16',
    'int32', 'uint32', 'int64', 'uint64', 'string', 'wstring'})

# A ROS name part: a letter, then letters, digits, underscores.
_NAME = r'[A-Za-z][A-Za-z0-9_]*'
_TYPE_NAME = re.compile(rf'^({_NAME})/(?:(msg)/)?({_NAME})$')


class DefinitionNotFound(LookupError):
    """Raised when the .msg file of a type is not installed."""


def split_type_name(type_name: str) -> tuple:
    """Return (package, type) of ``pkg/msg/Type`` or ``pkg/Type``; ValueError otherwise."""
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise ValueError(f'not a message type name: {type_name!r} (expected pkg/msg/Type)')
    return match.group(1), match.group(3)


def share_directory(package: str) -> pathlib.Path:
    """Return the installed share directory of ``package`` (DefinitionNotFound if none)."""
    try:
        return pathlib.Path(get_package_share_directory(package))
    except PackageNotFoundError:
        raise DefinitionNotFound(f'package {package!r} is not in the ament index '
                                 f'(is the workspace sourced?)') from None


@functools.lru_cache(maxsize=None)
def message_text(type_name: str) -> str:
    """Return the installed .msg text of ``type_name`` (``pkg/msg/Type`` or ``pkg/Type``)."""
    package, name = split_type_name(type_name)
    path = share_directory(package) / 'msg' / f'{name}.msg'
    try:
        return path.read_text()
    except OSError as error:
        raise DefinitionNotFound(f'no message definition for {type_name}: {error}') from None


def fields(type_name: str) -> list:
    """Return [(type, name), ...] of the fields of ``type_name`` (constants left out)."""
    result = []
    for line in message_text(type_name).splitlines():
        line = line.split('#', 1)[0].strip()
        parts = line.split()
        if len(parts) < 2 or '=' in line:       # empty, or a constant (NAME=value)
            continue
        result.append((parts[0], parts[1]))
    return result


def constants(type_name: str) -> dict:
    """Return {NAME: value text} of the constants of ``type_name`` (``uint8 NAME=3``)."""
    found = {}
    for line in message_text(type_name).splitlines():
        line = line.split('#', 1)[0].strip()
        if '=' not in line or len(line.split()) < 2:
            continue
        declaration, value = line.split('=', 1)
        found[declaration.split()[-1]] = value.strip()
    return found


def field_types(text: str, package: str) -> list:
    """Return the message types the fields of a .msg ``text`` use, as ``pkg/Type``, sorted.

    Comments, constants of primitive types, array and bound suffixes are handled; a type without
    a package refers to ``package`` (the package of the .msg file).
    """
    found = set()
    for line in text.splitlines():
        line = line.split('#', 1)[0].strip()
        if not line:
            continue
        field_type = line.split()[0]
        field_type = field_type.split('[', 1)[0]      # int32[], Foo[3], Foo[<=3]
        field_type = field_type.split('<=', 1)[0]     # string<=10
        if field_type in PRIMITIVE_TYPES:
            continue
        if '/' not in field_type:
            field_type = f'{package}/{field_type}'
        found.add(field_type)
    return sorted(found)


@functools.lru_cache(maxsize=None)
def full_definition(type_name: str) -> str:
    """Return the ``ros2msg`` schema text of ``type_name`` with every dependency appended.

    Dependencies are appended depth first, each type once, in sorted order per level (as
    rosbag2 does), so two recorders of the same graph write byte-identical schemas.
    """
    seen = set()

    def with_dependencies(name: str) -> str:
        package, _ = split_type_name(name)
        text = message_text(name)
        for dependency in field_types(text, package):
            if dependency in seen:
                continue
            seen.add(dependency)
            text += f'\n{SEPARATOR}\nMSG: {dependency}\n' + with_dependencies(dependency)
        return text

    return with_dependencies(type_name)
