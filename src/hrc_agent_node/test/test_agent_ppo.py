"""PPO core: GAE against hand-computed values (truncation bootstrapped), reward scaling, update."""


import numpy as np
import pytest
import torch

from hrc_agent_node.config import AgentParams
from hrc_agent_node.ppo import compute_gae, PPO, RewardScaler, RolloutBuffer, RunningMeanStd
from hrc_common.params import with_overrides

GAMMA, LAMBDA = 0.9, 0.5
REWARDS = [1.0, 2.0, 3.0]
VALUES = [0.5, 1.0, 1.5]
FINAL_VALUE = 2.0
# By hand, delta_t = r_t + gamma V(s_t+1) - V(s_t), A_t = delta_t + gamma lambda A_t+1:
#   truncated (bootstrap V(s_3) = 2): delta = 1.4, 2.35, 3.3 -> A = 3.12575, 3.835, 3.3
#   terminated (V(s_3) = 0):          delta = 1.4, 2.35, 1.5 -> A = 2.76125, 3.025, 1.5
TRUNCATED_ADVANTAGES = [3.12575, 3.835, 3.3]
TERMINATED_ADVANTAGES = [2.76125, 3.025, 1.5]


def test_gae_truncated_episode_bootstraps_from_the_final_value():
    advantages, returns = compute_gae(REWARDS, VALUES, [1.0, 1.5, FINAL_VALUE],
                                      [False, False, True], GAMMA, LAMBDA)
    assert advantages == pytest.approx(TRUNCATED_ADVANTAGES, abs=1e-12)
    assert returns == pytest.approx(np.add(TRUNCATED_ADVANTAGES, VALUES), abs=1e-12)


def test_gae_terminated_episode_uses_zero():
    advantages, _ = compute_gae(REWARDS, VALUES, [1.0, 1.5, 0.0], [False, False, True],
                                GAMMA, LAMBDA)
    assert advantages == pytest.approx(TERMINATED_ADVANTAGES, abs=1e-12)


def test_gae_does_not_flow_across_episodes():
    # episode A (truncated) then episode B: one step, reward 5, V = 1, terminated -> A = 4
    advantages, _ = compute_gae(REWARDS + [5.0], VALUES + [1.0], [1.0, 1.5, FINAL_VALUE, 0.0],
                                [False, False, True, True], GAMMA, LAMBDA)
    assert advantages == pytest.approx(TRUNCATED_ADVANTAGES + [4.0], abs=1e-12)


def test_gae_with_lambda_one_is_the_discounted_return_minus_value():
    advantages, returns = compute_gae(REWARDS, VALUES, [1.0, 1.5, 0.0], [False, False, True],
                                      GAMMA, 1.0)
    assert returns[0] == pytest.approx(1 + 0.9 * 2 + 0.81 * 3)
    assert advantages[0] == pytest.approx(returns[0] - VALUES[0])


def test_rollout_buffer_truncation_versus_termination():
    for terminated, expected in ((False, TRUNCATED_ADVANTAGES), (True, TERMINATED_ADVANTAGES)):
        buffer = RolloutBuffer()
        buffer.add_episode(np.zeros((3, 4)), [0.1, 0.2, 0.3], [0.0] * 3, VALUES, REWARDS,
                           FINAL_VALUE, terminated, GAMMA, LAMBDA)
        assert len(buffer) == 3
        assert buffer.tensors()['advantages'].numpy() == pytest.approx(expected, abs=1e-6)


def test_running_statistics_match_numpy():
    values = np.random.default_rng(0).normal(3.0, 2.0, size=1000)
    stats = RunningMeanStd()
    for chunk in np.array_split(values, 7):
        stats.update(chunk)
    assert stats.mean == pytest.approx(values.mean(), rel=1e-3)
    assert stats.var == pytest.approx(values.var(), rel=1e-3)


def test_reward_scaler_divides_by_return_std_and_can_be_off():
    scaler = RewardScaler(gamma=0.99)
    scaled = [scaler.scale(4.0) for _ in range(200)]
    assert scaled[-1] < 4.0 / 5  # the return grows to about 4 / (1 - 0.99) * (1 - 0.99^200)
    assert RewardScaler(gamma=0.99, enabled=False).scale(4.0) == 4.0


def small_config(**overrides):
    return with_overrides(AgentParams(), horizon=64, minibatch_size=16, **overrides)


def test_actions_are_reproducible_from_the_seed_and_bounded():
    observations = np.random.default_rng(1).normal(size=(20, 7))
    first = [PPO(7, small_config(), seed=3).act(obs) for obs in observations[:1]]
    learner_a, learner_b = PPO(7, small_config(), seed=3), PPO(7, small_config(), seed=3)
    run_a = [learner_a.act(obs) for obs in observations]
    run_b = [learner_b.act(obs) for obs in observations]
    assert run_a == run_b and run_a[0] == first[0]
    assert run_a != [PPO(7, small_config(), seed=4).act(obs) for obs in observations]
    for raw, action, _, _ in run_a:
        assert -1.0 <= action <= 1.0 and action == max(-1.0, min(1.0, raw))
    raw, action, _, _ = learner_a.act(observations[0], deterministic=True)
    with torch.no_grad():
        mean = learner_a.policy.distribution(torch.tensor(observations[:1],
                                                          dtype=torch.float32)).mean
    assert raw == pytest.approx(float(mean[0, 0]))


def test_update_moves_the_policy_toward_positive_advantages():
    """A one-state bandit: actions above 0 were good. After updates the mean action rises."""
    learner = PPO(4, small_config(clip_coef=0.2, entropy_coef=0.0), seed=0)
    observation = np.zeros(4, dtype=np.float32)
    start = learner.act(observation, deterministic=True)[0]
    for _ in range(5):
        buffer = RolloutBuffer()
        samples = [learner.act(observation) for _ in range(64)]
        raw = np.array([sample[0] for sample in samples])
        rewards = (raw > start).astype(float)   # one-step episodes, terminated
        for index in range(64):
            buffer.add_episode([observation], [raw[index]], [samples[index][2]],
                               [samples[index][3]], [rewards[index]], 0.0, True, 0.99, 0.95)
        stats = learner.update(buffer)
    assert stats['samples'] == 64 and stats['minibatches'] == 3 * 4
    assert learner.act(observation, deterministic=True)[0] > start + 0.1
