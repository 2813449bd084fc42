"""AgentParams: Table I defaults; bad values are refused with reasons; core wiring."""

from dataclasses import fields
import math
import types

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.observation import derive_seed
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import checked, ParameterError, with_overrides

def test_table_one_defaults():
    p = AgentParams()
    assert (p.gamma, p.horizon, p.entropy_coef, p.clip_coef, p.gae_lambda, p.minibatch_size,
            p.learning_rate, p.epochs) == (0.995, 512, 0.02, 0.05, 0.95, 64, 0.001, 3)
    assert p.preset == 'paper'


@pytest.mark.parametrize('overrides, reason', [
    ({'case': 9}, 'case: 9 is above the maximum 8'),
    ({'gamma': 1.5}, 'gamma: 1.5 is above the maximum 1.0'),
    ({'mode': 'turbo'}, "mode: 'turbo' is not one of"),
    ({'minibatch_size': 600}, 'minibatch_size: 600 exceeds horizon 512'),
    ({'evaluation_only': True}, 'evaluation_only: needs resume_from'),
    ({'evaluation_only': True, 'resume_from': 'x.pt', 'evaluation_episodes': 0},
     'needs evaluation_episodes of at least 1'),
])
def test_bad_values_are_refused_with_reason(overrides, reason):
    with pytest.raises(ParameterError) as error:
        checked(AgentParams(**overrides))
    assert reason in str(error.value)


def test_episode_seeds_are_derived_and_distinct():
    seeds = [derive_seed(3, episode) for episode in range(100)]
    assert len(set(seeds)) == 100 and all(0 <= seed < 2**31 for seed in seeds)
    assert seeds == [derive_seed(3, episode) for episode in range(100)]
    assert seeds != [derive_seed(4, episode) for episode in range(100)]


def fake_state(step, final=False, slider=0.01, angle=-0.2, ball=0.1):
    return types.SimpleNamespace(step=step, slider_position=slider, slider_velocity=0.0,
                                 pendulum_angle=angle, pendulum_angular_velocity=0.0,
                                 ball_position=ball, ball_velocity=0.0, truncated=final,
                                 terminated=False)


def test_core_rewards_the_state_reached_and_observes_zero_without_the_human():
    # Limits unlike the defaults: the wrench is scaled with the sim's, not a value of the agent.
    core = AgentCore(with_overrides(AgentParams(), case=2, preset='tuned', checkpoint_dir=''),
                     limits=SimLimits(control_period=0.1, max_force=3.0, max_torque=0.7))
    assert core.robot_dof == 'rotation' and not core.human_involved
    core.start_episode()
    with pytest.raises(ValueError, match='the human is not involved'):
        core.act(fake_state(0), human_action=0.7)
    first = core.act(fake_state(0))
    assert first.previous is None
    assert first.record.observed_human_action == 0.0   # the human is not involved in step 1
    assert first.wrench == pytest.approx(first.action * 0.7)
    second = core.act(fake_state(1, angle=0.05))
    record = second.previous
    assert record.step == 0 and record.subtask_ids == ('slider', 'pendulum')
    slider, pendulum = core.tree.shapes['slider'], core.tree.shapes['pendulum']
    assert record.reward_components == pytest.approx(
        (slider.value(0.01), pendulum.value(0.05)))     # from state 1, the state reached
    assert record.reward == pytest.approx(sum(record.reward_components))
    with pytest.raises(ValueError, match='step 1 again'):
        core.act(fake_state(1))
    result = core.end_episode(fake_state(2, final=True, angle=-0.3))
    assert result.steps == 2 and result.last_record.step == 1
    assert result.episode_return == pytest.approx(record.reward + result.last_record.reward)
    assert result.errors['pendulum'] == pytest.approx((0.05 + 0.3) / 2)
    assert result.human_effort == 0.0 and not math.isnan(result.robot_effort)
    assert core.total_episodes == 1 and core.human_involved_episodes == 0
    assert core.episode == 1 and not core.in_episode


def test_the_core_acts_only_with_the_sims_limits_and_refuses_unusable_ones():
    """The limits are the sim's: no AgentParams field, no default; bad values named at once."""
    names = {field.name for field in fields(AgentParams)}
    assert not {'max_force', 'max_torque', 'control_period'} & names
    core = AgentCore(with_overrides(AgentParams(), case=2, checkpoint_dir=''))
    core.start_episode()
    with pytest.raises(RuntimeError, match="the sim's limits are not known yet"):
        core.act(fake_state(0))
    with pytest.raises(ValueError) as refused:
        core.set_limits(SimLimits(control_period=0.2, max_force=math.nan, max_torque=0.0))
    assert 'max_force' in str(refused.value) and 'max_torque' in str(refused.value)
    assert not core.limits_known
    assert not core.set_limits(SimLimits(0.2, 2.0, 0.5))          # first: nothing changed
    decision = core.act(fake_state(0))
    assert decision.wrench == pytest.approx(decision.action * 0.5)
    assert core.set_limits(SimLimits(0.2, 2.0, 0.25))             # a different sim: reported
