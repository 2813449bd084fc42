"""When PPO updates, the learner modes, and the floor of the judging rule.

PPO updates after horizon samples or at an episode's end, whichever comes first.

Deterministic: seeded cores driven with hand-made states (no physics).
"""

import copy
import hashlib
import struct
import threading
import types

import numpy as np
import pytest

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.config import AgentParams
from hrc_agent_node.learner import BackgroundLearner, SynchronousLearner
from hrc_agent_node.strategies import episode_floor, training_episodes_per_trigger
from hrc_common.contract import SimLimits
from hrc_common.params import with_overrides

LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)


def state(step, final=False, angle=0.0, slider=0.0, ball=0.0):
    """Return a state with the attributes AgentCore reads (PhysicsState / TaskState names)."""
    return types.SimpleNamespace(step=step, slider_position=slider, slider_velocity=0.0,
                                 pendulum_angle=angle, pendulum_angular_velocity=0.0,
                                 ball_position=ball, ball_velocity=0.0, truncated=final,
                                 terminated=False, applied_force=0.0, applied_torque=0.0)


def make_core(**overrides):
    values = dict(case=1, seed=5, preset='tuned', checkpoint_dir='', horizon=3,
                  minibatch_size=2, max_training_episodes=100,
                  evaluation_episodes=0)
    values.update(overrides)
    return AgentCore(with_overrides(AgentParams(), **values), limits=LIMITS)


def angle_of(step):
    """Return a pendulum angle that changes every step, so every observation differs."""
    return 0.3 * np.sin(0.7 * step)


def test_update_runs_inside_the_episode_when_the_horizon_is_reached():
    core = make_core()
    plan = core.start_episode()
    assert not plan.judging
    updated_at = []
    for step in range(8):
        decision = core.act(state(step, angle=angle_of(step)))
        if decision.update is not None:
            updated_at.append((step, decision.update['samples'], core.ppo.updates))
    # Horizon 3: at the state of step 3 the transitions 0-2 are complete: cut, update, act.
    assert updated_at == [(3, 3, 1), (6, 3, 2)]
    assert core.buffered_samples == 0 and core.phase == 'training'
    core.end_episode(state(8, final=True, angle=angle_of(8)))
    # The episode's end comes before the next horizon: the 2 samples since step 6 update now.
    assert core.phase == 'updating' and core.buffered_samples == 2
    assert core.update()['samples'] == 2 and core.ppo.updates == 3
    # One judging episode follows (judging_interval 0): deterministic, no update inside.
    plan = core.start_episode()
    assert plan.judging
    assert all(core.act(state(step)).update is None for step in range(8))


class RecordingLearner(SynchronousLearner):
    """Keep the rollouts handed over (and do not change the weights)."""

    def __init__(self, agent):
        super().__init__(agent)
        self.rollouts = []

    def start(self, buffer):
        self.rollouts.append(buffer)
        return {'samples': len(buffer), 'seconds': 0.0}


def test_a_rollout_cut_inside_an_episode_bootstraps_from_the_cut_state():
    core = make_core(normalize_rewards=False)
    core.learner = RecordingLearner(core.ppo)
    core.start_episode()
    decisions = [core.act(state(step, angle=angle_of(step))) for step in range(4)]
    (rollout,) = core.learner.rollouts
    cut_value = decisions[3].record.value     # V(s_3): the weights did not change
    last_reward = decisions[3].previous.reward
    gamma = core.params.gamma
    # The last sample of the cut segment: return = r_2 + gamma V(s_3), not r_2 (a terminal).
    assert rollout.returns[0][-1] == pytest.approx(last_reward + gamma * cut_value, rel=1e-5)
    assert abs(gamma * cut_value) > 1e-3
    assert len(rollout) == 3


def run_with_golden_digest(core, steps=8, episodes=3):
    digest = hashlib.sha256()
    for _ in range(episodes):
        core.start_episode()
        for step in range(steps):
            record = core.act(state(step, angle=angle_of(step + core.episode))).record
            digest.update(struct.pack('<dd', record.raw_action, record.value))
        core.end_episode(state(steps, final=True))
        if core.phase == 'updating':
            core.update()
    return digest.hexdigest()


def test_synchronous_updates_inside_episodes_are_deterministic_and_swap_at_the_cut_step():
    first, second = make_core(), make_core()
    assert run_with_golden_digest(first) == run_with_golden_digest(second)
    assert first.ppo.updates == second.ppo.updates > 2
    # The action at the cut step already comes from the new weights.
    core = make_core()
    core.start_episode()
    for step in range(3):
        core.act(state(step, angle=angle_of(step)))
    before = copy.deepcopy(core.ppo.value)
    decision = core.act(state(3, angle=angle_of(3)))
    observation = core.observation(state(3, angle=angle_of(3)), 0.0)
    assert decision.update is not None
    assert decision.record.value == pytest.approx(core.ppo.value_of(observation), abs=1e-7)
    import torch
    with torch.no_grad():
        old_value = float(before(torch.as_tensor(observation).unsqueeze(0))[0])
    assert decision.record.value != pytest.approx(old_value, abs=1e-7)


