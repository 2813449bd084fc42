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
6. **Fatigue, bounded and recovering** (:mod:`hrc_joystick_node.fatigue`). Time on task
   raises the delay, the motor noise and the lapse rate towards a ceiling (a saturating
   exponential approach, ``fatigue_onset_minutes``, ``fatigue_*_ceiling``); rest restores it
   (``recovery_minutes``). The clock is the simulation's: :meth:`SimulatedHuman.act` takes the
   state's stamp (``now``, s on the session clock) and counts one control period per state as
   time on task and any longer gap (episodes the person sat out) as rest; every episode
   boundary adds the declared break ``rest_between_episodes``. Without ``now`` (older
   callers) only the periods acted and the declared breaks count. Never wall time, so a
   lockstep graph and an in-process run see the same person.
7. **Adaptation to the partner** (:mod:`hrc_joystick_node.adaptation`). A two-rate state-space
   model learns, trial by trial (episode by episode), a feedforward stick offset from the error
   the team left on the person's own level-2 subtask, as the person corrected it (the mean
   feedback correction of the hold, :attr:`SimulatedHuman.episode_correction`; ``fast_*``,
   ``slow_*``), so a partner who keeps pushing the person's subtask off is compensated over
   episodes and re-learned when the partner changes.
8. **A person of a population.** :func:`hrc_joystick_node.population.sample_person` draws a
   person around a profile (delay, noises, gains, constant perceptual offsets, learning rates),
   reproducibly from a seed; the ``*_offset`` fields are such a person's constant misjudgement
   of the zero (0 in the profiles themselves).

Determinism: every random draw comes from a numpy Generator seeded with ``(seed, episode)`` at
each :meth:`SimulatedHuman.reset`, so an episode reproduces from the seed, the episode index,
the person's state so far (``practiced_episodes``, the fatigue and the adaptation, see
:meth:`SimulatedHuman.snapshot`) and the sequence of states (and stamps).

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
  Mewhort 2000); vigilance and performance decline with time on task by a few tens of percent
  over tens of minutes, most of it early, and rest restores it (Mackworth 1948; Grier et al.
  2003; Warm, Parasuraman & Matthews 2008; see :mod:`hrc_joystick_node.fatigue`); the paper
  kept episodes to 40 s for that reason.
* People adapt to a systematic disturbance trial by trial, with a fast and a slow process
  (Thoroughman & Shadmehr 2000; Smith, Ghazizadeh & Shadmehr 2006; see
  :mod:`hrc_joystick_node.adaptation`).

