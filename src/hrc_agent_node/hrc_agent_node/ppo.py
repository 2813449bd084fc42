"""Proximal Policy Optimization for one continuous action (CleanRL-style, single file). Pure.

* Policy: a Gaussian over the robot's normalized action; the mean comes from an MLP (tanh
  hidden layers), the log standard deviation is a learned state-independent parameter.
  **Bounding**: the sampled action is unbounded; the command sent is the sample clipped to
  [-1, 1], and the log-probability is the one of the unclipped sample (as CleanRL and SB3 do for
  Box actions). The deterministic (evaluation) action is the mean, clipped.
* Value: a separate MLP of the same shape.
* Advantages: GAE(gamma, lambda) per episode segment. A time-limit truncation bootstraps from
  V of the final state, and so does a rollout cut inside an episode (after ``horizon`` samples)
  from V of the state where it was cut; only a termination uses 0
  (see :func:`compute_gae`).
* Update: ``epochs`` passes over the buffer in shuffled minibatches; clipped surrogate,
  value MSE, entropy bonus, advantages normalized per minibatch, global gradient-norm clip, Adam.
* Rewards for training may be divided by the running standard deviation of the discounted
  return (SB3's VecNormalize reward scaling): the paper's rewards sit near a large constant.

All randomness (initialization, exploration noise, minibatch order) comes from generators owned
by :class:`PPO`, so a run is reproduced from its seed and its state restored from a checkpoint.
"""

import copy
import math
import time

import numpy as np
import torch
from torch import nn


def compute_gae(rewards, values, next_values, episode_ends, gamma, gae_lambda):
    """Return (advantages, returns) by generalized advantage estimation.

    For each step t: ``rewards[t]`` is the reward of the transition s_t -> s_t+1, ``values[t]``
    = V(s_t), ``next_values[t]`` = V(s_t+1) (use 0 when s_t+1 is terminal; use V of the final
    state when the episode was truncated by the time limit), ``episode_ends[t]`` is true when
    the trajectory stops after step t (terminated or truncated: no advantage flows back across).

        delta_t = r_t + gamma * next_value_t - value_t
        A_t = delta_t + gamma * lambda * (1 - end_t) * A_t+1
        returns_t = A_t + value_t
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    next_values = np.asarray(next_values, dtype=np.float64)
    episode_ends = np.asarray(episode_ends, dtype=bool)
    advantages = np.zeros_like(rewards)
    running = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        if episode_ends[t]:
            running = 0.0
        delta = rewards[t] + gamma * next_values[t] - values[t]
        running = delta + gamma * gae_lambda * running
        advantages[t] = running
    return advantages, advantages + values


class RunningMeanStd:
    """Running mean and variance (parallel algorithm), for reward scaling."""

    def __init__(self):
        self.mean = 0.0
        self.var = 1.0
        self.count = 1e-4

    def update(self, values) -> None:
        """Fold a batch of values into the running statistics."""
        values = np.asarray(values, dtype=np.float64)
        if values.size == 0:
            return
        batch_mean, batch_var, batch_count = values.mean(), values.var(), values.size
        delta = batch_mean - self.mean
        total = self.count + batch_count
        self.mean += delta * batch_count / total
        m2 = self.var * self.count + batch_var * batch_count + delta ** 2 * self.count \
            * batch_count / total
        self.var = m2 / total
        self.count = total

    def state_dict(self) -> dict:
        """Return the statistics as plain data."""
        return {'mean': float(self.mean), 'var': float(self.var), 'count': float(self.count)}

    def load_state_dict(self, state: dict) -> None:
        """Restore statistics saved by :meth:`state_dict`."""
        self.mean, self.var, self.count = (float(state[key]) for key in ('mean', 'var', 'count'))


class RewardScaler:
    """Divide rewards by the running std of the discounted return (reset at episode start)."""

    def __init__(self, gamma: float, enabled: bool = True, epsilon: float = 1e-8):
        self.gamma = gamma
        self.enabled = enabled
        self.epsilon = epsilon
        self.return_stats = RunningMeanStd()
        self.discounted_return = 0.0

    def start_episode(self) -> None:
        """Forget the return of the previous episode."""
        self.discounted_return = 0.0

    def reset(self) -> None:
        """Forget every statistic (a new reward has another scale)."""
        self.return_stats = RunningMeanStd()
        self.discounted_return = 0.0

    def scale(self, reward: float, learn: bool = True) -> float:
        """Return the reward used for training; ``learn`` updates the statistics."""
        if not self.enabled:
            return float(reward)
        if learn:
            self.discounted_return = self.discounted_return * self.gamma + reward
            self.return_stats.update([self.discounted_return])
        return float(reward / math.sqrt(self.return_stats.var + self.epsilon))

    def state_dict(self) -> dict:
        """Return the scaler's state as plain data."""
        return {'stats': self.return_stats.state_dict(),
                'discounted_return': float(self.discounted_return)}

    def load_state_dict(self, state: dict) -> None:
        """Restore a state saved by :meth:`state_dict`."""
        self.return_stats.load_state_dict(state['stats'])
        self.discounted_return = float(state['discounted_return'])


