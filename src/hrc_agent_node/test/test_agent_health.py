"""The agent's ``agent: learner`` status: its levels, and what it reads of a real core.

Deterministic: seeded cores driven with hand-made states (no physics), as in
test_agent_update_schedule.
"""

import types

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.agent_health import LearnerHealth, update_line
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.diagnostics import ERROR, learner_level, OK, WARN
from hrc_common.params import with_overrides

LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)
BREAK_S = 2.0       # s between episodes, as a realtime session's episode_break


def state(step, final=False):
    return types.SimpleNamespace(step=step, slider_position=0.0, slider_velocity=0.0,
                                 pendulum_angle=0.1 * step, pendulum_angular_velocity=0.0,
                                 ball_position=0.0, ball_velocity=0.0, truncated=final,
                                 terminated=False, applied_force=0.0, applied_torque=0.0)


def core_of(algorithm):
    return AgentCore(with_overrides(AgentParams(), case=1, seed=5, preset='tuned',
                                    checkpoint_dir='', horizon=64, minibatch_size=2,
                                    algorithm=algorithm, sac_learning_starts=2,
                                    max_training_episodes=100, evaluation_episodes=0),
                     limits=LIMITS)


def values_of(status):
    return {pair.key: pair.value for pair in status.values}


def test_learner_levels():
    assert learner_level(None, BREAK_S) == (OK, 'no update yet (collecting samples)')
    assert learner_level({'seconds': 0.5, 'policy_loss': 0.1, 'value_loss': 2.0},
                         BREAK_S) == (OK, 'last update took 0.50 s')
    level, words = learner_level({'seconds': 3.5, 'policy_loss': 0.1, 'value_loss': 2.0},
                                 BREAK_S)
    assert level == WARN and 'took 3.5 s, longer than the 2.0 s break' in words
    # lockstep (no break): nobody waits for the robot's clock
    assert learner_level({'seconds': 3.5, 'policy_loss': 0.1, 'value_loss': 2.0}, 0.0)[0] == OK
    level, words = learner_level({'seconds': 0.5, 'policy_loss': float('nan'),
                                  'value_loss': float('inf')}, BREAK_S)
    assert level == ERROR and 'policy_loss and value_loss is not a finite number' in words


@pytest.mark.parametrize('algorithm', ['ppo', 'sac'])
def test_the_status_follows_a_real_core_through_an_episode_and_its_update(algorithm):
    core, health = core_of(algorithm), LearnerHealth()
    before = health.status(core, BREAK_S)
    assert before.name == 'agent: learner' and before.level == bytes([OK])
    assert values_of(before)['updates'] == '0' and values_of(before)['last_update_s'] == 'n/a'
    core.start_episode()
    for step in range(6):
        core.act(state(step))
    core.end_episode(state(6, final=True))
    assert core.phase == 'updating'
    assert values_of(health.status(core, BREAK_S))['updating'] == 'yes'
    stats = core.update()
    health.on_update(stats)
    after = health.status(core, BREAK_S)
    values = values_of(after)
    assert after.level == bytes([OK]) and values['updates'] == '1'
    assert values['algorithm'] == algorithm and values['mode'] == 'synchronous'
    assert float(values['last_update_s']) == pytest.approx(stats['seconds'], abs=1e-3)
    assert ('gradient_steps_owed' in values) == (algorithm == 'sac')
    assert update_line(stats, 'after episode 0', algorithm).startswith(
        f'{algorithm.upper()} update 1 (after episode 0): ')
    health.on_update(dict(stats, value_loss=float('nan')))
    assert health.status(core, BREAK_S).level == bytes([ERROR])
