"""How the sim reads an actor's wrench command (pure, no ROS: works on any wrench-like object).

Each actor drives one degree of freedom (``hrc_common.dof``): the sim takes only that
component of its ``WrenchStamped``. The rules, in order:

1. any non-finite component (NaN, inf) refuses the whole command: the sender is broken, so no
   part of it is trusted; the step counts the command as missing (zero);
2. the driving component beyond the limit (``max_force`` N or ``max_torque`` N*m) is clamped to
   it (the limit is the actuator's: a stronger push is applied at full strength);
3. the other non-zero components are off-axis: ignored and reported.
"""

from dataclasses import dataclass, field
import math

from hrc_common.dof import check_dof, off_axis_components, TRANSLATION, wrench_axis

ROBOT = 'robot'
HUMAN = 'human'
ACTORS = (ROBOT, HUMAN)


@dataclass
class Vector3:
    """geometry_msgs/Vector3 as plain values."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass
class Wrench:
    """geometry_msgs/Wrench as plain values (what :func:`read_command` reads).

    For the loops that run without messages (the in-process engine, the offline runner).
    """

    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


def wrench_on(dof: str, value: float) -> Wrench:
    """Return a wrench with ``value`` (N or N*m) on the component driving ``dof``."""
    wrench = Wrench()
    part, axis = wrench_axis(dof)
    setattr(getattr(wrench, part), axis, float(value))
    return wrench


@dataclass(frozen=True)
class Command:
    """The outcome of reading one command: what is applied and what was wrong with it."""

    value: float                  # N or N*m applied on the actor's degree of freedom
    requested: float              # the driving component as sent (nan if refused)
    refused: str = ''             # reason the command was refused (empty if accepted)
    clamped: bool = False         # the driving component exceeded the limit
    off_axis: dict = field(default_factory=dict)  # ignored components {'torque.x': 0.3}

    @property
    def accepted(self) -> bool:
        """True unless the command was refused."""
        return not self.refused


def read_command(wrench, dof: str, limit: float) -> Command:
    """Apply the rules of this module to a geometry_msgs/Wrench-like object for ``dof``."""
    components = {f'{part}.{axis}': float(getattr(getattr(wrench, part), axis))
                  for part in ('force', 'torque') for axis in 'xyz'}
    bad = {name: value for name, value in components.items() if not math.isfinite(value)}
    if bad:
        listed = ', '.join(f'{name}={value}' for name, value in sorted(bad.items()))
        return Command(0.0, math.nan, refused=f'non-finite component(s) {listed}')
    requested = components['.'.join(wrench_axis(dof))]
    value = max(-limit, min(limit, requested))
    return Command(value, requested, clamped=value != requested,
                   off_axis=off_axis_components(wrench, dof))


def unit_of(dof: str) -> str:
    """Return the unit of the command of ``dof`` ('N' or 'N*m')."""
    return 'N' if check_dof(dof) == TRANSLATION else 'N*m'
