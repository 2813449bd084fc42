"""The task as a PettingZoo parallel environment: the robot and the human are both agents.

For work where both sides learn (no simulated human inside). ``hrc_gym.parallel_env(case=6)``.

* Agents ``robot`` and ``human``; each drives the degree of freedom the case gives it (cases
  1, 3, 5: robot translation, human rotation; 2, 4, 6 swapped). Action ``Box(-1, 1, (1,))``.
* Observation of each agent: {B_y, P_z, S_x, a_partner} (+ rates), the same function as the
  robot's (``observation_of``), with the partner's command applied in the last period.
* Rewards on the state reached: the robot's is the training step's reward (its subtasks, the
  number ``AgentCore`` records); the human's is the same hierarchical reward over the subtasks
  the step asks the human to hold (``human_subtasks`` of params/cases.yaml).
* The training step must involve the human (default: the case's last step).
* Episodes are truncated at 200 steps (both agents), never terminated; ``infos`` of the last
  step carry ``episode_errors``.
* ``reset(seed=s)`` seeds the episode-start generator; later resets go on with it.
* ``render_mode='rgb_array'`` as the Gymnasium environment.
"""

import functools

from gymnasium import spaces
import numpy as np
from pettingzoo import ParallelEnv

from hrc_common.params import from_dict, ParameterError
from hrc_engine.loop import PartnerSide
from hrc_gym.task import (check_render_mode, HUMAN, RENDER_MODES, ROBOT, SEED_LIMIT,
                          TaskParams, TaskRun)



class SliderPendulumBallParallelEnv(ParallelEnv):
    """Both actors of the task as PettingZoo agents (see the module docstring)."""

    metadata = {'name': 'hrc_slider_pendulum_ball_v0', 'render_modes': RENDER_MODES,
                'render_fps': 5, 'is_parallelizable': True}

    def __init__(self, render_mode=None, physics_params=None, **params):
        check_render_mode(render_mode)
        params.setdefault('training_step', -1)
        self.config = from_dict(TaskParams, params)
        self.task = TaskRun(self.config, physics_params)
        if not self.task.human_involved:
            self.task.close()
            raise ParameterError(f'training_step {self.config.training_step} of case '
                                 f'{self.config.case} does not involve the human: both agents '
                                 f'need a step in which both act')
        # the human agent's command of the step, held over the period's slices
        self._human_command = 0.0
        self.task.set_human(PartnerSide(lambda state, subtasks: self._human_command,
                                        self.task.limits, detail='human agent'))
        self.render_mode = render_mode
        self.possible_agents = [ROBOT, HUMAN]
        self.agents = []
        self._np_random = None
        self._observation_space = spaces.Box(-10.0, 10.0, (self.task.observation_size,),
                                             np.float32)
        self._action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent):
        """Return the observation space of ``agent`` (the same for both)."""
        return self._observation_space

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent):
        """Return the action space of ``agent`` (the same for both)."""
        return self._action_space

    def reset(self, seed=None, options=None):
        """Start an episode; return (observations, infos) of both agents."""
        if seed is not None or self._np_random is None:
            self._np_random = np.random.default_rng(seed)
        self.agents = list(self.possible_agents)
        self.task.reset(int(self._np_random.integers(SEED_LIMIT)))
        observations = {agent: self.task.observation(agent) for agent in self.agents}
        return observations, {agent: {'dof': self.task.dofs[agent]} for agent in self.agents}

    def step(self, actions):
        """Apply both agents' commands for one control period (a missing one counts as 0)."""
        if not self.agents:
            raise RuntimeError('the episode is over: call reset()')
        commands = {agent: float(np.clip(np.asarray(actions.get(agent, 0.0),
                                                    dtype=np.float64).reshape(-1)[0], -1.0, 1.0))
                    for agent in self.agents}
        self._human_command = commands.get(HUMAN, 0.0)
        self.task.advance(commands.get(ROBOT, 0.0))
        state = self.task.state
        observations, rewards, terminations, truncations, infos = {}, {}, {}, {}, {}
        for agent in self.agents:
            components, reward = self.task.reward(agent)
            observations[agent] = self.task.observation(agent)
            rewards[agent] = float(reward)
            terminations[agent] = bool(state.terminated)
            truncations[agent] = bool(state.truncated)
            infos[agent] = {'step': state.step, 'reward_components': components,
                            'action': commands[agent]}
        if self.task.finished:
            errors = self.task.episode_errors()
            for agent in self.agents:
                infos[agent]['episode_errors'] = errors
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def render(self):
        """Return an RGB image of the system (``render_mode='rgb_array'``), else None."""
        return self.task.render(self.render_mode)

    def close(self):
        """Release the physics client."""
        self.task.close()