def mlp(inputs: int, hidden_size: int, hidden_layers: int, outputs: int,
        output_gain: float) -> nn.Sequential:
    """Return tanh MLP with orthogonal initialization (gain sqrt 2 hidden, ``output_gain`` out)."""
    layers = []
    width = inputs
    for _ in range(hidden_layers):
        linear = nn.Linear(width, hidden_size)
        nn.init.orthogonal_(linear.weight, math.sqrt(2.0))
        nn.init.zeros_(linear.bias)
        layers += [linear, nn.Tanh()]
        width = hidden_size
    head = nn.Linear(width, outputs)
    nn.init.orthogonal_(head.weight, output_gain)
    nn.init.zeros_(head.bias)
    layers.append(head)
    return nn.Sequential(*layers)


class GaussianPolicy(nn.Module):
    """Gaussian policy over one normalized action: mean MLP, learned log std."""

    def __init__(self, observation_size: int, hidden_size: int, hidden_layers: int,
                 initial_log_std: float):
        super().__init__()
        # Small output gain: the first actions are near 0, exploration comes from the std.
        self.mean = mlp(observation_size, hidden_size, hidden_layers, 1, 0.01)
        self.log_std = nn.Parameter(torch.full((1,), float(initial_log_std)))

    def distribution(self, observations: torch.Tensor) -> torch.distributions.Normal:
        """Return the action distribution for a batch of observations."""
        mean = self.mean(observations)
        return torch.distributions.Normal(mean, self.log_std.exp().expand_as(mean))


class ValueFunction(nn.Module):
    """State-value MLP V(s)."""

    def __init__(self, observation_size: int, hidden_size: int, hidden_layers: int):
        super().__init__()
        self.net = mlp(observation_size, hidden_size, hidden_layers, 1, 1.0)

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        """Return V for a batch of observations, shape (batch,)."""
        return self.net(observations).squeeze(-1)


BUFFER_FIELDS = ('observations', 'actions', 'log_probs', 'values', 'advantages', 'returns')


