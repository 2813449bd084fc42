"""SAC (``algorithm: sac``): learns a small known problem, is seeded, resumes, runs a session.

The known problem: a point on a line, x' = clip(x + 0.2 a, -1, 1), reward -|x'|, 20-step
episodes from x uniform in [-1, 1]. Learned within 500 steps (seed 0; 800 gradient steps of
32 transitions): from x0 = +-0.5 and +-0.9 the deterministic policy ends within 0.05 of 0 after
10 steps (observed: at most 0.009; seed 1: 0.019). With the actor's loss sign flipped, or the
reward left out of the critics' target, it does not (checked by hand when written).
"""

import json

import numpy as np
import pytest
import torch

from hrc_engine import offline
from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.checkpoint import (CheckpointError, load_into, make_checkpoint,
                                       read_checkpoint, save_checkpoint)
from hrc_agent_node.config import AgentParams
from hrc_engine.offline import make_partner, run_episode
from hrc_agent_node.sac import SAC, squashed_log_prob
from hrc_common.contract import SimLimits
from hrc_common.params import checked, ParameterError, with_overrides
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall

# Small networks and few gradient steps keep these tests fast; the defaults are DroQ's.
SMALL_SAC = dict(sac_hidden_size=16, sac_batch_size=16, sac_updates_per_step=2,
                 sac_learning_starts=20)
# Short episodes (4 s = 20 steps) for the sessions on the physics.
PHYSICS = PhysicsParams(episode_duration=4.0)


def point_problem(seed: int, steps: int) -> list:
    """Train SAC ``steps`` steps on the point problem; return |x| after 10 judged steps."""
    config = with_overrides(AgentParams(), algorithm='sac', sac_hidden_size=32,
                            sac_batch_size=32, sac_updates_per_step=2, sac_learning_starts=100,
                            sac_reward_scale=1.0)
    agent = SAC(1, config, seed)
    rng = np.random.default_rng(seed)
    position, step_in_episode = rng.uniform(-1.0, 1.0), 0
    for _ in range(steps):
        observation = np.array([position], np.float32)
        action = agent.act(observation)[1]
        reached = float(np.clip(position + 0.2 * action, -1.0, 1.0))
        # A time limit, not a termination: the transition bootstraps (terminated False).
        agent.observe(observation, action, -abs(reached),
                      np.array([reached], np.float32), terminated=False)
        position, step_in_episode = reached, step_in_episode + 1
        if step_in_episode == 20:
            position, step_in_episode = rng.uniform(-1.0, 1.0), 0
    distances = []
    for start in (-0.9, -0.5, 0.5, 0.9):
        position = start
        for _ in range(10):
            action = agent.act(np.array([position], np.float32), deterministic=True)[1]
            position = float(np.clip(position + 0.2 * action, -1.0, 1.0))
        distances.append(abs(position))
    return distances


@pytest.mark.slow   # a training run (500 learning steps): out of the quick tier
def test_sac_learns_to_move_a_point_to_zero():
    distances = point_problem(seed=0, steps=500)
    print('|x| after 10 steps:', [round(d, 4) for d in distances])
    assert max(distances) <= 0.05


def test_squashed_log_prob_is_the_change_of_variables():
    mean, log_std = torch.tensor([[0.3], [-1.0]]), torch.tensor([[-0.5], [0.2]])
    raw = torch.tensor([[0.7], [-3.5]])
    squashed = torch.distributions.TransformedDistribution(
        torch.distributions.Normal(mean, log_std.exp()),
        [torch.distributions.transforms.TanhTransform()])
    expected = squashed.log_prob(torch.tanh(raw)).sum(-1)
    assert squashed_log_prob(raw, mean, log_std) == pytest.approx(expected, abs=1e-4)


def sac_params(**overrides):
    values = dict(case=3, seed=5, preset='tuned', algorithm='sac', max_training_episodes=6,
                  evaluation_episodes=1, checkpoint_dir='', **SMALL_SAC)
    values.update(overrides)
    return with_overrides(AgentParams(), **values)


def run(core, episodes, between=None, on_step=None):
    """Run ``episodes`` episodes as run_session does; return every action and each return.

    ``between()`` runs after each episode's update; ``on_step(core)`` after each decision.
    """
    actions, returns = [], []

    def record(state, decision, human_action):
        actions.append(decision.action)
        if on_step is not None:
            on_step(core)

    with SliderPendulumBall(PHYSICS) as sim:
        core.set_limits(SimLimits.of(sim.params))
        partner = make_partner(core)
        for _ in range(episodes):
            if core.phase == 'done':
                break
            returns.append(run_episode(core, sim, partner, on_step=record).episode_return)
            if core.phase == 'updating':
                core.update()
            if between is not None:
                between()
    return actions, returns


def test_same_seed_same_actions_and_no_global_generator_used():
    first_actions, first_returns = run(AgentCore(sac_params()), 4)
    # torch's global generator drawn between episodes must change nothing (dropout masks,
    # minibatches and noise come from the learner's own generators).
    second_actions, second_returns = run(AgentCore(sac_params()), 4,
                                         between=lambda: torch.rand(7))
    assert first_actions == second_actions and first_returns == second_returns
    other_actions, _ = run(AgentCore(sac_params(seed=6)), 4)
    assert other_actions != first_actions


