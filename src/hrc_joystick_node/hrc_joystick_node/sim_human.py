"""A simulated human at a joystick: perception, delay, control, motor noise, learning, fatigue.

Pure Python and numpy (no rclpy): the human node, the experiment runner and the benchmarks all
use :class:`SimulatedHuman` in the same way::

    human = SimulatedHuman(load_profile('skilled'), dof='rotation', seed=3)
    human.reset(episode=0)
    command = human.act(state, ['pendulum'])   # float in [-1, 1] for every control step

``state`` is anything with the attributes of ``hrc_sim_node.physics.PhysicsState`` (``step``,
``slider_position``, ``slider_velocity``, ``pendulum_angle``, ``pendulum_angular_velocity``,
``ball_position``, ``ball_velocity``); ``subtasks`` are the ids the session assigns to the
human: ``slider`` (keep S_x at 0), ``pendulum`` (keep P_z at 0), ``ball`` (keep B_y at 0).

The model, step by step (one call of :meth:`SimulatedHuman.act` per control period T)
------------------------------------------------------------------------------------------
1. **Perception.** The person sees the slider height, the beam angle and the ball position on a
   monitor. Each percept is the true value plus a per-episode misjudgement of the zero (a bias,
   drawn at reset: "where is the middle", "what is horizontal") plus a fresh noise sample per
   step. Velocities are perceived with a relative (Weber) error plus a floor. The noise and the
   bias are per watched quantity, and the beam angle is perceived worse than the slider height:
   the paper (Sec. V.B) reports that its subjects judged translation better than rotation and
   "struggled to identify if the pendulum was in the horizontal direction".
2. **Reaction delay.** The person acts on what they perceived ``reaction_delay`` s ago (a
   buffer of percepts, linearly interpolated between control steps). A ``prediction`` share of
   the delay is compensated by extrapolating with the perceived velocity, as trained operators
   do (the crossover model's lead equalization).
3. **Control.** A proportional-derivative law on the person's own degree of freedom, written in
   the terms a person would use: the error (``*_full_scale``) at which they push the stick all
   the way, and how far ahead (``lead_time``) they look; a practiced person also pushes harder
   against a steady load (an integral term, ``integral_time``), e.g. the ball resting at an
   end stop and weighing the beam down. Both plants are velocity-like (heavy damping), so the
   gains follow the crossover model: a crossover of about 2 rad/s, which the 0.2 s period and
   the delay still leave stable; a novice's higher gain on the beam overshoots.
   Holding the ball (subtask ``ball``) is a cascade: the ball's offset sets a target beam
   angle (``ball_tilt``, ``ball_lead``, at most ``max_tilt``; the ball rolls toward the low
   end, so a ball east of the middle asks for the east end up), which the rotation actor
   tracks directly. The translation actor has no direct hold on the ball: it can only nudge
   the beam through the coupling of the physics (speeding the slider up presses the east end
   down, by about m_p * d / c_p = 0.25 rad per m/s of slider speed change with the default
   physics), so it adds ``(P_z - target) / coupling_full_scale`` to its slider command: a
   weak, real authority, as the paper's asymmetric task intends. Subtasks of the other degree
   of freedom are out of the person's reach and ignored (with nothing in reach the intent is
   0 and only the motor noise floor moves the stick).
4. **Motor execution.** Limited bandwidth: the stick moves at most ``max_rate`` per second and
   follows the intent with a first-order neuromuscular lag (``neuromuscular_time``). Motor
   noise is signal-dependent (standard deviation ``motor_noise * |command|`` plus a floor
   ``motor_noise_floor``). With probability ``lapse_probability`` per step attention lapses and
   the stick is held where it was.
5. **Learning curve.** Noise, biases, motor noise and lapses start ``untrained_factor`` times
   larger and fall exponentially with the episodes the person has practiced (involved in at
   least one step), time constant ``learning_episodes``; the lead time and the prediction grow
   correspondingly from a fraction to their trained values.
6. **Fatigue.** Time on task (the steps acted so far in the session) raises the motor noise,
   the lapse rate and the delay by ``fatigue_per_minute`` per minute (a vigilance decrement).

Determinism: every random draw comes from a numpy Generator seeded with ``(seed, episode)`` at
each :meth:`SimulatedHuman.reset`, so an episode reproduces from the seed, the episode index,
the practice and time on task so far (``practiced_episodes``, ``steps_on_task``) and the
sequence of states.

Facts the numbers rest on (documented defaults in ``params/sim_human.yaml``)
--------------------------------------------------------------------------
* Visual reaction time to a display ~0.2-0.3 s; the effective delay of a human operator in
  compensatory tracking 0.1-0.3 s (McRuer & Jex 1967, crossover model; Welford 1980).
* Bisecting a line (finding "the middle") is precise to ~1-3 % of its length with a small
  constant bias (Jewell & McCourt 2000, pseudoneglect): on the 0.2 m rod, a few mm.
* Orientation judgments are best near horizontal/vertical (~1-2 degrees, Appelle 1972, the
  oblique effect) in ideal conditions; judging a moving beam on a monitor is worse, and the
  paper's subjects found the rotation hard: several degrees here.
* Velocity discrimination has a Weber fraction of ~0.1-0.2 (McKee 1981).
* Motor noise grows with the command (signal-dependent noise, Harris & Wolpert 1998; Schmidt
  et al. 1979); a person moves a joystick through its range in ~0.2-0.4 s (bandwidth).
* Practice improves performance roughly exponentially for an individual (Heathcote, Brown &
  Mewhort 2000); vigilance and performance decline with time on task (Mackworth 1948); the
  paper kept episodes to 40 s for that reason.
"""

