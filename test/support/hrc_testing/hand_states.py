"""Hand-made states for the agent core's tests (no physics): the attributes AgentCore reads."""

import types

DEFAULTS = dict(slider_position=0.0, slider_velocity=0.0, pendulum_angle=0.0,
                pendulum_angular_velocity=0.0, ball_position=0.0, ball_velocity=0.0,
                terminated=False, applied_force=0.0, applied_torque=0.0)


def hand_state(step: int, final: bool = False, **values):
    """Return a state of control step ``step`` (truncated when ``final``).

    ``values`` override the defaults (all 0) or add attributes (e.g. robot_command_missing).
    """
    return types.SimpleNamespace(step=step, truncated=final, **dict(DEFAULTS, **values))
