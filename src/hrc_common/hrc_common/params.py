"""One source of truth for node parameters: a dataclass whose fields carry their documentation.

A node's parameters are a dataclass; each field is made with :func:`param`, which stores the
description, the allowed range or choices, and whether the value may change at run time. Then

* :func:`validate` checks an instance (pure, no ROS) and returns the reasons it is bad;
* :func:`declare_parameters` declares every field on a node with a ``ParameterDescriptor``
  (description, ranges), reads the values given (``params/<node>.yaml``, ``-p``), validates
  them, and raises :class:`ParameterError` with every reason when they are bad;
* :func:`load_yaml` reads ``params/<node>.yaml`` into the dataclass without ROS (for tests,
  tools and the pure cores);
* :mod:`hrc_common.params_arguments` checks a node's command line and parameter files before
  ``rclpy.init``; :func:`declare_parameters` adds its reasons to its own, so a node refuses every
  bad parameter source at once;
* :mod:`hrc_common.params_yaml` writes ``params/<node>.yaml`` from the dataclass.

A dataclass may define ``check(self) -> list[str]`` for conditions across fields.
"""

from dataclasses import dataclass, field, fields, MISSING, replace
import math
import typing

from hrc_common import bounded_yaml

from hrc_common.params_arguments import closest_hint, node_parameter_problems, process_arguments


class ParameterError(ValueError):
    """Raised when parameter values are rejected; the message lists every reason.

    ``reasons`` holds them one by one (for printing one a line).
    """

    def __init__(self, message: str, reasons=None):
        super().__init__(message)
        self.reasons = list(reasons) if reasons else [message]


@dataclass(frozen=True)
class ParamSpec:
    """What a field accepts: description, numeric range (inclusive), or a set of choices."""

    description: str
    low: typing.Optional[float] = None
    high: typing.Optional[float] = None
    choices: typing.Optional[tuple] = None
    read_only: bool = True


def param(default, description, *, low=None, high=None, choices=None, read_only=True):
    """Make a dataclass field with its documentation and bounds.

    Lists and dicts are copied per instance (a dict: the session's ``--set`` overrides; no
    node parameter is a mapping).
    """
    spec = ParamSpec(description, low, high, tuple(choices) if choices else None, read_only)
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata={'spec': spec})
    if isinstance(default, dict):
        return field(default_factory=lambda: dict(default), metadata={'spec': spec})
    return field(default=default, metadata={'spec': spec})


def spec_of(dataclass_field) -> ParamSpec:
    """Return the ParamSpec of a field made with :func:`param`."""
    try:
        return dataclass_field.metadata['spec']
    except KeyError:
        raise TypeError(f'field {dataclass_field.name!r} was not made with params.param()')


def default_of(dataclass_field):
    """Return the default value of a dataclass field."""
    if dataclass_field.default is not MISSING:
        return dataclass_field.default
    return dataclass_field.default_factory()


