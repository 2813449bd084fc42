"""The task as a Gymnasium environment for the robot's degree of freedom, the human inside.

``gymnasium.make('hrc/SliderPendulumBall-v0', case=2, training_step=0)`` (registered when
``hrc_gym`` is imported) or :class:`SliderPendulumBallEnv` directly.

* **Action**: ``Box(-1, 1, (1,))``, the robot's normalized command on its degree of freedom
  (case 1, 3, 5: translation, 1 = ``max_force`` 2 N; case 2, 4, 6: rotation, 1 = ``max_torque``
  0.5 N*m); values outside are clamped by the physics.
* **Observation**: the paper's {B_y, P_z, S_x, a_h} divided by the agent's scales (0.25 m,
  0.5 rad, 0.1 m; a_h in [-1, 1]), plus dB_y/dt, dP_z/dt, dS_x/dt (0.5 m/s, 1 rad/s, 0.2 m/s)
  with ``observe_rates=True``; clipped to [-10, 10]; float32. a_h is the human's command the
  physics applied in the last control period (0 when the step does not involve the human).
* **Reward**: the case's training step's hierarchical reward on the state reached (eq. 2-5 of
  the paper, ``TaskTree.reward``), the same number ``AgentCore`` records; ``info`` carries its
  components. Case 2 step 0: f(S_x) + f(P_z), the robot alone; ``training_step=-1`` the last
  step (human involved, all three subtasks).
* **Episode**: 200 control steps of 0.2 s (40 s). ``terminated`` is always False (the end stops
  keep every body on the model, no state is terminal); ``truncated`` is True on step 200 (the
  time limit, so a learner must bootstrap from the final state). The final ``info`` holds
  ``episode_errors`` (mean |x - mu| per subtask) and ``episode_satisfied`` (within tolerance).
* **The human**: when the step involves it, the simulated human of ``hrc_joystick_node``
  (``human=<profile>`` or ``population:<profile>``) or a cloned model (``model:<path>``),
  answered through the human node's own
  per-step core (``HumanCore``, with the sim's stamps as its clock), acts on the same state as
  the robot; or any object passed as ``human_model`` with ``act(state, subtasks) -> float``
  (and optionally ``reset(episode)``), e.g. a model cloned from a person's bags.
* **Seeding**: ``reset(seed=s)`` seeds the episode-start generator (``self.np_random``) and a
  fresh simulated human (seed derived from s, no practice yet); later ``reset()`` calls go on
  with both (the human practices across episodes, as in the project's sessions).
* **A session**: ``session=SessionSettings(case=2, seed=0, human_profile='novice',
  overrides={'sim.max_torque': 0.8})`` (the configuration ``hrc session`` and the engines take)
  gives the case, the human's profile, the physics (``params/sim.yaml`` with the ``sim.*``
  overrides) and the seed of the first ``reset()`` (``hrc_gym.session``).
* **Rendering**: ``render_mode='rgb_array'``: a 240 x 320 RGB image from PyBullet's tiny
  renderer (no display needed).
"""

import gymnasium
from gymnasium import spaces
import numpy as np

from hrc_common.params import from_dict
from hrc_common.session_plan import SessionSettings
from hrc_engine.loop import PartnerSide
from hrc_joystick_node.human_model import load_human_model
from hrc_joystick_node.human_profile import load_profile
from hrc_gym.task import (check_render_mode, GymParams, HUMAN, make_human, MODEL_PREFIX,
                          NO_HUMAN, POPULATION_PREFIX, RENDER_MODES, ROBOT, SEED_LIMIT, TaskRun)
from hrc_gym.session import session_keywords
from hrc_sim_node.physics import PhysicsParams



class _ModelPartner:
    """A human model object (``act(state, subtasks)``, maybe ``reset(episode)``): a partner."""

    def __init__(self, model):
        self.model = model

    def start_episode(self, episode: int) -> None:
        if hasattr(self.model, 'reset'):
            self.model.reset(episode)

    def __call__(self, state, subtasks) -> float:
        return float(self.model.act(state, list(subtasks)))