def test_learning_happens_inside_act_at_defined_steps():
    core = AgentCore(sac_params())
    run(core, 1)                    # 20 transitions: the 20th starts learning (2 steps)
    assert core.policy_learner.gradient_steps == 2 and core.judging_due   # reported: judge next
    stored = len(core.policy_learner.replay)
    counts = []
    run(core, 1, on_step=lambda core: counts.append(core.policy_learner.gradient_steps))
    assert core.evaluation_results == [] and core.judging_episodes == 1
    # judging: no learning
    assert counts == [2] * 20 and len(core.policy_learner.replay) == stored
    counts = []
    run(core, 1, on_step=lambda core: counts.append(core.policy_learner.gradient_steps))
    # The first act() has no transition to store; each later one stores and learns 2 steps
    # before the action is chosen; end_episode stores the last transition and learns from it.
    assert counts == [2 + 2 * step for step in range(20)]
    assert core.policy_learner.gradient_steps == 2 + 2 * 20
    assert len(core.policy_learner.replay) == stored + 20


def test_episode_end_schedule_learns_only_in_update():
    core = AgentCore(sac_params(sac_update_at='episode_end', judging_interval=100000))
    run(core, 1)
    assert core.policy_learner.gradient_steps == 2     # the 20th transition, learned in update()
    counts = []
    with SliderPendulumBall(PHYSICS) as sim:
        run_episode(core, sim, make_partner(core),
                    on_step=lambda state, decision, human:
                    counts.append(core.policy_learner.gradient_steps))
        assert counts == [2] * 20 and core.phase == 'updating'
        stats = core.update()
    assert stats['gradient_steps'] == 2 * 20 and core.policy_learner.gradient_steps == 2 + 2 * 20


def test_checkpoint_round_trip_and_exact_resume(tmp_path):
    straight = AgentCore(sac_params())
    straight_actions, straight_returns = run(straight, 5)
    first = AgentCore(sac_params())
    first_actions, first_returns = run(first, 2)
    path = save_checkpoint(first, tmp_path / 'latest.pt')
    checkpoint = read_checkpoint(path)           # torch.load(weights_only=True) inside
    assert 'sac' in checkpoint['core'] and 'ppo' not in checkpoint['core']
    assert checkpoint['config']['params']['algorithm'] == 'sac'
    other = AgentCore(sac_params(seed=99))       # other initial weights, replaced by the file
    load_into(other, path)
    for observation in np.random.default_rng(0).normal(size=(5, 7)).astype(np.float32):
        assert other.policy_learner.act(observation, True) == first.policy_learner.act(
            observation, True)
    resumed = AgentCore(sac_params())
    load_into(resumed, path)
    assert len(resumed.policy_learner.replay) == len(first.policy_learner.replay) > 0
    resumed_actions, resumed_returns = run(resumed, 3)
    assert first_returns + resumed_returns == straight_returns
    assert first_actions + resumed_actions == straight_actions


def test_checkpoint_of_the_other_learner_is_refused(tmp_path):
    ppo_path = save_checkpoint(AgentCore(sac_params(algorithm='ppo')), tmp_path / 'ppo.pt')
    with pytest.raises(CheckpointError, match='written by the ppo learner but this agent runs '
                                              'sac'):
        load_into(AgentCore(sac_params()), ppo_path)
    sac_path = save_checkpoint(AgentCore(sac_params()), tmp_path / 'sac.pt')
    with pytest.raises(CheckpointError, match='written by the sac learner but this agent runs '
                                              'ppo'):
        load_into(AgentCore(sac_params(algorithm='ppo')), sac_path)


def test_a_sac_checkpoint_of_the_wrong_layout_is_refused_with_every_reason(tmp_path):
    checkpoint = make_checkpoint(AgentCore(sac_params()))
    del checkpoint['core']['sac']['replay']
    checkpoint['core']['sac']['updates'] = 'many'
    torch.save(checkpoint, tmp_path / 'bad.pt')
    with pytest.raises(CheckpointError) as error:
        load_into(AgentCore(sac_params()), tmp_path / 'bad.pt')
    assert "checkpoint.core.sac lacks 'replay'" in str(error.value)
    assert 'checkpoint.core.sac.updates must be int, got str' in str(error.value)


def test_a_new_reward_empties_the_replay_buffer():
    core = AgentCore(sac_params(case=2))
    run(core, 1)
    assert len(core.policy_learner.replay) == 20
    previous = core.progress.step
    core.progress.step_index = 1                 # case 2: the human joins, the ball enters
    core._start_step(previous)
    assert len(core.policy_learner.replay) == 0 and core.policy_learner.pending_updates == 0


def test_offline_case_2_session_with_sac_writes_a_checkpoint(tmp_path, capsys):
    path = tmp_path / 'sac.pt'
    code = offline.main(['--case', '2', '--learning', 'sac', '--episodes', '2',
                         '--evaluation-episodes', '1', '--quiet', '--checkpoint', str(path),
                         '--set', 'sac_hidden_size=16', 'sac_batch_size=16',
                         'sac_updates_per_step=1', 'sac_learning_starts=100'])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary['case'] == 2 and summary['training_episodes'] == 2
    assert summary['updates'] >= 1          # learning reported after the first episode
    checkpoint = read_checkpoint(path)
    assert checkpoint['core']['sac']['gradient_steps'] > 0
    assert checkpoint['core']['phase'] == 'done'


def test_a_replay_buffer_smaller_than_the_warm_up_is_refused():
    with pytest.raises(ParameterError, match='sac_learning_starts: 300 exceeds sac_replay_size '
                                             '200'):
        checked(sac_params(sac_learning_starts=300, sac_replay_size=200))
    checked(sac_params(algorithm='ppo', sac_learning_starts=300, sac_replay_size=200))
