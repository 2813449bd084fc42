"""Train this project's PPO and Stable-Baselines3's PPO on the same environment. Pure.

Both learners get the same :class:`~hrc_gym.env.SliderPendulumBallEnv` (same setting, same seed,
so the same sequence of episode starts and the same simulated human) and the paper's Table I
settings; each returns one record per training episode: the episode's return (the raw reward of
the training step, not the scaled one a learner may train on) and its mean subtask errors.

* ours: ``hrc_agent_node.agent_core.AgentCore`` (the agent node's core) driven through the
  environment: ``act`` on the environment's physics state, ``end_episode`` and ``update`` as the
  offline loop calls them. ``AgentCore`` computes its reward itself from the same state; every
  episode checks that it equals the environment's return (they share ``TaskTree.reward``).
* SB3: ``stable_baselines3.PPO`` with Table I, the same network shape (two tanh layers of 64,
  separate policy and value networks, state-independent log std starting at -0.5) and the same
  reward scaling (``VecNormalize``: divide by the running std of the discounted return, no
  observation normalization, no clipping).

Differences that remain (by design of each library, see docs/gym.md): SB3 updates every 512
steps mid-episode (bootstrapping the cut), ours at the first episode end with at least 512
samples (every 3 episodes = 600 samples); SB3's value loss is MSE, ours 0.5 * MSE (both with
weight 0.5).
"""

import math

from hrc_agent_node.agent_core import AgentCore
from hrc_agent_node.strategies import StrategyProgress
from hrc_common.params import with_overrides
import numpy as np
import torch

from hrc_gym.env import SliderPendulumBallEnv

# The two settings of the cross-check: case 2's first training step (the robot alone, reward
# f(S_x) + f(P_z), judged on the pendulum, which its rotation drives) and the whole task with
# the simulated human (case 6: the robot rotates, the human translates, reward on all three
# subtasks; the same roles and reward as case 2's second step).
SETTINGS = {
    'alone': {'case': 2, 'training_step': 0, 'human': 'none'},
    'whole': {'case': 6, 'training_step': 0, 'human': 'paper'},
}
COMMON = {'preset': 'tuned', 'observe_rates': True}
CRITERION_WINDOW = 3


def make_env(setting: str, **overrides) -> SliderPendulumBallEnv:
    """Return the environment of a named setting (tuned reward, observation with rates)."""
    return SliderPendulumBallEnv(**dict(COMMON, **SETTINGS[setting], **overrides))


def agent_params(env: SliderPendulumBallEnv, seed: int, episodes: int, **changes):
    """Return the AgentParams of our PPO for ``env``'s task (Table I, no step advance).

    ``changes``: other AgentParams values (e.g. ``horizon``), for experiments.
    """
    overrides = dict(seed=seed, max_training_episodes=episodes, evaluation_episodes=0,
                     checkpoint_dir='', torch_threads=1,
                     # Stay in the environment's training step: the criterion is judged
                     # afterwards, on the training episodes, for both learners alike.
                     convergence_window=1000, satisfied_window=1000,
                     # no judging episodes within the budget (one after every 10^5 training
                     # episodes): both learners spend every episode on training
                     judging_interval=100000)
    return with_overrides(env.task.agent_params, **dict(overrides, **changes))


def sb3_ppo_kwargs(params) -> dict:
    """Return stable_baselines3.PPO keyword arguments equal to our PPO's ``params``."""
    return dict(n_steps=params.horizon, batch_size=params.minibatch_size,
                n_epochs=params.epochs, learning_rate=params.learning_rate,
                gamma=params.gamma, gae_lambda=params.gae_lambda, clip_range=params.clip_coef,
                ent_coef=params.entropy_coef, vf_coef=params.value_coef,
                max_grad_norm=params.max_grad_norm,
                normalize_advantage=params.normalize_advantages,
                policy_kwargs=dict(net_arch=dict(pi=[params.hidden_size] * params.hidden_layers,
                                                 vf=[params.hidden_size] * params.hidden_layers),
                                   activation_fn=torch.nn.Tanh,
                                   log_std_init=params.initial_log_std, ortho_init=True))