from dataclasses import dataclass, fields
import math
import pathlib
import typing

import numpy
import yaml

from hrc_common.dof import check_dof, ROTATION, TRANSLATION
from hrc_common.params import from_dict, param, ParameterError

SLIDER = 'slider'
PENDULUM = 'pendulum'
BALL = 'ball'
SUBTASKS = (SLIDER, PENDULUM, BALL)
# The level-2 subtask each degree of freedom drives directly.
OWN_SUBTASK = {TRANSLATION: SLIDER, ROTATION: PENDULUM}
# Aliases by the paper's notation T_i^j written T<level>_<index> (SessionStatus comments).
SUBTASK_ALIASES = {'T2_1': SLIDER, 'T2_2': PENDULUM, 'T1_1': BALL}
# Time over which a person integrates motion to judge a speed (s): the velocity noise floor is
# the position noise per this time.
MOTION_INTEGRATION_TIME = 0.5
# Percepts kept for the delay line (control steps): 64 * 0.2 s, far beyond any reaction delay.
HISTORY_LENGTH = 64


@dataclass
class HumanProfile:
    """The parameters of one simulated person (see the module docstring for the model).

    The defaults are the ``skilled`` profile of ``params/sim_human.yaml`` (a test keeps them
    equal); a profile in the YAML file may leave out the fields it does not change.
    """

    description: str = param('', 'who this profile models')
    # perception
    slider_noise: float = param(0.0015, 'std of the perceived slider height, per step (m)',
                                low=0.0, high=0.1)
    pendulum_noise: float = param(0.02, 'std of the perceived beam angle, per step (rad)',
                                  low=0.0, high=1.0)
    ball_noise: float = param(0.004, 'std of the perceived ball position, per step (m)',
                              low=0.0, high=0.25)
    slider_bias: float = param(0.0015, 'std of the per-episode misjudged middle of the rod (m)',
                               low=0.0, high=0.1)
    pendulum_bias: float = param(0.015, 'std of the per-episode misjudged horizontal (rad)',
                                 low=0.0, high=1.0)
    ball_bias: float = param(0.003, 'std of the per-episode misjudged middle of the beam (m)',
                             low=0.0, high=0.25)
    velocity_noise: float = param(0.12, 'Weber fraction of perceived speeds (relative std)',
                                  low=0.0, high=2.0)
    # timing
    reaction_delay: float = param(0.22, 'delay from seeing to acting (s)', low=0.0, high=2.0)
    prediction: float = param(0.5, 'share of the delay compensated by extrapolation',
                              low=0.0, high=1.0)
    # control
    slider_full_scale: float = param(0.1, 'slider error at which the stick is pushed fully (m)',
                                     low=1e-4, high=1.0)
    pendulum_full_scale: float = param(0.5, 'beam angle error at which the stick is pushed '
                                       'fully (rad)', low=1e-3, high=10.0)
    lead_time: float = param(0.1, 'look-ahead of the derivative action (s)', low=0.0, high=5.0)
    integral_time: float = param(
        1.5, 'integral time of the level-2 hold (s): a person who sees the slider or the beam '
        'stay off pushes harder against a steady load; 0 = no integral', low=0.0, high=1000.0)
    ball_tilt: float = param(0.5, 'target beam angle per ball offset (rad/m)', low=0.0,
                             high=100.0)
    ball_lead: float = param(0.6, 'look-ahead on the ball (s)', low=0.0, high=5.0)
    max_tilt: float = param(0.2, 'largest beam angle asked for to move the ball (rad)',
                            low=0.0, high=1.5)
    coupling_full_scale: float = param(3.0, 'translation actor: beam angle error that makes it '
                                       'push fully to nudge the beam through the coupling (rad)',
                                       low=1e-3, high=100.0)
    # motor execution
    max_rate: float = param(8.0, 'fastest stick movement (full scale per s)', low=0.1,
                            high=1000.0)
    neuromuscular_time: float = param(0.08, 'time constant of the arm following the intent (s)',
                                      low=0.0, high=2.0)
    motor_noise: float = param(0.08, 'motor noise std per unit of command (relative)', low=0.0,
                               high=2.0)
    motor_noise_floor: float = param(0.01, 'motor noise std at rest (normalized command)',
                                     low=0.0, high=1.0)
    lapse_probability: float = param(0.01, 'chance per step that the stick is held unchanged',
                                     low=0.0, high=1.0)
    # learning and fatigue
    untrained_factor: float = param(1.2, 'noises, biases and lapses of the first episode, '
                                    'relative to the trained person', low=1.0, high=20.0)
    learning_episodes: float = param(4.0, 'time constant of the learning curve (episodes)',
                                     low=0.1, high=10000.0)
    fatigue_per_minute: float = param(0.01, 'growth of motor noise, lapses and delay per '
                                      'minute on task (relative)', low=0.0, high=10.0)


