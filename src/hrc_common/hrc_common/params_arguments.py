"""A node's command line and parameter files, checked before ``rclpy.init`` (pure, no ROS).

:func:`parse_ros_arguments` checks a node's command line (every ``--params-file`` readable, YAML,
a mapping of node sections; every ``-p`` well formed) and :func:`node_parameter_problems` checks
what applies to one node (its section present, no unknown names, with the closest known name as
a hint). :func:`hrc_common.params.declare_parameters` adds these reasons to its own, so a node
refuses every bad parameter source at once.
"""

from dataclasses import dataclass, field, fields
import difflib
import re
import sys

import yaml

from hrc_common import bounded_yaml


# Parameters every rclpy node accepts besides its own.
ROS_BUILTIN_PARAMETERS = frozenset({'use_sim_time', 'start_type_description_service'})
ROS_BUILTIN_PREFIXES = ('qos_overrides.',)
# ROS arguments (after --ros-args) that take a value, and those that do not (rcl's list).
_ROS_VALUE_FLAGS = frozenset({'-r', '--remap', '-e', '--enclave', '--log-level',
                              '--log-file-name', '--log-config-file'})
_ROS_PLAIN_FLAGS = frozenset({'--enable-rosout-logs', '--disable-rosout-logs',
                              '--enable-stdout-logs', '--disable-stdout-logs',
                              '--enable-external-lib-logs', '--disable-external-lib-logs'})
PARAMETERS_KEY = 'ros__parameters'


def closest_hint(name: str, known) -> str:
    """Return " (did you mean 'x'?)" for the known name closest to ``name``, or ''."""
    close = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ''


@dataclass
class ParamsFile:
    """A readable --params-file: {section (node name pattern): {parameter name: value}}."""

    path: str
    sections: dict


@dataclass
class RosArguments:
    """What a node's command line asks of its parameters, and what is wrong with it."""

    files: list = field(default_factory=list)        # ParamsFile, in order
    overrides: list = field(default_factory=list)    # (node or '', parameter name) of -p
    problems: list = field(default_factory=list)     # reasons, in order


def _flatten(values: dict, prefix: str = '') -> dict:
    """Return nested parameter mappings as dotted names (as rcl does)."""
    flat = {}
    for key, value in values.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(_flatten(value, name + '.'))
        else:
            flat[name] = value
    return flat


def _sections(document: dict, where: str, problems: list, prefix: str = '') -> dict:
    """Return {node pattern: parameters} of a params document; append shape problems."""
    found = {}
    for key, value in document.items():
        name = f'{prefix}/{key}' if prefix else str(key)
        if not isinstance(value, dict):
            problems.append(f'{where}: section {name!r} must be a mapping with '
                            f'{PARAMETERS_KEY}, got {type(value).__name__}')
        elif PARAMETERS_KEY in value:
            parameters = value[PARAMETERS_KEY]
            extra = sorted(str(other) for other in value if other != PARAMETERS_KEY)
            if extra:
                problems.append(f'{where}: section {name!r} has keys {extra} next to '
                                f'{PARAMETERS_KEY} (misplaced parameters?)')
            if parameters is None:
                parameters = {}
            if not isinstance(parameters, dict):
                problems.append(f'{where}: {name}.{PARAMETERS_KEY} must be a mapping of '
                                f'parameter names, got {type(parameters).__name__}')
                parameters = {}
            found[name] = _flatten(parameters)
        elif value:
            found.update(_sections(value, where, problems, name))   # a namespace level
        else:
            problems.append(f'{where}: section {name!r} has no {PARAMETERS_KEY}')
    return found


def read_params_file(path: str, problems: list):
    """Return the ParamsFile at ``path``, or None after appending why it is unusable."""
    where = f'--params-file {path}'
    try:
        with open(path, 'rb') as stream:
            raw = stream.read()
    except OSError as error:
        problems.append(f'{where}: cannot read it: {error.strerror}')
        return None
    try:
        text = raw.decode('utf-8')
        if '\x00' in text:
            raise UnicodeDecodeError('utf-8', raw, 0, 1, 'NUL byte')
    except UnicodeDecodeError:
        problems.append(f'{where}: not a YAML parameter file (binary data)')
        return None
    try:
        document = bounded_yaml.load(text, where)
    except yaml.YAMLError as error:
        mark = getattr(error, 'problem_mark', None)
        at = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        problems.append(f'{where}: not YAML{at}: {getattr(error, "problem", None) or error}')
        return None
    if document is None:
        document = {}
    if not isinstance(document, dict):
        problems.append(f'{where}: expected a mapping of node names to {{{PARAMETERS_KEY}: '
                        f'...}}, got a {type(document).__name__}')
        return None
    return ParamsFile(path, _sections(document, where, problems))