What is fact and what is a modelling choice: the structure (delay, PD(+I) control in crossover
terms, signal-dependent noise, exponential practice, saturating fatigue, two-rate adaptation)
follows the sources above; every number is a profile parameter chosen to match their orders
of magnitude (marked per module), not fitted to data of this task.
"""

from dataclasses import dataclass
import math
import pathlib
import typing

import numpy
import yaml

from hrc_common.dof import check_dof, ROTATION, TRANSLATION
from hrc_common.params import from_dict, param, ParameterError
from hrc_common.paths import params_file
from hrc_joystick_node.adaptation import TwoRateAdaptation
from hrc_joystick_node.fatigue import Fatigue

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
    # learning curve
    untrained_factor: float = param(1.2, 'noises, biases and lapses of the first episode, '
                                    'relative to the trained person', low=1.0, high=20.0)
    learning_episodes: float = param(4.0, 'time constant of the learning curve (episodes)',
                                     low=0.1, high=10000.0)
    # fatigue (hrc_joystick_node.fatigue)
    fatigue_onset_minutes: float = param(20.0, 'time on task (simulation min) that takes '
                                         'fatigue 63 % of the way to its ceiling', low=0.01,
                                         high=100000.0)
    recovery_minutes: float = param(5.0, 'rest (simulation min) that removes 63 % of the '
                                    'fatigue', low=0.01, high=100000.0)
    fatigue_delay_ceiling: float = param(0.15, 'largest relative increase of the reaction '
                                         'delay with fatigue', low=0.0, high=10.0)
    fatigue_noise_ceiling: float = param(0.3, 'largest relative increase of the motor noise '
                                         'with fatigue', low=0.0, high=10.0)
    fatigue_lapse_ceiling: float = param(1.0, 'largest relative increase of the lapse '
                                         'probability with fatigue', low=0.0, high=100.0)
    rest_between_episodes: float = param(10.0, 'declared break between two episodes (s of '
                                         'simulation time: reset, countdown, the update)',
                                         low=0.0, high=100000.0)
    # adaptation to the partner (hrc_joystick_node.adaptation)
    fast_retention: float = param(0.6, 'retention per episode of the fast adaptation process',
                                  low=0.0, high=0.9999)
    fast_learning_rate: float = param(0.2, 'learning rate per episode of the fast process '
                                      '(share of the episode error)', low=0.0, high=2.0)
    slow_retention: float = param(0.97, 'retention per episode of the slow adaptation process',
                                  low=0.0, high=0.9999)
    slow_learning_rate: float = param(0.05, 'learning rate per episode of the slow process',
                                      low=0.0, high=2.0)
    # a person of the population (hrc_joystick_node.population); 0 in the profiles
    slider_offset: float = param(0.0, "this person's constant misjudgement of the middle of "
                                 'the rod (m)', low=-0.1, high=0.1)
    pendulum_offset: float = param(0.0, "this person's constant misjudgement of the "
                                   'horizontal (rad)', low=-1.0, high=1.0)
    ball_offset: float = param(0.0, "this person's constant misjudgement of the middle of the "
                               'beam (m)', low=-0.25, high=0.25)


def default_profiles_path() -> pathlib.Path:
    """Return ``params/sim_human.yaml`` (``hrc_common.paths.params_file``)."""
    return params_file('sim_human.yaml')


def load_profiles(path=None) -> typing.Dict[str, HumanProfile]:
    """Read every profile of ``path`` (default: the installed sim_human.yaml).

    The file is checked by shape before use: it must be YAML text holding a mapping with a
    non-empty mapping ``profiles:`` of name -> mapping of fields. Anything else (missing,
    unreadable, binary, not YAML, a list, a string) raises ParameterError with every reason.
    """
    path = pathlib.Path(path) if path is not None else default_profiles_path()
    try:
        text = path.read_text(encoding='utf-8')
    except UnicodeDecodeError:
        raise ParameterError(f'{path}: not a YAML text file (binary content)') from None
    except OSError as error:
        raise ParameterError(f'{path}: cannot read: {error.strerror or error}') from None
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        where = getattr(error, 'problem_mark', None)
        at = f' (line {where.line + 1}, column {where.column + 1})' if where else ''
        raise ParameterError(f'{path}: not valid YAML{at}: '
                             f'{getattr(error, "problem", None) or error}') from None
    if not isinstance(document, dict):
        raise ParameterError(f'{path}: expected a mapping with "profiles:", got '
                             f'{type(document).__name__}')
    entries = document.get('profiles')
    if not isinstance(entries, dict) or not entries:
        raise ParameterError(f'{path}: expected a non-empty mapping "profiles:"')
    profiles, reasons = {}, []
    for name, values in entries.items():
        if values is not None and not isinstance(values, dict):
            reasons.append(f'{path}: profile {name!r}: expected a mapping of fields, got '
                           f'{type(values).__name__}')
            continue
        try:
            profiles[str(name)] = from_dict(HumanProfile, values or {})
        except ParameterError as error:
            reasons += [f'{path}: profile {name!r}: {reason}' for reason in error.reasons]
        except TypeError as error:  # a field of the wrong type the dataclass cannot take
            reasons.append(f'{path}: profile {name!r}: {error}')
    if reasons:
        raise ParameterError('; '.join(reasons), reasons)
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


class StateView(typing.NamedTuple):
    """The PhysicsState attributes the simulated human reads (e.g. taken from a TaskState)."""

    step: int
    time: float  # s since the episode's reset
    slider_position: float
    slider_velocity: float
    pendulum_angle: float
    pendulum_angular_velocity: float
    ball_position: float
    ball_velocity: float


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
        self.steps_on_task = 0  # steps acted in the whole session
        self.fatigue = Fatigue(profile.fatigue_onset_minutes * 60.0,
                               profile.recovery_minutes * 60.0, profile.fatigue_delay_ceiling,
                               profile.fatigue_noise_ceiling, profile.fatigue_lapse_ceiling)
        self.adaptation = TwoRateAdaptation(profile.fast_retention, profile.fast_learning_rate,
                                            profile.slow_retention, profile.slow_learning_rate)
        self.episode = None
        self._last_time = None  # simulation time (s) of the last state acted on
        self._acted_this_episode = False
        self._error_sum = 0.0  # this episode's own-subtask error (normalized), for adaptation
        self._error_steps = 0
        self.reset(0)

    # -- episode -------------------------------------------------------------------------
    def reset(self, episode: int, rest_seconds: typing.Optional[float] = None) -> None:
        """Start episode ``episode``: learn from the last one, rest, reseed, clear the memory.

        Each episode boundary passed since the last episode rests the person for
        ``rest_seconds`` (default: the profile's ``rest_between_episodes``), simulation time.
        """
        if self._acted_this_episode:
            self.practiced_episodes += 1
            if self._error_steps:
                self.adaptation.update(self.episode_correction)
        if self.episode is not None and int(episode) != self.episode:
            boundaries = max(1, int(episode) - self.episode)
            rest = self.profile.rest_between_episodes if rest_seconds is None else rest_seconds
            self.fatigue.rest(boundaries * float(rest))
        self._acted_this_episode = False
        self._error_sum, self._error_steps = 0.0, 0
        self.episode = int(episode)
        self._rng = numpy.random.default_rng([self.seed, self.episode])
        profile, practice = self.profile, self.practice_factor
        self._bias = _Percept(
            slider=profile.slider_offset + self._rng.normal(0.0, profile.slider_bias * practice),
            slider_velocity=0.0,
            pendulum=profile.pendulum_offset + self._rng.normal(0.0,
                                                                profile.pendulum_bias * practice),
            pendulum_velocity=0.0,
            ball=profile.ball_offset + self._rng.normal(0.0, profile.ball_bias * practice),
            ball_velocity=0.0)
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
        """Multiplier (>= 1) of the motor noise from fatigue (delay and lapses: ``fatigue``)."""
        return self.fatigue.noise_factor

    @property
    def episode_correction(self) -> float:
        """Mean feedback correction of the own subtask so far this episode (stick units).

        The error the team leaves on the person's subtask as the person corrects it: what the
        adaptation learns from when the episode ends (0 before any step on the subtask).
        """
        return self._error_sum / self._error_steps if self._error_steps else 0.0

    def snapshot(self) -> dict:
        """Return the person's state carried between episodes, as plain values."""
        return {'practiced_episodes': self.practiced_episodes,
                'steps_on_task': self.steps_on_task, 'last_time': self._last_time,
                'fatigue': self.fatigue.snapshot(), 'adaptation': self.adaptation.snapshot()}

    def restore(self, snapshot: dict) -> None:
        """Take a state of :meth:`snapshot` (call :meth:`reset` afterwards)."""
        self.practiced_episodes = int(snapshot['practiced_episodes'])
        self.steps_on_task = int(snapshot['steps_on_task'])
        self._last_time = snapshot['last_time']
        self.fatigue.restore(snapshot['fatigue'])
        self.adaptation.restore(snapshot['adaptation'])
        self._acted_this_episode = False

    def _advance_clock(self, now: typing.Optional[float]) -> None:
        """Count the time since the last state acted on: one period on task, the rest rest."""
        period = self.control_period
        if now is None:
            now = period if self._last_time is None else self._last_time + period
        gap = period if self._last_time is None else float(now) - self._last_time
        if gap > 0.0:
            self.fatigue.work(min(gap, period))
            self.fatigue.rest(gap - period)
        self._last_time = float(now)

    # -- one step ------------------------------------------------------------------------
    def act(self, state, subtasks, now: typing.Optional[float] = None) -> float:
        """Return the stick command in [-1, 1] for ``state`` given the assigned subtasks.

        ``now``: the simulation time of ``state`` on the session clock (s; the TaskState
        stamp), for fatigue and rest; None counts one control period per call.
        """
        subtasks, _ = normalize_subtasks(subtasks)
        profile, rng = self.profile, self._rng
        practice = self.practice_factor
        self._advance_clock(now)
        fatigue = self.fatigue
        self._acted_this_episode = True
        self.steps_on_task += 1

        self._history.append(self._perceive(state, practice))
        del self._history[:-HISTORY_LENGTH]
        delay = profile.reaction_delay * fatigue.delay_factor
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

        lapse = profile.lapse_probability * practice * fatigue.lapse_factor
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
                     + profile.motor_noise_floor) * practice * fatigue.noise_factor
        command = self._stick + rng.normal(0.0, noise_std)
        return max(-1.0, min(1.0, float(command)))

    def _hold(self, error: float, rate: float, lead: float, full_scale: float) -> float:
        """Return the normalized push against ``error`` of the level-2 hold (PID in effect).

        Plus the learned feedforward against the partner (adaptation); the feedback part is
        the error as the person corrects it (stick units), which the adaptation learns from
        at the end of the episode (feedback-error learning).
        """
        push = (error + lead * rate) / full_scale
        if self.profile.integral_time > 0.0:
            self._hold_integral += error / full_scale * (self.control_period
                                                         / self.profile.integral_time)
            # Anti-windup: the integral alone never asks for more than the full stick.
            self._hold_integral = max(-1.0, min(1.0, self._hold_integral))
            push += self._hold_integral
        self._error_sum += push
        self._error_steps += 1
        return push + self.adaptation.compensation

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