def test_background_update_keeps_the_old_weights_acting_until_it_finished():
    core = make_core()
    core.set_learner_mode('background')
    assert isinstance(core.learner, BackgroundLearner)
    gate, trained = threading.Event(), threading.Event()
    real_update = core.ppo.update

    def gated_update(buffer):
        # The live networks are trained at once; the update "finishes" when the gate opens.
        stats = real_update(buffer)
        trained.set()
        assert gate.wait(30), 'the test never opened the gate'
        return stats

    core.ppo.update = gated_update
    core.start_episode()
    old_values = []
    for step in range(3):
        core.act(state(step, angle=angle_of(step)))
    frozen = copy.deepcopy(core.ppo.value)
    for step in range(3, 6):   # the update started at step 3 and has not finished
        decision = core.act(state(step, angle=angle_of(step)))
        assert decision.update is None and core.learner.busy
        old_values.append(decision.record.value)
        assert trained.wait(30)   # from step 4 on, the live networks hold the new weights
    import torch
    with torch.no_grad():
        expected = [float(frozen(torch.as_tensor(core.observation(
            state(step, angle=angle_of(step)), 0.0)).unsqueeze(0))[0])
            for step in range(3, 6)]
    assert old_values == pytest.approx(expected, abs=1e-7)
    gate.set()
    core.learner._thread.join(30)
    decision = core.act(state(6, angle=angle_of(6)))   # the next step boundary swaps
    assert decision.update is not None and decision.update['samples'] == 3
    observation = core.observation(state(6, angle=angle_of(6)), 0.0)
    assert decision.record.value == pytest.approx(core.ppo.value_of(observation), abs=1e-7)
    assert core.judging_due
    # The 3 samples of steps 3..5 (collected by the old weights while the update ran) were
    # kept: they fill the next horizon, so the next update starts at this same boundary.
    assert core.learner.busy and core.buffered_samples == 0
    core.act(state(7, angle=angle_of(7)))
    core.end_episode(state(8, final=True))
    assert core.phase == 'updating'
    stats = core.update()   # waits for the running one, then the 2 samples of steps 6..7
    assert stats['samples'] == 2 and not core.learner.busy and core.ppo.updates == 3
    core.state_dict()   # a checkpoint can be taken: nothing runs any more


# ---------------------------------------------------------------- the floor of the judging rule


@pytest.mark.parametrize('interval, floor', [
    (0, 4),      # 1 training episode (an update at its end), then 3 judging in a row
    (2, 5),      # judging after every 2nd training episode
])
def test_floor_of_human_involved_episodes_in_the_last_step(interval, floor):
    """A policy that satisfies every subtask from the start: the rule alone sets the count.

    Case 6 (learn together): one step, the human in every episode, window 3. 50-step episodes
    and horizon 128 (an update at every episode's end, as with the paper's 200 steps and 512),
    and one PPO epoch: the count does not depend on what the policy learns (every state is at
    the target), only on when updates and judging episodes come.
    """
    steps, horizon = 50, 128
    core = make_core(case=6, horizon=horizon, minibatch_size=64, epochs=1,
                     convergence_window=3, judging_interval=interval)
    while core.phase == 'training' or core.phase == 'updating':
        if core.phase == 'updating':
            core.update()
            continue
        core.start_episode()
        for step in range(steps):
            core.act(state(step))
        core.end_episode(state(steps, final=True))
    assert core.converged
    assert core.human_involved_episodes == core.total_episodes == floor
    assert episode_floor(3, training_episodes_per_trigger(interval)) == floor


def test_in_a_row_restarts_training_after_a_failed_judging_episode():
    core = make_core(horizon=4, convergence_window=3)
    kinds = []
    good, bad = dict(angle=0.0, slider=0.0), dict(angle=1.0, slider=0.09)
    # judging episodes: good, bad (window broken), then good, good, good
    judged = iter([good, bad, good, good, good])
    while core.training_step.index == 0:
        plan = core.start_episode()
        values = next(judged) if plan.judging else bad
        kinds.append('J' if plan.judging else 'T')
        for step in range(4):
            core.act(state(step, **values))
        core.end_episode(state(4, final=True, **values))
        if core.phase == 'updating':
            core.update()
    assert ''.join(kinds) == 'TJJTJJJ'
