"""Convergence judged on judging episodes; PPO fixes; evaluation resumed without double count.

PPO fixes: the buffer and the reward scale reset on a new reward, and a truncated episode
bootstraps from the final state's observation.

Deterministic: seeded cores driven with hand-made states (no physics), so each test knows
exactly which episodes satisfy the step's condition.
"""

import types

import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import load_into, save_checkpoint
from hrc_agent_node.config import AgentParams
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides

STEPS = 4          # control steps per hand-made episode
LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)   # a sim's
GOOD = dict(slider=0.0, angle=0.0, ball=0.0)       # every subtask satisfied
BAD = dict(slider=0.09, angle=1.0, ball=0.2)       # none satisfied


def state(step, final=False, slider=0.0, angle=0.0, ball=0.0, force=0.0, torque=0.0):
    """Return a state with the attributes AgentCore reads (PhysicsState / TaskState names)."""
    return types.SimpleNamespace(step=step, slider_position=slider, slider_velocity=0.0,
                                 pendulum_angle=angle, pendulum_angular_velocity=0.0,
                                 ball_position=ball, ball_velocity=0.0, truncated=final,
                                 terminated=False, applied_force=force, applied_torque=torque)


def make_core(**overrides):
    """Return a seeded core whose update is due after 2 hand-made episodes (horizon 8)."""
    values = dict(case=1, seed=5, preset='tuned', checkpoint_dir='', horizon=8,
                  minibatch_size=4, convergence_window=2, satisfied_window=2,
                  max_training_episodes=100, evaluation_episodes=0)
    values.update(overrides)
    return AgentCore(with_overrides(AgentParams(), **values), limits=LIMITS)


def run_episode(core, training=BAD, judging=GOOD):
    """Run one hand-made episode: ``training`` values in training, ``judging`` otherwise."""
    plan = core.start_episode()
    values = judging if plan.deterministic else training
    for step in range(STEPS):
        core.act(state(step, **values))
    result = core.end_episode(state(STEPS, final=True, **values))
    if core.phase == 'updating':
        core.update()
    return plan, result


def test_judging_episode_follows_each_update_and_alone_decides_the_advance():
    core = make_core()
    kinds = []
    while core.training_step.index == 0:
        plan, result = run_episode(core)
        kinds.append('judging' if plan.judging else 'training')
        assert not plan.evaluation
    # An update at the training episode's end, then judging episodes of the same policy in a
    # row until the window (2) is full.
    assert kinds == ['training', 'judging', 'judging']
    assert result.judging and result.converged and result.event == 'advanced'
    # Every episode counts in the totals; the judging ones are not learned from.
    assert core.total_episodes == 3 and core.judging_episodes == 2
    assert core.buffered_samples == 0


def test_judging_episodes_are_deterministic_counted_and_human_involved():
    core = make_core(case=5)   # learn together: the human acts from the first episode
    records = []
    for _ in range(3):
        plan = core.start_episode()
        for step in range(STEPS):
            records.append((plan.judging, core.act(state(step, **BAD)).record))
        core.end_episode(state(STEPS, final=True, **BAD))
        if core.phase == 'updating':
            samples = core.buffered_samples
            core.update()
    # training (update), judging (fails: training resumes), training (update): each update
    # learns from its training episode alone, the judging episode added no sample
    assert samples == STEPS
    assert all(record.deterministic == judging for judging, record in records)
    assert (core.total_episodes, core.human_involved_episodes, core.judging_episodes) == \
        (3, 3, 1)


def test_judging_interval_counts_training_episodes():
    core = make_core(judging_interval=3)     # the updates after each episode trigger none
    kinds = [run_episode(core, judging=BAD)[0].judging for _ in range(8)]
    assert kinds == [False, False, False, True, False, False, False, True]


def advance(core) -> list:
    """Run bad training and good judging episodes until the first step advances; its kinds."""
    kinds = []
    while core.training_step.index == 0:
        plan, result = run_episode(core)
        kinds.append('J' if plan.judging else 'T')
    assert result.event == 'advanced' and core.phase == 'training'
    return kinds


def test_new_reward_resets_the_buffer_and_the_reward_scaler():
    """Case 1 step 1 (slider + pendulum) -> step 2 (all three): the old reward's scale goes.

    The training episode's rewards moved the scaler; the two judging episodes that advance
    the step add none, so without the reset step 2 would learn with step 1's scale.
    """
    core = make_core()
    assert advance(core) == ['T', 'J', 'J']
    assert core.buffered_samples == 0
    assert core.reward_scaler.state_dict() == AgentCore(core.params).reward_scaler.state_dict()


def test_same_reward_keeps_the_reward_scale(tmp_path):
    """A step change that keeps the robot's reward keeps its scale."""
    cases = tmp_path / 'cases.yaml'
    cases.write_text(
        'strategies:\n  two_same:\n    steps:\n'
        '      - {robot_subtasks: [slider, pendulum], human_involved: false, advance: converged}\n'
        '      - {robot_subtasks: [slider, pendulum], human_involved: true,\n'
        '         human_subtasks: [ball], advance: converged}\n'
        'cases:\n  1: {strategy: two_same, robot_action: translation}\n')
    core = make_core(cases_file=str(cases))
    advance(core)
    assert core.training_step.index == 1
    assert core.reward_scaler.state_dict()['stats']['count'] > 1


def test_truncated_episode_bootstraps_from_the_final_state_with_its_human_action():
    """The value of the final state is taken with the human command applied at that state."""
    core = make_core(case=5)                  # the human turns the pendulum, observed applied
    max_torque = core.limits.max_torque
    seen = []
    value_of = core.ppo.value_of
    core.ppo.value_of = lambda observation: seen.append(observation) or value_of(observation)
    core.start_episode()
    for step in range(STEPS):
        core.act(state(step, torque=0.1 * max_torque))
    core.end_episode(state(STEPS, final=True, torque=-0.7 * max_torque))
    assert len(seen) == 1
    assert seen[0] == pytest.approx(core.observation(state(STEPS, torque=-0.7 * max_torque),
                                                     -0.7))
    assert seen[0][3] == pytest.approx(-0.7)   # not the previous step's 0.1


def test_evaluation_aborted_then_resumed_runs_only_the_episodes_left(tmp_path):
    """Abort after 2 of 3 evaluation episodes, resume: 1 more, 3 in all (was 2 + 3 = 5)."""
    checkpoint = tmp_path / 'latest.pt'
    core = make_core(max_training_episodes=1, evaluation_episodes=3)
    run_episode(core)
    assert core.phase == 'evaluation'
    for _ in range(2):
        plan, _ = run_episode(core)
        assert plan.evaluation
        save_checkpoint(core, checkpoint)      # the node saves latest.pt at each episode end
    core.start_episode()
    core.act(state(0))
    core.abort()                               # the third evaluation episode is dropped
    resumed = make_core(max_training_episodes=1, evaluation_episodes=3)
    load_into(resumed, checkpoint)
    run = 0
    while resumed.phase != 'done':
        plan, _ = run_episode(resumed)
        assert plan.evaluation and plan.episode == 3
        run += 1
    assert run == 1 and resumed.evaluation_summary()['episodes'] == 3
    # A finished session stays finished when resumed: no evaluation episode runs again.
    save_checkpoint(resumed, checkpoint)
    again = make_core(max_training_episodes=1, evaluation_episodes=3)
    load_into(again, checkpoint)
    assert again.phase == 'done' and again.evaluation_summary()['episodes'] == 3