class RolloutBuffer:
    """Finished episode segments waiting for the next update (GAE already computed)."""

    def __init__(self):
        self.clear()

    def clear(self) -> None:
        """Drop every stored sample."""
        self.observations = []
        self.actions = []
        self.log_probs = []
        self.advantages = []
        self.returns = []
        self.values = []

    def __len__(self) -> int:
        return sum(len(segment) for segment in self.advantages)

    def add_episode(self, observations, actions, log_probs, values, rewards, final_value,
                    terminated, gamma, gae_lambda) -> None:
        """Add one episode's samples (or a segment of one, cut where the rollout was cut).

        ``final_value`` = V of the state after the last sample (the final state of a truncated
        episode, or the state where the rollout was cut); ignored if ``terminated``.
        """
        if len(observations) == 0:
            return
        values = np.asarray(values, dtype=np.float64)
        next_values = np.append(values[1:], 0.0 if terminated else float(final_value))
        ends = np.zeros(len(values), dtype=bool)
        ends[-1] = True
        advantages, returns = compute_gae(rewards, values, next_values, ends, gamma, gae_lambda)
        self.observations.append(np.asarray(observations, dtype=np.float32))
        self.actions.append(np.asarray(actions, dtype=np.float32))
        self.log_probs.append(np.asarray(log_probs, dtype=np.float32))
        self.values.append(values.astype(np.float32))
        self.advantages.append(advantages.astype(np.float32))
        self.returns.append(returns.astype(np.float32))

    def tensors(self) -> dict:
        """Return every stored sample as float32 tensors."""
        def cat(parts):
            return torch.from_numpy(np.concatenate(parts))
        return {'observations': cat(self.observations), 'actions': cat(self.actions),
                'log_probs': cat(self.log_probs), 'advantages': cat(self.advantages),
                'returns': cat(self.returns), 'values': cat(self.values)}

    def state_dict(self) -> dict:
        """Return the stored samples as tensors (checkpoints load them with weights_only)."""
        return {name: [torch.from_numpy(np.array(segment)) for segment in getattr(self, name)]
                for name in BUFFER_FIELDS}

    def load_state_dict(self, state: dict) -> None:
        """Restore samples saved by :meth:`state_dict`."""
        for name in BUFFER_FIELDS:
            setattr(self, name, [np.asarray(segment) for segment in state[name]])


