"""What the robot observes, and the seed of each episode: shared by every loop.

``observation_of`` builds the normalized observation {B_y, P_z, S_x, a_h} (+ rates) the policy
sees; ``applied_command`` reads the human's command the sim applied from a state;
``derive_seed`` gives an episode's reset seed from the session seed. Used by
:class:`hrc_agent_node.agent_core.AgentCore` and the Gymnasium/PettingZoo environments
(hrc_gym), so both observe the same way.
"""

import numpy as np

from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits


def derive_seed(session_seed: int, episode: int) -> int:
    """Return the reset seed of an episode, derived from the session seed (31-bit)."""
    return int(np.random.SeedSequence([int(session_seed), int(episode)]).generate_state(1)[0]
               & 0x7FFFFFFF)


def observation_of(params: AgentParams, state, partner_action: float) -> np.ndarray:
    """Return the normalized observation {B_y, P_z, S_x, a_h} (+ the three rates).

    Shared by AgentCore and the Gymnasium/PettingZoo environments (hrc_gym); ``params`` gives
    the scales and ``observe_rates``; ``partner_action`` is the other actor's command.
    """
    p = params
    values = [state.ball_position / p.ball_position_scale,
              state.pendulum_angle / p.pendulum_angle_scale,
              state.slider_position / p.slider_position_scale,
              partner_action]
    if p.observe_rates:
        values += [state.ball_velocity / p.ball_velocity_scale,
                   state.pendulum_angular_velocity / p.pendulum_velocity_scale,
                   state.slider_velocity / p.slider_velocity_scale]
    # Clip: a wild state must not saturate the tanh layers into a useless gradient.
    return np.clip(np.asarray(values, dtype=np.float32), -10.0, 10.0)


def applied_command(state, dof: str, limits: SimLimits) -> float:
    """Return the normalized command the sim applied on ``dof`` in the last control period."""
    applied = state.applied_force if dof == 'translation' else state.applied_torque
    return float(applied) / limits.full_scale(dof)
