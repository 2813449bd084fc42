"""Soft Actor-Critic with a high update-to-data ratio, DroQ style (``algorithm: sac``). Pure.

The off-policy learner beside PPO (``ppo.py``): it learns from a replay buffer of single
transitions, so it can learn at every control step instead of only after a horizon of samples.

* Policy: a tanh-squashed Gaussian over the robot's normalized action; mean and log standard
  deviation (clamped to [-5, 2]) come from one ReLU MLP. The command sent is tanh(sample), in
  (-1, 1), and its log-probability includes the tanh correction. The deterministic (judging,
  evaluation) action is tanh(mean).
* Critics: an ensemble of ``sac_critics`` Q-functions, each hidden layer Linear -> Dropout ->
  LayerNorm -> ReLU (DroQ: Hiraoka et al. 2022, "Dropout Q-functions for doubly efficient
  reinforcement learning"). The small dropout and the layer norm keep the Q estimates from
  running away when the critics take ``sac_updates_per_step`` gradient steps per control step
  (update-to-data ratio 20 in DroQ). Targets: soft Polyak copies (``sac_tau``), the minimum over
  the ensemble, minus temperature * log-probability of the next action.
* Temperature: learned (log), toward the target entropy -1 (minus the action size).
* Bootstrapping: a time-limit truncation bootstraps from the final state; only a termination
  uses 0 (the transition's ``terminated`` flag).
* Reward: the task's reward (the same tree, preset and step as PPO's) times the fixed
  ``sac_reward_scale``. Not PPO's running normalization: a replay buffer would then hold
  transitions of different scales side by side (and the normalized rewards, ~0.25 a step, left
  the entropy bonus dominant: the first try's training episodes kept an action std of 0.8).

Why DroQ and not REDQ: REDQ reaches the same sample efficiency with 10 critics and a random
subset of 2 in each target; DroQ needs 2 critics, so each of the many gradient steps costs a
fifth of REDQ's, which matters on the 2 cores the sim, the person's model and the learner share.
The ensemble is one module (batched matrix products), not a Python loop over critics.

When it learns (:attr:`SAC.update_schedule`): ``step`` = the owed gradient steps run as soon as
a transition is stored, which AgentCore does inside ``act()`` (before the next action is chosen)
and ``end_episode()``, so the steps where learning happens are defined by the episode alone
(lockstep sessions, the graph and the in-process engine stay identical); ``episode_end`` = the
gradient steps owed for an episode's transitions run in ``update()``, between episodes.
In the agent node's realtime episodes the owed steps of the ``step`` schedule run in a learner
thread instead (``sac_background``): the control step only stores the transition and acts.

All randomness (initialization, exploration noise, dropout masks, minibatch sampling, the
policy's samples in the updates) comes from generators owned by :class:`SAC`, never from
torch's global generator, so a run is reproduced from its seed and restored from a checkpoint.
"""

import math
import threading
import time

import numpy as np
import torch
from torch import nn

from hrc_agent_node.sac_background import BackgroundSACLearning

LOG_STD_MIN = -5.0
LOG_STD_MAX = 2.0
ACTION_SIZE = 1

REPLAY_FIELDS = ('observations', 'actions', 'rewards', 'next_observations', 'terminated')

# The learner's part of a checkpoint (checkpoint.py checks a file against it before loading).
STATE_LAYOUT = {
    'actor': dict, 'critic': dict, 'target_critic': dict, 'log_temperature': torch.Tensor,
    'actor_optimizer': dict, 'critic_optimizer': dict, 'temperature_optimizer': dict,
    'action_generator': torch.Tensor, 'update_generator': torch.Tensor,
    'updates': int, 'gradient_steps': int, 'pending_updates': int,
    'replay': {'size': int, 'position': int,
               **{name: torch.Tensor for name in REPLAY_FIELDS}},
}