def default_profiles_path() -> pathlib.Path:
    """Return the installed ``share/hrc_joystick_node/params/sim_human.yaml``."""
    from ament_index_python.packages import get_package_share_directory

    share = pathlib.Path(get_package_share_directory('hrc_joystick_node'))
    return share / 'params' / 'sim_human.yaml'


def load_profiles(path=None) -> typing.Dict[str, HumanProfile]:
    """Read every profile of ``path`` (default: the installed sim_human.yaml)."""
    path = pathlib.Path(path) if path is not None else default_profiles_path()
    with open(path) as stream:
        document = yaml.safe_load(stream) or {}
    entries = document.get('profiles')
    if not isinstance(entries, dict) or not entries:
        raise ParameterError(f'{path}: expected a non-empty mapping "profiles:"')
    profiles = {}
    for name, values in entries.items():
        try:
            profiles[name] = from_dict(HumanProfile, values or {})
        except ParameterError as error:
            raise ParameterError(f'{path}: profile {name!r}: {error}') from None
    return profiles


def load_profile(name: str, path=None) -> HumanProfile:
    """Return profile ``name`` from ``path`` (default: the installed sim_human.yaml)."""
    profiles = load_profiles(path)
    if name not in profiles:
        raise ParameterError(f'unknown simulated-human profile {name!r}: known {sorted(profiles)}')
    return profiles[name]