def _check_value(name, value, default, spec):
    """Return the reasons why ``value`` is not acceptable for a field."""
    reasons = []
    if isinstance(default, bool):
        if not isinstance(value, bool):
            return [f'{name}: expected a boolean, got {value!r}']
    elif isinstance(default, (int, float)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return [f'{name}: expected a number, got {value!r}']
        if isinstance(default, int) and not isinstance(value, int):
            return [f'{name}: expected an integer, got {value!r}']
        if not math.isfinite(value):
            return [f'{name}: must be finite, got {value!r}']
        if spec.low is not None and value < spec.low:
            reasons.append(f'{name}: {value} is below the minimum {spec.low}')
        if spec.high is not None and value > spec.high:
            reasons.append(f'{name}: {value} is above the maximum {spec.high}')
    elif isinstance(default, str):
        if not isinstance(value, str):
            return [f'{name}: expected a string, got {value!r}']
    elif isinstance(default, list):
        if not isinstance(value, (list, tuple)):
            return [f'{name}: expected a list, got {value!r}']
        if spec.choices is not None:
            unknown = [item for item in value if item not in spec.choices]
            if unknown:
                reasons.append(f'{name}: {unknown} not among {list(spec.choices)}')
        return reasons
    elif isinstance(default, dict):
        if not isinstance(value, dict):
            return [f'{name}: expected a mapping, got {value!r}']
        return reasons
    if spec.choices is not None and value not in spec.choices:
        reasons.append(f'{name}: {value!r} is not one of {list(spec.choices)}')
    return reasons


def field_problems(dataclass_field, value) -> list:
    """Return the reasons ``value`` does not fit one field made with :func:`param`."""
    return _check_value(dataclass_field.name, value, default_of(dataclass_field),
                        spec_of(dataclass_field))


def validate(instance) -> list:
    """Return every reason why the dataclass ``instance`` holds bad values (empty if good)."""
    reasons = []
    for dataclass_field in fields(instance):
        reasons += _check_value(dataclass_field.name, getattr(instance, dataclass_field.name),
                                default_of(dataclass_field), spec_of(dataclass_field))
    if hasattr(instance, 'check'):
        # The conditions across fields too, so that every reason shows at once; a check that
        # cannot even run on the bad values says nothing more than the reasons above.
        try:
            reasons += [reason for reason in instance.check() if reason not in reasons]
        except Exception:  # noqa: BLE001 (any failure on values already refused above)
            if not reasons:
                raise
    return reasons


def checked(instance):
    """Return ``instance`` if valid, else raise ParameterError listing every reason."""
    reasons = validate(instance)
    if reasons:
        raise ParameterError(f'{type(instance).__name__} rejected: ' + '; '.join(reasons),
                             reasons)
    return instance


def from_dict(params_cls, values: dict):
    """Build and validate ``params_cls`` from a dict; unknown keys are an error."""
    names = {dataclass_field.name for dataclass_field in fields(params_cls)}
    unknown = sorted(set(values) - names)
    if unknown:
        # a parameter that once chose an earlier behaviour says where that behaviour lives
        retired = getattr(params_cls, 'RETIRED_PARAMETERS', {})
        reasons = [f'parameter {name!r} was retired: {retired[name]}' if name in retired
                   else f'unknown parameter {name!r}{closest_hint(name, names)}'
                   for name in unknown]
        raise ParameterError(f'{params_cls.__name__}: ' + '; '.join(reasons), reasons)
    converted = {}
    for dataclass_field in fields(params_cls):
        if dataclass_field.name in values:
            value = values[dataclass_field.name]
            default = default_of(dataclass_field)
            # YAML writes 1 for 1.0; accept integers where a float is expected.
            is_integer = isinstance(value, int) and not isinstance(value, bool)
            if isinstance(default, float) and is_integer:
                value = float(value)
            if isinstance(default, list) and isinstance(value, tuple):
                value = list(value)
            converted[dataclass_field.name] = value
    return checked(params_cls(**converted))


def load_yaml(params_cls, path, node_name: str):
    """Read ``path`` (ROS 2 parameter YAML) and return ``params_cls`` for ``node_name``.

    Accepts the node's own section (``node_name:`` or ``/**:``) with ``ros__parameters``.
    """
    with open(path) as stream:
        document = bounded_yaml.load(stream.read(), str(path)) or {}
    values = {}
    for key in ('/**', node_name, '/' + node_name):
        section = document.get(key)
        if section is not None:
            values.update(section.get('ros__parameters', {}) or {})
    return from_dict(params_cls, values)


def with_overrides(instance, **overrides):
    """Return a validated copy of ``instance`` with some fields replaced."""
    return checked(replace(instance, **overrides))


def as_dict(instance) -> dict:
    """Return the parameters as a plain dict (for logs, bag metadata, checkpoints)."""
    return {dataclass_field.name: getattr(instance, dataclass_field.name)
            for dataclass_field in fields(instance)}


def describe(params_cls) -> str:
    """Return a help text listing every parameter with its default, bounds and description."""
    lines = []
    for dataclass_field in fields(params_cls):
        spec = spec_of(dataclass_field)
        bounds = ''
        if spec.low is not None or spec.high is not None:
            bounds = f' [{spec.low if spec.low is not None else "-inf"}, ' \
                     f'{spec.high if spec.high is not None else "inf"}]'
        if spec.choices:
            bounds = f' {{{", ".join(map(str, spec.choices))}}}'
        lines.append(f'  {dataclass_field.name} (default {default_of(dataclass_field)!r}){bounds}')
        lines.append(f'      {spec.description}')
    return '\n'.join(lines)


def _integer_override_as_float(node, name: str, default) -> None:
    """Let ``-p max_force:=3`` or ``max_force: 3`` in a file set a float parameter to 3.0.

    rcl types a number without a decimal point as an integer, which rclpy refuses for a float
    parameter; the override is converted before the parameter is declared.
    """
    from rclpy.parameter import Parameter  # lazy: rclpy, only nodes call this

    overrides = getattr(node, '_parameter_overrides', None)
    given = overrides.get(name) if isinstance(overrides, dict) else None
    if (isinstance(default, float) and given is not None
            and given.type_ == Parameter.Type.INTEGER):
        overrides[name] = Parameter(name, Parameter.Type.DOUBLE, float(given.value))


def declare_parameters(node, params_cls):
    """Declare every field of ``params_cls`` on ``node`` and return the validated values.

    Ranges go into the ParameterDescriptor (so ``ros2 param describe`` shows them); values that
    break a range, a choice or a cross-field check raise ParameterError with every reason.
    Read-only fields cannot change after start; the others are re-validated on every change.
    """
    # rclpy: only nodes declare parameters; the pure cores import this module without it
    from rcl_interfaces.msg import (  # lazy: rclpy's messages, only nodes declare parameters
        FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult)
    from rclpy.exceptions import InvalidParameterValueException  # lazy: rclpy, as above

    values = {}
    # Sources that do not fit the node (a misspelt section, unknown names) come first.
    reasons = node_parameter_problems(process_arguments(), node.get_name(),
                                      node.get_fully_qualified_name(), params_cls)
    for dataclass_field in fields(params_cls):
        spec = spec_of(dataclass_field)
        default = default_of(dataclass_field)
        description = spec.description
        if spec.choices:
            description += f' (one of: {", ".join(map(str, spec.choices))})'
        descriptor = ParameterDescriptor(description=description, read_only=spec.read_only)
        # rclpy enforces these ranges itself (at declaration and on later changes).
        if isinstance(default, float) and spec.low is not None and spec.high is not None:
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=float(spec.low), to_value=float(spec.high), step=0.0)]
        elif (isinstance(default, int) and not isinstance(default, bool)
              and spec.low is not None and spec.high is not None):
            descriptor.integer_range = [IntegerRange(
                from_value=int(spec.low), to_value=int(spec.high), step=0)]
        _integer_override_as_float(node, dataclass_field.name, default)
        try:
            value = node.declare_parameter(dataclass_field.name, default, descriptor).value
            # An empty YAML list ([]) arrives untyped (NOT_SET): it means an empty list.
            values[dataclass_field.name] = [] if value is None and isinstance(default, list) \
                else value
        except InvalidParameterValueException as error:
            reasons.append(f'{dataclass_field.name}: {error}')
        except Exception as error:  # a wrong type given on the command line or YAML
            reasons.append(f'{dataclass_field.name}: {type(error).__name__}: {error}')
    if reasons:
        # Check the other values too, so that one run lists every reason.
        try:
            from_dict(params_cls, values)
        except ParameterError as error:
            reasons += error.reasons
        raise ParameterError(f'{params_cls.__name__} rejected: ' + '; '.join(reasons), reasons)
    current = from_dict(params_cls, values)
    known = set(values)

    def on_set(changes):
        # Names of other parameter sets on the same node are theirs to check.
        proposed = {change.name: change.value for change in changes if change.name in known}
        if not proposed:
            return SetParametersResult(successful=True)
        try:
            from_dict(params_cls, {**as_dict(current), **proposed})
        except ParameterError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)
    return current