def derived_seed(seed: int, stream: int) -> int:
    """Return a 31-bit seed for one stream (``stream``) of a run seeded with ``seed``."""
    return int(np.random.SeedSequence([int(seed), int(stream)]).generate_state(1)[0]
               & SEED_LIMIT)


def check_human_spec(spec: str) -> None:
    """Raise ParameterError unless ``spec`` is 'none', a profile, a population or a model."""
    if spec == NO_HUMAN:
        return
    if spec.startswith(MODEL_PREFIX):
        load_human_model(spec[len(MODEL_PREFIX):])
        return
    load_profile(spec[len(POPULATION_PREFIX):] if spec.startswith(POPULATION_PREFIX) else spec)


class SliderPendulumBallEnv(gymnasium.Env):
    """The robot's side of the task; the human is part of the environment (module docstring)."""

    metadata = {'render_modes': RENDER_MODES, 'render_fps': 5}

    def __init__(self, render_mode=None, human_model=None, physics_params: PhysicsParams = None,
                 session: SessionSettings = None, **params):
        check_render_mode(render_mode)
        # The session-level settings (case, seed, profile, sim overrides) from the one session
        # configuration when given (hrc_gym.session), else the keywords as documented.
        self.session = session
        if session is not None:
            params, physics_params = session_keywords(session, params, physics_params)
        self.config = from_dict(GymParams, params)
        check_human_spec(self.config.human)
        self.render_mode = render_mode
        self.task = TaskRun(self.config, physics_params)
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.observation_space = spaces.Box(-10.0, 10.0, (self.task.observation_size,),
                                            np.float32)
        self._human_model = human_model
        self.human = None         # the human side of the loop (hrc_engine.loop)
        self._human_ready = False
        self._episode = 0
        self._return = 0.0

    @property
    def state(self):
        """Return the physics state of the current step (``PhysicsState``)."""
        return self.task.state

    def reset(self, *, seed=None, options=None):
        """Start an episode (see the module docstring for seeding); return (obs, info)."""
        if seed is None and not self._human_ready and self.session is not None:
            seed = self.session.seed   # the session's seed seeds its first episode
        super().reset(seed=seed)
        if seed is not None or not self._human_ready:
            # A new person (no practice yet) and a new session clock for every seeded run.
            self._episode = 0
            self._human_ready = True
            task = self.task
            if self._human_model is not None:
                # a model object acts once a control period, the rate it was recorded at
                self.human = PartnerSide(_ModelPartner(self._human_model), task.limits,
                                         hold_over_slices=True, detail='human model')
            else:
                human_seed = derived_seed(seed if seed is not None
                                          else int(self.np_random.integers(SEED_LIMIT)), 1)
                self.human = make_human(self.config.human, task.dofs[HUMAN], human_seed,
                                        task.limits, task.human_involved,
                                        task.subtasks[HUMAN])
            task.set_human(self.human)
        else:
            self._episode += 1
        self._return = 0.0
        self.task.reset(int(self.np_random.integers(SEED_LIMIT)), self._episode)
        return self.task.observation(ROBOT), {'step': 0}

    def step(self, action):
        """Advance one control period with the robot's command (the human acts alongside)."""
        if self.task.state is None:
            raise RuntimeError('call reset() before step()')
        if self.task.finished:
            raise RuntimeError('the episode is over: call reset()')
        command = float(np.clip(np.asarray(action, dtype=np.float64).reshape(-1)[0], -1.0, 1.0))
        human_command = self.task.advance(command)
        components, reward = self.task.reward(ROBOT)
        self._return += reward
        state = self.task.state
        info = {'step': state.step, 'robot_action': command, 'human_action': human_command,
                'reward_components': components}
        if self.task.finished:
            errors = self.task.episode_errors()
            info.update(episode_errors=errors, episode_return=self._return,
                        episode_satisfied=self.task.progress.satisfied(errors))
        return (self.task.observation(ROBOT), float(reward), bool(state.terminated),
                bool(state.truncated), info)

    def render(self):
        """Return an RGB image of the system (``render_mode='rgb_array'``), else None."""
        return self.task.render(self.render_mode)

    def close(self):
        """Release the physics client."""
        self.task.close()