def normalize_subtasks(subtasks) -> typing.Tuple[typing.List[str], typing.List[str]]:
    """Return (known subtask ids, unknown ids), translating the T<level>_<index> aliases."""
    known, unknown = [], []
    for item in subtasks:
        name = SUBTASK_ALIASES.get(item, item)
        if name in SUBTASKS:
            if name not in known:
                known.append(name)
        else:
            unknown.append(item)
    return known, unknown


class _Percept(typing.NamedTuple):
    slider: float
    slider_velocity: float
    pendulum: float
    pendulum_velocity: float
    ball: float
    ball_velocity: float


def _interpolate(older: _Percept, newer: _Percept, weight_newer: float) -> _Percept:
    return _Percept(*(o + weight_newer * (n - o) for o, n in zip(older, newer)))


class SimulatedHuman:
    """One simulated person driving one degree of freedom (see the module docstring).

    ``practiced_episodes`` starts the learning curve further on (e.g. a person who already
    practiced); it counts up by one for every episode in which :meth:`act` is called.
    """

    def __init__(self, profile: HumanProfile, dof: str, seed: int = 0,
                 control_period: float = 0.2, practiced_episodes: int = 0):
        if control_period <= 0:
            raise ValueError(f'control_period must be > 0 s, got {control_period}')
        self.profile = profile
        self.dof = check_dof(dof)
        self.seed = int(seed)
        self.control_period = float(control_period)
        self.practiced_episodes = int(practiced_episodes)
        self.steps_on_task = 0  # steps acted in the whole session (fatigue)
        self.episode = None
        self._acted_this_episode = False
        self.reset(0)

    # -- episode -------------------------------------------------------------------------
    def reset(self, episode: int) -> None:
        """Start episode ``episode``: reseed, draw the episode's biases, clear the memory."""
        if self._acted_this_episode:
            self.practiced_episodes += 1
        self._acted_this_episode = False
        self.episode = int(episode)
        self._rng = numpy.random.default_rng([self.seed, self.episode])
        profile, practice = self.profile, self.practice_factor
        self._bias = _Percept(
            slider=self._rng.normal(0.0, profile.slider_bias * practice), slider_velocity=0.0,
            pendulum=self._rng.normal(0.0, profile.pendulum_bias * practice),
            pendulum_velocity=0.0,
            ball=self._rng.normal(0.0, profile.ball_bias * practice), ball_velocity=0.0)
        self._history: typing.List[_Percept] = []
        self._stick = 0.0  # where the stick is (normalized), before motor noise
        self._intent = 0.0  # where the arm is heading (after the rate limit)
        self._hold_integral = 0.0  # integral part of the level-2 hold (normalized command)

    @property
    def practice_factor(self) -> float:
        """Multiplier (>= 1) of noises and lapses from the learning curve, for this episode."""
        profile = self.profile
        remaining = math.exp(-self.practiced_episodes / profile.learning_episodes)
        return 1.0 + (profile.untrained_factor - 1.0) * remaining

    @property
    def fatigue_factor(self) -> float:
        """Multiplier (>= 1) of motor noise, lapses and delay from time on task."""
        minutes = self.steps_on_task * self.control_period / 60.0
        return 1.0 + self.profile.fatigue_per_minute * minutes

    # -- one step ------------------------------------------------------------------------
    def act(self, state, subtasks) -> float:
        """Return the stick command in [-1, 1] for ``state`` given the assigned subtasks."""
        subtasks, _ = normalize_subtasks(subtasks)
        profile, rng = self.profile, self._rng
        practice, fatigue = self.practice_factor, self.fatigue_factor
        self._acted_this_episode = True
        self.steps_on_task += 1

        self._history.append(self._perceive(state, practice))
        del self._history[:-HISTORY_LENGTH]
        delay = profile.reaction_delay * fatigue
        seen = self._delayed(delay / self.control_period)
        # Extrapolate the delayed percept over the compensated share of the delay; a novice
        # (practice > 1) anticipates less.
        horizon = profile.prediction * delay / practice
        lead = profile.lead_time / practice
        slider = seen.slider + horizon * seen.slider_velocity
        angle = seen.pendulum + horizon * seen.pendulum_velocity
        ball = seen.ball + horizon * seen.ball_velocity

        target_angle = 0.0
        if BALL in subtasks:
            ball_error = ball + profile.ball_lead * seen.ball_velocity
            target_angle = profile.ball_tilt * ball_error
            target_angle = max(-profile.max_tilt, min(profile.max_tilt, target_angle))
        intent = 0.0
        if self.dof == ROTATION and (PENDULUM in subtasks or BALL in subtasks):
            intent = -self._hold(angle - target_angle, seen.pendulum_velocity, lead,
                                 profile.pendulum_full_scale)
        elif self.dof == TRANSLATION:
            if SLIDER in subtasks:
                intent = -self._hold(slider, seen.slider_velocity, lead,
                                     profile.slider_full_scale)
            if BALL in subtasks:
                # Accelerating the slider up presses the east end down: push up when the
                # beam is above the angle the ball needs.
                intent += (angle - target_angle) / profile.coupling_full_scale
        intent = max(-1.0, min(1.0, intent))

        lapse = profile.lapse_probability * practice * fatigue
        if rng.random() >= lapse:
            # Bandwidth: a slew-rate limit, then the neuromuscular lag toward that point.
            step_limit = profile.max_rate * self.control_period
            self._intent += max(-step_limit, min(step_limit, intent - self._intent))
            if profile.neuromuscular_time > 0.0:
                follow = 1.0 - math.exp(-self.control_period / profile.neuromuscular_time)
            else:
                follow = 1.0
            self._stick += follow * (self._intent - self._stick)
        noise_std = (profile.motor_noise * abs(self._stick)
                     + profile.motor_noise_floor) * practice * fatigue
        command = self._stick + rng.normal(0.0, noise_std)
        return max(-1.0, min(1.0, float(command)))

    def _hold(self, error: float, rate: float, lead: float, full_scale: float) -> float:
        """Return the normalized push against ``error`` of the level-2 hold (PID in effect)."""
        push = (error + lead * rate) / full_scale
        if self.profile.integral_time > 0.0:
            self._hold_integral += error / full_scale * (self.control_period
                                                         / self.profile.integral_time)
            # Anti-windup: the integral alone never asks for more than the full stick.
            self._hold_integral = max(-1.0, min(1.0, self._hold_integral))
            push += self._hold_integral
        return push

    def _perceive(self, state, practice: float) -> _Percept:
        profile, rng, bias = self.profile, self._rng, self._bias
        values = []
        for position, velocity, noise, offset in (
                (state.slider_position, state.slider_velocity, profile.slider_noise,
                 bias.slider),
                (state.pendulum_angle, state.pendulum_angular_velocity, profile.pendulum_noise,
                 bias.pendulum),
                (state.ball_position, state.ball_velocity, profile.ball_noise, bias.ball)):
            noise *= practice
            values.append(position - offset + rng.normal(0.0, noise))
            velocity_std = (profile.velocity_noise * practice * abs(velocity)
                            + noise / MOTION_INTEGRATION_TIME)
            values.append(velocity + rng.normal(0.0, velocity_std))
        return _Percept(*values)

    def _delayed(self, lag_steps: float) -> _Percept:
        """Return the percept of ``lag_steps`` control steps ago (interpolated)."""
        history = self._history
        newest = len(history) - 1
        position = newest - lag_steps
        if position <= 0:
            return history[0]  # not enough memory yet: the oldest percept of the episode
        older = int(math.floor(position))
        weight = position - older
        if older >= newest:
            return history[newest]
        return _interpolate(history[older], history[older + 1], weight)


def profile_names(path=None) -> typing.List[str]:
    """Return the names of the profiles in ``path`` (default: the installed sim_human.yaml)."""
    return sorted(load_profiles(path))


def profile_fields() -> typing.List[str]:
    """Return the names of a profile's fields (for documentation and checks)."""
    return [dataclass_field.name for dataclass_field in fields(HumanProfile)]