def _record(info) -> dict:
    return {'return': float(info['episode_return']), 'errors': dict(info['episode_errors'])}


def train_ours(setting: str, seed: int, episodes: int, **changes) -> list:
    """Train AgentCore for ``episodes`` episodes on the setting's environment; return records.

    ``changes``: AgentParams values other than Table I's (experiments only).
    """
    env = make_env(setting)
    try:
        core = AgentCore(agent_params(env, seed, episodes, **changes), tree=env.task.tree,
                         cases={env.task.case.case_id: env.task.case}, limits=env.task.limits)
        records = []
        env.reset(seed=seed)
        for episode in range(episodes):
            core.start_episode()  # its reset seed is unused: the environment draws starts
            if episode:
                env.reset()
            info = {}
            while not env.task.finished:
                decision = core.act(env.state)
                _, _, _, _, info = env.step(np.array([decision.action], dtype=np.float32))
            result = core.end_episode(env.state)
            if not math.isclose(result.episode_return, info['episode_return'],
                                rel_tol=1e-9, abs_tol=1e-9):
                raise AssertionError(f'AgentCore return {result.episode_return} differs from '
                                     f"the environment's {info['episode_return']}")
            records.append(_record(info))
            if core.phase == 'updating':
                core.update()
        return records
    finally:
        env.close()


def train_sb3(setting: str, seed: int, episodes: int, env=None) -> tuple:
    """Train SB3's PPO for ``episodes`` episodes; return (records, model)."""
    # stable_baselines3: an optional dependency (the cross-check only), about 2 s to import
    from stable_baselines3 import PPO  # lazy: stable_baselines3 (optional, 2 s)
    from stable_baselines3.common.callbacks import BaseCallback  # lazy: as above
    from stable_baselines3.common.logger import Logger  # lazy: as above
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize  # lazy: as above

    torch.set_num_threads(1)
    env = env if env is not None else make_env(setting)
    params = agent_params(env, seed, episodes)
    records = []

    class EpisodeRecorder(BaseCallback):
        def _on_step(self) -> bool:
            for info in self.locals['infos']:
                if 'episode_return' in info and len(records) < episodes:
                    records.append(_record(info))
            return len(records) < episodes

    vec_env = VecNormalize(DummyVecEnv([lambda: env]), norm_obs=False, norm_reward=True,
                           gamma=params.gamma, clip_reward=math.inf)
    model = PPO('MlpPolicy', vec_env, seed=seed, device='cpu', verbose=0,
                **sb3_ppo_kwargs(params))
    # SB3's default logger makes an empty SB3-<date> folder in /tmp at every learn()
    model.set_logger(Logger(folder=None, output_formats=[]))
    model.learn(total_timesteps=episodes * env.task.steps_per_episode,
                callback=EpisodeRecorder())
    return records, model


def run_policy(env, policy, episodes: int, seed: int) -> list:
    """Run ``policy(observation) -> action`` for ``episodes`` episodes; return the returns."""
    returns = []
    observation, _ = env.reset(seed=seed)
    for episode in range(episodes):
        if episode:
            observation, _ = env.reset()
        total, done = 0.0, False
        while not done:
            observation, reward, terminated, truncated, _ = env.step(policy(observation))
            total += reward
            done = terminated or truncated
        returns.append(total)
    return returns


def random_returns(setting: str, seed: int, episodes: int) -> list:
    """Return the episode returns of a uniformly random policy (seeded)."""
    env = make_env(setting)
    env.action_space.seed(seed)
    try:
        return run_policy(env, lambda observation: env.action_space.sample(), episodes, seed)
    finally:
        env.close()


def episodes_to_criterion(env, records, window: int = CRITERION_WINDOW):
    """Return the training episodes until the step's criterion held (None if it never did).

    The strategies' own judge (``StrategyProgress``): every subtask the training step watches
    within its tolerance in each of ``window`` consecutive episodes.
    """
    task = env.task
    progress = StrategyProgress(task.case, task.tree, window, window)
    progress.step_index = task.step_spec.index
    for count, record in enumerate(records, start=1):
        met, _ = progress.record(record['errors'])
        if met:
            return count
    return None
