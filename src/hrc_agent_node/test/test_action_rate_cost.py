"""Smoothness in the reward: the robot loses action_rate_cost x (a_k - a_(k-1))^2 per step.

Two seeded cores that act identically (the same seed, hand-made states, no physics), one with
the cost: every step's reward differs by exactly the cost of the change of the action; the
first step of an episode (no action before it) costs nothing; the task's components are the
same.
"""

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides
from hrc_testing.hand_states import hand_state

LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)
STEPS = 6


def state(step, final=False):
    return hand_state(step, final, slider_position=0.01 * step, pendulum_angle=0.05,
                      ball_position=0.02)


def records(cost: float) -> list:
    core = AgentCore(with_overrides(AgentParams(), case=5, seed=4, algorithm='sac',
                                    preset='tuned', checkpoint_dir='', action_rate_cost=cost,
                                    sac_learning_starts=1000), limits=LIMITS)
    core.start_episode()
    closed = [core.act(state(step)).previous for step in range(STEPS)]
    core.end_episode(state(STEPS, final=True))
    return [record for record in closed if record is not None]


def test_the_reward_loses_the_cost_of_each_change_of_the_action():
    plain, smooth = records(0.0), records(2.0)
    assert len(plain) == STEPS - 1
    for index, (a, b) in enumerate(zip(plain, smooth)):
        assert a.action == b.action and a.reward_components == b.reward_components
        before = plain[index - 1].action if index else a.action
        assert a.reward - b.reward == pytest.approx(2.0 * (a.action - before) ** 2)
    assert plain[0].reward == smooth[0].reward          # nothing before the first action
    assert any(a.reward != b.reward for a, b in zip(plain, smooth))
