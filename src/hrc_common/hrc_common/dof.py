"""Degrees of freedom and the wrench axis convention.

World frame ("world"): x points toward the viewer (the pendulum's joint axis), y points east
along the horizontal pendulum, z points up along the rod. Hence:

* translation: ``force.z`` (N) pushes the slider up the rod (+ = up);
* rotation: ``torque.x`` (N*m) turns the pendulum about its joint axis; + raises the east end
  (counter-clockwise as the viewer sees it) and increases P_z.

Every other wrench component is off-axis: the sim ignores it and reports it.
"""

TRANSLATION = 'translation'
ROTATION = 'rotation'
DOFS = (TRANSLATION, ROTATION)

# Index of each degree of freedom as stored in messages (HumanAction/SessionStatus DOF_*).
DOF_INDEX = {TRANSLATION: 0, ROTATION: 1}
DOF_NAME = {index: name for name, index in DOF_INDEX.items()}


def other_dof(dof: str) -> str:
    """Return the degree of freedom that is not ``dof``."""
    check_dof(dof)
    return ROTATION if dof == TRANSLATION else TRANSLATION


def check_dof(dof: str) -> str:
    """Return ``dof`` or raise ValueError naming the allowed values."""
    if dof not in DOFS:
        raise ValueError(f'unknown degree of freedom {dof!r}: expected one of {DOFS}')
    return dof


def wrench_axis(dof: str) -> tuple:
    """Return (part, axis) of the WrenchStamped component that drives ``dof``."""
    return ('force', 'z') if check_dof(dof) == TRANSLATION else ('torque', 'x')


def wrench_value(wrench, dof: str) -> float:
    """Return the component of a geometry_msgs/Wrench that drives ``dof``."""
    part, axis = wrench_axis(dof)
    return float(getattr(getattr(wrench, part), axis))


def off_axis_components(wrench, dof: str) -> dict:
    """Return {'force.x': value, ...} of the non-zero components that do not drive ``dof``."""
    driving = '.'.join(wrench_axis(dof))
    found = {}
    for part in ('force', 'torque'):
        vector = getattr(wrench, part)
        for axis in 'xyz':
            name = f'{part}.{axis}'
            value = float(getattr(vector, axis))
            if name != driving and value != 0.0:
                found[name] = value
    return found


def set_wrench_value(wrench, dof: str, value: float) -> None:
    """Set the component of ``wrench`` that drives ``dof`` to ``value``."""
    part, axis = wrench_axis(dof)
    setattr(getattr(wrench, part), axis, float(value))