class PPO:
    """Policy, value function, optimizer and the generators of one PPO learner.

    ``config`` is any object with the PPO fields of :class:`hrc_agent_node.config.AgentParams`.
    """

    def __init__(self, observation_size: int, config, seed: int):
        self.config = config
        self.observation_size = int(observation_size)
        torch.set_num_threads(int(getattr(config, 'torch_threads', 1)))
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.policy = GaussianPolicy(observation_size, config.hidden_size,
                                         config.hidden_layers, config.initial_log_std)
            self.value = ValueFunction(observation_size, config.hidden_size,
                                       config.hidden_layers)
        parameters = list(self.policy.parameters()) + list(self.value.parameters())
        self.optimizer = torch.optim.Adam(parameters, lr=config.learning_rate, eps=1e-5)
        # Exploration noise and minibatch order: separate streams, both from the seed.
        self.action_generator = torch.Generator().manual_seed(seed * 2 + 1)
        self.shuffle_generator = torch.Generator().manual_seed(seed * 2 + 2)
        self.updates = 0
        # (policy, value) the actor uses while a background update trains the live networks.
        self._frozen_actor = None

    def freeze_actor(self) -> None:
        """Act with a copy of the current networks until :meth:`release_actor`.

        A background update (``hrc_agent_node.learner``) trains ``policy`` and ``value`` in
        another thread; the actor must neither read them half-updated nor wait for them.
        """
        self._frozen_actor = (copy.deepcopy(self.policy), copy.deepcopy(self.value))

    def release_actor(self) -> None:
        """Act with the live (updated) networks again: the weight swap, at a step boundary."""
        self._frozen_actor = None

    def _acting_networks(self) -> tuple:
        return self._frozen_actor or (self.policy, self.value)

    @torch.no_grad()
    def act(self, observation, deterministic: bool = False) -> tuple:
        """Return (raw action, clipped action, log_prob, value) for one observation."""
        policy, value_function = self._acting_networks()
        obs = torch.as_tensor(np.asarray(observation, dtype=np.float32)).unsqueeze(0)
        distribution = policy.distribution(obs)
        if deterministic:
            raw = distribution.mean
        else:
            raw = torch.normal(distribution.mean, distribution.stddev,
                               generator=self.action_generator)
        log_prob = distribution.log_prob(raw).sum(-1)
        value = value_function(obs)
        raw_value = float(raw[0, 0])
        return (raw_value, min(1.0, max(-1.0, raw_value)), float(log_prob[0]), float(value[0]))

    @torch.no_grad()
    def value_of(self, observation) -> float:
        """Return V(observation)."""
        obs = torch.as_tensor(np.asarray(observation, dtype=np.float32)).unsqueeze(0)
        return float(self._acting_networks()[1](obs)[0])

    def update(self, buffer: RolloutBuffer) -> dict:
        """Run one PPO update on every sample of ``buffer``; return statistics."""
        config = self.config
        start = time.perf_counter()
        data = buffer.tensors()
        samples = data['observations'].shape[0]
        stats = {'policy_loss': 0.0, 'value_loss': 0.0, 'entropy': 0.0, 'approx_kl': 0.0,
                 'clip_fraction': 0.0}
        batches = 0
        for _ in range(config.epochs):
            order = torch.randperm(samples, generator=self.shuffle_generator)
            for first in range(0, samples, config.minibatch_size):
                index = order[first:first + config.minibatch_size]
                if index.numel() < 2 and config.normalize_advantages:
                    continue  # a lone sample has no advantage spread to normalize by
                distribution = self.policy.distribution(data['observations'][index])
                new_log_prob = distribution.log_prob(data['actions'][index].unsqueeze(-1)
                                                     ).sum(-1)
                entropy = distribution.entropy().sum(-1).mean()
                log_ratio = new_log_prob - data['log_probs'][index]
                ratio = log_ratio.exp()
                advantages = data['advantages'][index]
                if config.normalize_advantages:
                    advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
                surrogate = torch.max(-advantages * ratio,
                                      -advantages * ratio.clamp(1.0 - config.clip_coef,
                                                                1.0 + config.clip_coef))
                policy_loss = surrogate.mean()
                value_loss = 0.5 * ((self.value(data['observations'][index])
                                     - data['returns'][index]) ** 2).mean()
                loss = policy_loss - config.entropy_coef * entropy \
                    + config.value_coef * value_loss
                self.optimizer.zero_grad()
                loss.backward()
                if config.max_grad_norm > 0:
                    nn.utils.clip_grad_norm_(list(self.policy.parameters())
                                             + list(self.value.parameters()),
                                             config.max_grad_norm)
                self.optimizer.step()
                with torch.no_grad():
                    stats['policy_loss'] += float(policy_loss)
                    stats['value_loss'] += float(value_loss)
                    stats['entropy'] += float(entropy)
                    stats['approx_kl'] += float(((ratio - 1) - log_ratio).mean())
                    stats['clip_fraction'] += float(((ratio - 1.0).abs()
                                                     > config.clip_coef).float().mean())
                batches += 1
        for key in stats:
            stats[key] /= max(batches, 1)
        self.updates += 1
        stats.update(samples=samples, minibatches=batches, seconds=time.perf_counter() - start,
                     update=self.updates, action_std=float(self.policy.log_std.detach().exp()[0]))
        return stats

    def state_dict(self) -> dict:
        """Return networks, optimizer and generators (for checkpoints)."""
        return {'policy': self.policy.state_dict(), 'value': self.value.state_dict(),
                'optimizer': self.optimizer.state_dict(),
                'action_generator': self.action_generator.get_state(),
                'shuffle_generator': self.shuffle_generator.get_state(),
                'updates': self.updates}

    def load_state_dict(self, state: dict, policy_only: bool = False) -> None:
        """Restore a state saved by :meth:`state_dict` (``policy_only``: networks alone)."""
        self.policy.load_state_dict(state['policy'])
        self.value.load_state_dict(state['value'])
        self.updates = int(state['updates'])
        if policy_only:
            return
        self.optimizer.load_state_dict(state['optimizer'])
        self.action_generator.set_state(state['action_generator'])
        self.shuffle_generator.set_state(state['shuffle_generator'])