class ReplayBuffer:
    """Ring buffer of transitions (s, a, r, s', terminated), newest overwriting the oldest."""

    def __init__(self, observation_size: int, capacity: int):
        self.observation_size = int(observation_size)
        self.capacity = int(capacity)
        self.clear()

    def clear(self) -> None:
        """Drop every transition."""
        self.observations = np.zeros((self.capacity, self.observation_size), np.float32)
        self.actions = np.zeros((self.capacity, ACTION_SIZE), np.float32)
        self.rewards = np.zeros(self.capacity, np.float32)
        self.next_observations = np.zeros((self.capacity, self.observation_size), np.float32)
        self.terminated = np.zeros(self.capacity, np.float32)
        self.size = 0
        self.position = 0      # where the next transition goes

    def __len__(self) -> int:
        return self.size

    def add(self, observation, action: float, reward: float, next_observation,
            terminated: bool) -> None:
        """Store one transition."""
        index = self.position
        self.observations[index] = observation
        self.actions[index, 0] = action
        self.rewards[index] = reward
        self.next_observations[index] = next_observation
        self.terminated[index] = float(terminated)
        self.position = (index + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)

    def sample(self, batch_size: int, generator: torch.Generator) -> dict:
        """Return ``batch_size`` transitions drawn uniformly with replacement, as tensors."""
        index = torch.randint(self.size, (batch_size,), generator=generator).numpy()
        return {name: torch.from_numpy(getattr(self, name)[index]) for name in REPLAY_FIELDS}

    def state_dict(self) -> dict:
        """Return the stored transitions as tensors (checkpoints load them with weights_only)."""
        state = {name: torch.from_numpy(getattr(self, name)[:self.size].copy())
                 for name in REPLAY_FIELDS}
        state.update(size=self.size, position=self.position)
        return state

    def load_state_dict(self, state: dict) -> None:
        """Restore transitions saved by :meth:`state_dict` (into a buffer of this capacity)."""
        size = int(state['size'])
        if size > self.capacity:
            raise ValueError(f'the checkpoint holds {size} transitions but sac_replay_size is '
                             f'{self.capacity}')
        self.clear()
        for name in REPLAY_FIELDS:
            getattr(self, name)[:size] = state[name].numpy()
        self.size = size
        self.position = int(state['position']) % self.capacity


class GeneratorDropout(nn.Module):
    """Dropout whose masks come from a given generator (torch's own uses the global one)."""

    def __init__(self, probability: float, generator: torch.Generator):
        super().__init__()
        self.probability = float(probability)
        self.generator = generator

    def forward(self, inputs: torch.Tensor) -> torch.Tensor:
        """Zero each input with the probability and rescale the rest (training mode only)."""
        if not self.training or self.probability == 0.0:
            return inputs
        keep = torch.rand(inputs.shape, generator=self.generator) >= self.probability
        return inputs * keep / (1.0 - self.probability)


class EnsembleLinear(nn.Module):
    """``members`` independent linear layers applied in one batched product.

    Input (members, batch, inputs) -> output (members, batch, outputs). Initialized as
    nn.Linear is (uniform in +-1/sqrt(inputs)), each member from its own draws.
    """

    def __init__(self, members: int, inputs: int, outputs: int):
        super().__init__()
        bound = 1.0 / math.sqrt(inputs)
        self.weight = nn.Parameter(torch.empty(members, inputs, outputs).uniform_(-bound, bound))
        self.bias = nn.Parameter(torch.empty(members, 1, outputs).uniform_(-bound, bound))

    def forward(self, inputs: torch.Tensor) -> torch.Tensor:
        """Return bias + inputs @ weight for every member."""
        return torch.baddbmm(self.bias, inputs, self.weight)