def parse_ros_arguments(argv) -> RosArguments:
    """Parse the ``--ros-args`` sections of ``argv`` and read every --params-file (pure).

    Finds what would make ``rclpy.init`` fail with a traceback (a params file missing, not YAML,
    binary, not a mapping of node sections; ``-p`` without ``:=``; unknown ROS flags), every
    reason at once.
    """
    result = RosArguments()
    in_ros, index, argv = False, 1, list(argv)
    while index < len(argv):
        token = argv[index]
        index += 1
        if token == '--ros-args':
            in_ros = True
            continue
        if not in_ros:
            continue
        if token == '--':
            in_ros = False
            continue
        needs_value = token in ('-p', '--param', '--params-file') or token in _ROS_VALUE_FLAGS
        if needs_value and index >= len(argv):
            result.problems.append(f'--ros-args {token}: a value must follow')
            continue
        value = argv[index] if needs_value else None
        index += int(needs_value)
        if token in ('-p', '--param'):
            if ':=' not in value or not value.split(':=', 1)[0]:
                result.problems.append(f'{token} {value}: expected name:=value')
                continue
            name = value.split(':=', 1)[0]
            node, _, name = name.rpartition(':')
            result.overrides.append((node, name))
        elif token == '--params-file':
            params_file = read_params_file(value, result.problems)
            if params_file is not None:
                result.files.append(params_file)
        elif token not in _ROS_VALUE_FLAGS and token not in _ROS_PLAIN_FLAGS:
            result.problems.append(f'--ros-args: unknown argument {token!r}')
    return result


def section_applies(pattern: str, node_fqn: str) -> bool:
    """Return whether a params file section names the node ``node_fqn`` (e.g. '/sim').

    Sections as rcl reads them: ``sim``, ``/sim``, ``/**``, ``/ns/*`` (``*`` one level, ``**``
    any levels).
    """
    pattern = pattern if pattern.startswith('/') else '/' + pattern
    regex = re.escape(pattern).replace('/\\*\\*', '(/.*)?').replace('\\*', '[^/]*')
    return re.fullmatch(regex, node_fqn) is not None


def _allowed(name: str, known) -> bool:
    return (name in known or name in ROS_BUILTIN_PARAMETERS
            or name.startswith(ROS_BUILTIN_PREFIXES))


def node_parameter_problems(arguments: RosArguments, node_name: str, node_fqn: str,
                            params_cls) -> list:
    """Return why the parameter sources of ``arguments`` do not fit this node (pure).

    A params file must hold a section for the node (a misspelt section is named, with the
    node's name as the hint); the node's sections and ``-p`` must name only parameters of
    ``params_cls`` (the closest known name is the hint).
    """
    known = {dataclass_field.name for dataclass_field in fields(params_cls)}
    problems = []
    for params_file in arguments.files:
        where = f'--params-file {params_file.path}'
        applying = [key for key in params_file.sections if section_applies(key, node_fqn)]
        others = [key for key in params_file.sections if key not in applying]
        misspelt = [key for key in others if difflib.get_close_matches(
            key.rsplit('/', 1)[-1], [node_name], n=1, cutoff=0.7)]
        for key in misspelt:
            problems.append(f"{where}: section {key!r} does not name this node "
                            f"(did you mean '{node_name}'?)")
        if not applying and not misspelt:
            problems.append(f'{where}: no section for node {node_name!r} (sections: '
                            f'{others or "none"}, expected {node_name}: or /**:)')
        for key in applying:
            for name in params_file.sections[key]:
                if not _allowed(name, known):
                    problems.append(f'{where}: section {key!r}: unknown parameter {name!r}'
                                    f'{closest_hint(name, known)}')
    for node, name in arguments.overrides:
        if node and not section_applies(node, node_fqn):
            continue   # -p other_node:name applies to another node
        if not _allowed(name, known):
            problems.append(f'-p {name}: unknown parameter{closest_hint(name, known)}')
    return problems


_process_arguments = None


def set_process_arguments(argv) -> None:
    """Remember the command line the node was started with (run_node calls it)."""
    global _process_arguments
    _process_arguments = list(argv)


def process_arguments() -> RosArguments:
    """Return the parsed ROS arguments of this process (run_node's argv, else sys.argv)."""
    return parse_ros_arguments(_process_arguments if _process_arguments is not None
                               else sys.argv)