class CriticEnsemble(nn.Module):
    """Q(s, a) of every member: hidden layers Linear -> Dropout -> LayerNorm -> ReLU (DroQ)."""

    def __init__(self, observation_size: int, hidden_size: int, hidden_layers: int,
                 members: int, dropout: float, dropout_generator: torch.Generator):
        super().__init__()
        self.members = members
        layers = []
        width = observation_size + ACTION_SIZE
        for _ in range(hidden_layers):
            layers += [EnsembleLinear(members, width, hidden_size),
                       GeneratorDropout(dropout, dropout_generator),
                       nn.LayerNorm(hidden_size), nn.ReLU()]
            width = hidden_size
        layers.append(EnsembleLinear(members, width, 1))
        self.net = nn.Sequential(*layers)

    def forward(self, observations: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        """Return Q of every member, shape (members, batch)."""
        inputs = torch.cat([observations, actions], dim=-1)
        inputs = inputs.unsqueeze(0).expand(self.members, -1, -1)
        return self.net(inputs).squeeze(-1)


class SquashedGaussianActor(nn.Module):
    """Policy: a Gaussian (mean and log std from one MLP) squashed by tanh into (-1, 1)."""

    def __init__(self, observation_size: int, hidden_size: int, hidden_layers: int):
        super().__init__()
        layers = []
        width = observation_size
        for _ in range(hidden_layers):
            layers += [nn.Linear(width, hidden_size), nn.ReLU()]
            width = hidden_size
        self.body = nn.Sequential(*layers)
        self.head = nn.Linear(width, 2 * ACTION_SIZE)   # mean and log std

    def mean_and_log_std(self, observations: torch.Tensor) -> tuple:
        """Return the Gaussian's mean and (clamped) log standard deviation."""
        mean, log_std = self.head(self.body(observations)).chunk(2, dim=-1)
        return mean, log_std.clamp(LOG_STD_MIN, LOG_STD_MAX)

    def sample(self, observations: torch.Tensor, generator: torch.Generator) -> tuple:
        """Return (raw sample, squashed action, log-probability of the squashed action)."""
        mean, log_std = self.mean_and_log_std(observations)
        noise = torch.randn(mean.shape, generator=generator)
        raw = mean + log_std.exp() * noise      # reparameterized: gradients flow to mean, std
        return raw, torch.tanh(raw), squashed_log_prob(raw, mean, log_std)


def squashed_log_prob(raw: torch.Tensor, mean: torch.Tensor,
                      log_std: torch.Tensor) -> torch.Tensor:
    """Return log pi(tanh(raw)) summed over the action: the Gaussian's minus log|d tanh/d raw|.

    log(1 - tanh(u)^2) = 2 (log 2 - u - softplus(-2u)), a form that stays finite for large |u|.
    """
    gaussian = torch.distributions.Normal(mean, log_std.exp()).log_prob(raw)
    correction = 2.0 * (math.log(2.0) - raw - nn.functional.softplus(-2.0 * raw))
    return (gaussian - correction).sum(-1)


class SAC:
    """Actor, critics, temperature, replay buffer and generators of one SAC learner.

    ``config`` is any object with the ``sac_*`` fields of
    :class:`hrc_agent_node.config.AgentParams` (and ``hidden_layers``, ``torch_threads``).
    The methods AgentCore calls: :meth:`act`, :meth:`observe`, :attr:`update_due`,
    :meth:`update`, :meth:`clear_replay`, :meth:`state_dict`, :meth:`load_state_dict`.
    """

    def __init__(self, observation_size: int, config, seed: int):
        self.config = config
        self.observation_size = int(observation_size)
        torch.set_num_threads(int(getattr(config, 'torch_threads', 1)))
        # Exploration noise; dropout masks, minibatches and the updates' policy samples.
        self.action_generator = torch.Generator().manual_seed(seed * 2 + 1)
        self.update_generator = torch.Generator().manual_seed(seed * 2 + 2)
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.actor = SquashedGaussianActor(observation_size, config.sac_hidden_size,
                                               config.hidden_layers)
            self.critic = self._make_critic()
        self.target_critic = self._make_critic()
        self.target_critic.load_state_dict(self.critic.state_dict())
        self.target_critic.requires_grad_(False)
        self.log_temperature = torch.tensor([math.log(config.sac_initial_temperature)],
                                            requires_grad=True)
        self.target_entropy = -float(ACTION_SIZE)
        rate = config.sac_learning_rate
        self.actor_optimizer = torch.optim.Adam(self.actor.parameters(), lr=rate)
        self.critic_optimizer = torch.optim.Adam(self.critic.parameters(), lr=rate)
        self.temperature_optimizer = torch.optim.Adam([self.log_temperature], lr=rate)
        self.replay = ReplayBuffer(observation_size, config.sac_replay_size)
        self.updates = 0             # update() calls that learned (reports)
        self.gradient_steps = 0      # critic gradient steps in total
        self.pending_updates = 0     # stored transitions whose gradient steps are owed
        self._since_report = _Totals()
        # Held by every use of the networks, the optimizers and the replay buffer: a learner
        # thread (sac_background) takes it per gradient step, the control thread to act.
        self.lock = threading.RLock()
        # Held while one owed transition is learned, by the thread or update(): update() waits
        # on it so that no claimed transition is still being learned when it reports.
        self._transition = threading.Lock()
        self.background = None       # a BackgroundSACLearning while realtime episodes run

    def _make_critic(self) -> CriticEnsemble:
        config = self.config
        return CriticEnsemble(self.observation_size, config.sac_hidden_size,
                              config.hidden_layers, config.sac_critics, config.sac_dropout,
                              self.update_generator)

    @property
    def update_schedule(self) -> str:
        """Return when gradient steps run: 'step' (as transitions arrive) or 'episode_end'."""
        return self.config.sac_update_at

    @property
    def ready(self) -> bool:
        """Return True once the replay buffer holds enough transitions to learn from."""
        return len(self.replay) >= max(self.config.sac_learning_starts, 1)

    @torch.no_grad()
    def act(self, observation, deterministic: bool = False) -> tuple:
        """Return (raw action, squashed action, log_prob, Q) for one observation.

        Q is the ensemble's mean estimate (dropout off) of the action taken, for the records.
        """
        with self.lock:
            return self._act(observation, deterministic)

    def _act(self, observation, deterministic: bool) -> tuple:
        obs = torch.as_tensor(np.asarray(observation, dtype=np.float32)).unsqueeze(0)
        mean, log_std = self.actor.mean_and_log_std(obs)
        if deterministic:
            raw = mean
        else:
            raw = mean + log_std.exp() * torch.randn(mean.shape, generator=self.action_generator)
        action = torch.tanh(raw)
        log_prob = squashed_log_prob(raw, mean, log_std)
        self.critic.eval()
        value = self.critic(obs, action).mean(0)
        self.critic.train()
        return float(raw[0, 0]), float(action[0, 0]), float(log_prob[0]), float(value[0])

    def observe(self, observation, action: float, reward: float, next_observation,
                terminated: bool) -> None:
        """Store one transition; under the ``step`` schedule learn from it at once.

        ``reward``: the task's reward of the transition, stored times ``sac_reward_scale`` (a
        fixed factor: a running normalization, as PPO's, would leave transitions of different
        scales side by side in the replay buffer).
        """
        with self.lock:
            self.replay.add(observation, action, reward * self.config.sac_reward_scale,
                            next_observation, terminated)
            if self.ready:   # transitions stored before learning starts owe no gradient steps
                self.pending_updates += 1
        if self.update_schedule != 'step':
            return
        if self.background is not None:
            self.background.wake()       # the learner thread takes the owed steps
        else:
            self._learn_pending()

    @property
    def update_due(self) -> bool:
        """Return True when :meth:`update` has something to do or to report.

        Owed gradient steps (``episode_end``) or steps taken since the last report (``step``):
        AgentCore then enters its ``updating`` phase, and (``judging_interval: 0``) judges the
        policy that learned.
        """
        return self.ready and (self.pending_updates > 0 or self._since_report.steps > 0)

    def update(self) -> dict:
        """Run the owed gradient steps; return statistics of the learning since the last call."""
        start = time.perf_counter()
        self._learn_pending()
        totals, self._since_report = self._since_report, _Totals()
        self.updates += 1
        steps = max(totals.steps, 1)
        return {'policy_loss': totals.actor_loss / max(totals.actor_steps, 1),
                'value_loss': totals.critic_loss / steps,
                'entropy': totals.entropy / max(totals.actor_steps, 1),
                'approx_kl': float('nan'),         # no trust region in SAC
                'clip_fraction': float('nan'),
                'temperature': float(self.log_temperature.detach().exp()[0]),
                'action_std': totals.action_std / max(totals.actor_steps, 1),
                'gradient_steps': totals.steps, 'minibatches': totals.steps,
                'samples': len(self.replay),
                'seconds': totals.seconds + (time.perf_counter() - start),
                'update': self.updates}

    def clear_replay(self) -> None:
        """Forget every stored transition (a new reward makes them wrong) and owed steps."""
        with self.lock:
            self.replay.clear()
            self.pending_updates = 0

    def set_background(self, on: bool, niceness: int = 0, switch_interval: float = 0.0):
        """Take the owed steps of the ``step`` schedule in a learner thread (``on``) or not.

        Between episodes only (the agent node: realtime episodes in the background). Turned
        off, the thread stops after its current step; the steps it still owed run in the next
        :meth:`update`.
        """
        if on and self.background is None and self.update_schedule == 'step':
            self.background = BackgroundSACLearning(self, niceness, switch_interval)
        elif not on and self.background is not None:
            self.background, running = None, self.background
            running.stop()

    # ------------------------------------------------------------------ learning

    def _learn_pending(self) -> None:
        """Take the owed gradient steps (all of them), the learner thread's in flight included."""
        while self.learn_one_owed():
            pass
        with self._transition:     # a transition the learner thread claimed is learned now
            pass

    def learn_one_owed(self) -> bool:
        """Per owed transition: ``sac_updates_per_step`` critic steps, then one actor step.

        Claims one owed transition and learns from it, holding :attr:`lock` one gradient step
        at a time (so an ``act`` waits at most one step); returns False when none was owed.
        """
        with self._transition:
            with self.lock:
                if not self.ready or self.pending_updates == 0:
                    return False
                self.pending_updates -= 1
            start = time.perf_counter()
            for _ in range(self.config.sac_updates_per_step):
                with self.lock:
                    self._critic_step(self.replay.sample(self.config.sac_batch_size,
                                                         self.update_generator))
            with self.lock:
                self._actor_step(self.replay.sample(self.config.sac_batch_size,
                                                    self.update_generator)['observations'])
                self._since_report.seconds += time.perf_counter() - start
        return True

    def _critic_step(self, batch: dict) -> None:
        config = self.config
        temperature = self.log_temperature.detach().exp()
        with torch.no_grad():
            _, next_actions, next_log_prob = self.actor.sample(batch['next_observations'],
                                                               self.update_generator)
            next_q = self.target_critic(batch['next_observations'], next_actions).min(0).values
            soft_value = next_q - temperature * next_log_prob
            target = batch['rewards'] + config.sac_gamma * (1.0 - batch['terminated']) \
                * soft_value
        q = self.critic(batch['observations'], batch['actions'])
        loss = 0.5 * ((q - target.unsqueeze(0)) ** 2).mean(1).sum()   # summed over members
        self.critic_optimizer.zero_grad()
        loss.backward()
        self.critic_optimizer.step()
        with torch.no_grad():
            for target_parameter, parameter in zip(self.target_critic.parameters(),
                                                   self.critic.parameters()):
                target_parameter.lerp_(parameter, config.sac_tau)
        self.gradient_steps += 1
        self._since_report.steps += 1
        self._since_report.critic_loss += float(loss.detach()) / self.critic.members

    def _actor_step(self, observations: torch.Tensor) -> None:
        temperature = self.log_temperature.detach().exp()
        _, actions, log_prob = self.actor.sample(observations, self.update_generator)
        # The critics judge the policy's actions (mean over the ensemble, as DroQ); their own
        # parameters get no gradient here (only the actor's optimizer steps).
        q = self.critic(observations, actions).mean(0)
        actor_loss = (temperature * log_prob - q).mean()
        self.actor_optimizer.zero_grad()
        actor_loss.backward()
        self.actor_optimizer.step()
        temperature_loss = -(self.log_temperature
                             * (log_prob.detach() + self.target_entropy)).mean()
        self.temperature_optimizer.zero_grad()
        temperature_loss.backward()
        self.temperature_optimizer.step()
        totals = self._since_report
        totals.actor_steps += 1
        totals.actor_loss += float(actor_loss.detach())
        totals.entropy += float(-log_prob.detach().mean())
        with torch.no_grad():
            totals.action_std += float(self.actor.mean_and_log_std(observations)[1].exp().mean())

    # ------------------------------------------------------------------ checkpoints

    def state_dict(self) -> dict:
        """Return networks, optimizers, generators and the replay buffer (for checkpoints)."""
        with self.lock:
            return self._state_dict()

    def _state_dict(self) -> dict:
        return {'actor': self.actor.state_dict(), 'critic': self.critic.state_dict(),
                'target_critic': self.target_critic.state_dict(),
                'log_temperature': self.log_temperature.detach().clone(),
                'actor_optimizer': self.actor_optimizer.state_dict(),
                'critic_optimizer': self.critic_optimizer.state_dict(),
                'temperature_optimizer': self.temperature_optimizer.state_dict(),
                'action_generator': self.action_generator.get_state(),
                'update_generator': self.update_generator.get_state(),
                'updates': self.updates, 'gradient_steps': self.gradient_steps,
                'pending_updates': self.pending_updates,
                'replay': self.replay.state_dict()}

    def load_state_dict(self, state: dict, policy_only: bool = False) -> None:
        """Restore a state saved by :meth:`state_dict` (``policy_only``: networks alone)."""
        self.actor.load_state_dict(state['actor'])
        self.critic.load_state_dict(state['critic'])
        self.target_critic.load_state_dict(state['target_critic'])
        with torch.no_grad():
            self.log_temperature.copy_(state['log_temperature'])
        self.updates = int(state['updates'])
        self.gradient_steps = int(state['gradient_steps'])
        if policy_only:
            return
        self.actor_optimizer.load_state_dict(state['actor_optimizer'])
        self.critic_optimizer.load_state_dict(state['critic_optimizer'])
        self.temperature_optimizer.load_state_dict(state['temperature_optimizer'])
        self.action_generator.set_state(state['action_generator'])
        self.update_generator.set_state(state['update_generator'])
        self.pending_updates = int(state['pending_updates'])
        self.replay.load_state_dict(state['replay'])


class _Totals:
    """Sums over the gradient steps since the last :meth:`SAC.update` report."""

    def __init__(self):
        self.steps = 0
        self.actor_steps = 0
        self.critic_loss = 0.0
        self.actor_loss = 0.0
        self.entropy = 0.0
        self.action_std = 0.0
        self.seconds = 0.0
