"""A simulated human at a joystick: perception, delay, control, motor noise, learning, fatigue.

Pure Python and numpy (no rclpy): the human node, the experiment runner and the benchmarks all
use :class:`SimulatedHuman` in the same way::

    human = SimulatedHuman(load_profile('skilled'), dof='rotation', seed=3,
                           control_period=0.02)   # load_profile: hrc_joystick_node.human_profile
    human.reset(episode=0)
    command = human.act(state, ['pendulum'])   # float in [-1, 1], once per control_period

``state`` is anything with the attributes of ``hrc_sim_node.physics.PhysicsState`` (``step``,
``slider_position``, ``slider_velocity``, ``pendulum_angle``, ``pendulum_angular_velocity``,
``ball_position``, ``ball_velocity``); ``subtasks`` are the ids the session assigns to the
human: ``slider`` (keep S_x at 0), ``pendulum`` (keep P_z at 0), ``ball`` (keep B_y at 0).

The model, step by step (one call of :meth:`SimulatedHuman.act` per ``control_period`` T)
-------------------------------------------------------------------------------------------
The person is called every ``control_period`` s (the caller's contract: the sim's
``human_period``, 0.02 s by default, or its control period, 0.2 s). Every delay, time
constant, rate and probability of the model is in seconds and converted with T, so the same
profile is the same person at any call period: noises are first-order (Ornstein-Uhlenbeck)
processes advanced by T with the exact factor exp(-T / tau), lapses last seconds, the stick
moves at most ``max_rate`` per second.

1. **Perception** and 2. **reaction delay** (:mod:`hrc_joystick_node.perception`): biased,
   noisy percepts of the slider, the beam (worse: the horizontal is hard to judge) and the
   ball, the ball's rolling as a cue to the tilt, acted on ``reaction_delay`` s later. A
   ``prediction`` share of the delay is compensated by extrapolating with the perceived
   velocity, as trained operators do (the crossover model's lead equalization).
3. **Control.** A proportional-derivative law on the person's own degree of freedom, written in
   the terms a person would use: the error (``*_full_scale``) at which they push the stick all
   the way, and how far ahead (``lead_time``) they look; a practiced person also pushes harder
   against a steady load (an integral term, ``integral_time``), e.g. the ball resting at an
   end stop and weighing the beam down. Both plants are velocity-like (heavy damping), so the
   gains follow the crossover model: a crossover of about 2.5-3.5 rad/s for ``skilled`` and
   ``paper`` (measured by ``bench/crossover.py``), with a lead that cancels the plants' lags;
   ``novice`` about 2 rad/s and less; a novice's higher gain on the beam overshoots.
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
   ``motor_noise_floor``) and correlated over ``motor_noise_time`` (a unit Ornstein-Uhlenbeck
   process: the arm low-passes the noise of the motor command, as it does the intent).
   Attention lapses fill the share ``lapse_probability`` of the time, each ``lapse_duration``
   s long (a Poisson process of starts at the rate share / duration); during a lapse the stick
   is held where it was.
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
   boundary adds the declared break ``rest_between_episodes``. Without ``now`` only the
   periods acted and the declared breaks count. Never wall time, so a lockstep graph and an
   in-process run see the same person.
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
9. **Co-adaptation to the partner's predictability** (:mod:`hrc_joystick_node.co_adaptation`,
   off but in ``paper_co_adapting``). An internal model of the partner's degree of freedom
   whose surprise makes the person stiffer (a gain on the intent), slower (slew rate and
   neuromuscular lag) and, through frustration, noisier and less attentive.

Determinism: every random draw comes from a numpy Generator seeded with ``(seed, episode)`` at
each :meth:`SimulatedHuman.reset`, so an episode reproduces from the seed, the episode index,
the person's state so far (``practiced_episodes``, the fatigue and the adaptation, see
:meth:`SimulatedHuman.snapshot`) and the sequence of states (and stamps).

Facts the control and motor numbers rest on (perception's: :mod:`hrc_joystick_node.perception`;
why the paper's person has its numbers: :mod:`hrc_joystick_node.human_profile`)
------------------------------------------------------------------------------------------
* Manual control of a velocity-like plant (K/s near the crossover) is described by McRuer's
  crossover model: open loop ~ w_c e^(-s tau_e) / s near w_c, with w_c ~2-5 rad/s and an
  effective delay tau_e ~0.1-0.3 s (McRuer & Jex 1967). The ``paper`` person's delay (0.2 s),
  lead (0.2 s, cancelling the plants' 0.09-0.16 s lags, the model's lead equalization) and
  gains (``*_full_scale``, one crossover frequency on both plants) are chosen so that
  ``bench/crossover.py`` fits it within those ranges on both degrees of freedom (measured
  there, not fitted to data of this task).
* Motor noise grows with the command (signal-dependent noise, Harris & Wolpert 1998; Schmidt
  et al. 1979); a person moves a joystick through its range in ~0.2-0.4 s (bandwidth). Motor
  noise is correlated over ``motor_noise_time`` = 0.1 s, the arm's neuromuscular time
  constant (the optimal-control model of the human operator filters its motor noise through
  the same lag; Kleinman, Baron & Levison 1970).
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
of magnitude (marked per module), not fitted to data of this task. Lapses as a Poisson process
of fixed length are a choice without a direct source.
"""

import math
import typing

import numpy

from hrc_common.dof import check_dof, ROTATION, TRANSLATION
from hrc_joystick_node.adaptation import TwoRateAdaptation
from hrc_joystick_node.co_adaptation import CoAdaptation, co_adapting
from hrc_joystick_node.fatigue import Fatigue
from hrc_joystick_node.human_profile import HumanProfile
from hrc_joystick_node.perception import advance, memory, Perception

SLIDER = 'slider'
PENDULUM = 'pendulum'
BALL = 'ball'
SUBTASKS = (SLIDER, PENDULUM, BALL)
# The level-2 subtask each degree of freedom drives directly.
OWN_SUBTASK = {TRANSLATION: SLIDER, ROTATION: PENDULUM}
# Aliases by the paper's notation T_i^j written T<level>_<index> (SessionStatus comments).
SUBTASK_ALIASES = {'T2_1': SLIDER, 'T2_2': PENDULUM, 'T1_1': BALL}


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


class SimulatedHuman:
    """One simulated person driving one degree of freedom (see the module docstring).

    ``control_period``: the s between calls of :meth:`act`, from the sim's limits (its control
    period, or ``SimLimits.human_step`` at the human's rate); no default, so no caller runs a
    person at a period the sim does not have. ``practiced_episodes`` starts the learning curve
    further on (e.g. a person who already practiced); it counts up by one for every episode in
    which :meth:`act` is called.
    """

    def __init__(self, profile: HumanProfile, dof: str, seed: int = 0, *,
                 control_period: float, practiced_episodes: int = 0):
        if control_period <= 0:
            raise ValueError(f'control_period must be > 0 s, got {control_period}')
        self.profile = profile
        self.dof = check_dof(dof)
        self.seed = int(seed)
        self.control_period = float(control_period)
        self.perception = Perception(profile, self.control_period)
        # One call advances the motor noise by control_period seconds: the factor of a
        # first-order process of time constant tau is exp(-period / tau).
        self._motor_memory = memory(self.control_period, profile.motor_noise_time)
        if profile.lapse_duration > 0.0:
            # Lapses start as a Poisson process whose rate makes them fill the share
            # lapse_probability of the time (for small shares): rate = share / duration.
            self._lapse_calls = profile.lapse_duration / self.control_period
        else:
            self._lapse_calls = 0.0
        self.practiced_episodes = int(practiced_episodes)
        self.steps_on_task = 0  # steps acted in the whole session
        self.fatigue = Fatigue(profile.fatigue_onset_minutes * 60.0,
                               profile.recovery_minutes * 60.0, profile.fatigue_delay_ceiling,
                               profile.fatigue_noise_ceiling, profile.fatigue_lapse_ceiling)
        self.adaptation = TwoRateAdaptation(profile.fast_retention, profile.fast_learning_rate,
                                            profile.slow_retention, profile.slow_learning_rate)
        # None when the profile switches no mechanism on: the person is then bit-identical to
        # one without the component.
        self.co_adaptation = (CoAdaptation(profile, self.dof, self.control_period)
                              if co_adapting(profile) else None)
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
            self._rest(boundaries * float(rest))
        if self.co_adaptation is not None:
            self.co_adaptation.start_episode()
        self._acted_this_episode = False
        self._error_sum, self._error_steps = 0.0, 0
        self.episode = int(episode)
        self._rng = numpy.random.default_rng([self.seed, self.episode])
        self.perception.reset(self._rng, self.practice_factor)
        # Unit-variance motor noise state, None until the first call of the episode draws it
        # from its stationary distribution.
        self._motor_state: typing.Optional[float] = None
        self._lapse_left = 0.0  # calls of the current lapse still to come
        self._stick = 0.0  # where the stick is (normalized), before motor noise
        self._intent = 0.0  # where the arm is heading (after the rate limit)
        self._hold_integral = 0.0  # integral part of the level-2 hold (normalized command)
        self._command = 0.0  # the last command (the efference copy of co-adaptation)

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
        snapshot = {'practiced_episodes': self.practiced_episodes,
                    'steps_on_task': self.steps_on_task, 'last_time': self._last_time,
                    'fatigue': self.fatigue.snapshot(), 'adaptation': self.adaptation.snapshot()}
        if self.co_adaptation is not None:
            snapshot['co_adaptation'] = self.co_adaptation.snapshot()
        return snapshot

    def restore(self, snapshot: dict) -> None:
        """Take a state of :meth:`snapshot` (call :meth:`reset` afterwards)."""
        self.practiced_episodes = int(snapshot['practiced_episodes'])
        self.steps_on_task = int(snapshot['steps_on_task'])
        self._last_time = snapshot['last_time']
        self.fatigue.restore(snapshot['fatigue'])
        self.adaptation.restore(snapshot['adaptation'])
        if self.co_adaptation is not None and 'co_adaptation' in snapshot:
            self.co_adaptation.restore(snapshot['co_adaptation'])
        self._acted_this_episode = False

    def _advance_clock(self, now: typing.Optional[float]) -> None:
        """Count the time since the last state acted on: one period on task, the rest rest."""
        period = self.control_period
        if now is None:
            now = period if self._last_time is None else self._last_time + period
        gap = period if self._last_time is None else float(now) - self._last_time
        if gap > 0.0:
            self.fatigue.work(min(gap, period))
            self._rest(gap - period)
        self._last_time = float(now)

    def _rest(self, seconds: float) -> None:
        """Rest ``seconds`` of simulation time: fatigue recovers, co-adaptation relaxes."""
        self.fatigue.rest(seconds)
        if self.co_adaptation is not None:
            self.co_adaptation.rest(seconds)

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

        self.perception.remember(state, practice)
        delay = profile.reaction_delay * fatigue.delay_factor
        seen = self.perception.delayed(delay / self.control_period)
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
        gain, bandwidth, noise, lapses = self._co_adapt(seen)
        intent = max(-1.0, min(1.0, intent * gain))

        lapse = profile.lapse_probability * practice * fatigue.lapse_factor * lapses
        if not self._lapsed(lapse, rng.random()):
            # Bandwidth: a slew-rate limit, then the neuromuscular lag toward that point.
            step_limit = profile.max_rate * self.control_period * bandwidth
            self._intent += max(-step_limit, min(step_limit, intent - self._intent))
            if profile.neuromuscular_time > 0.0:
                follow = 1.0 - math.exp(-self.control_period * bandwidth
                                        / profile.neuromuscular_time)
            else:
                follow = 1.0
            self._stick += follow * (self._intent - self._stick)
        noise_std = (profile.motor_noise * abs(self._stick)
                     + profile.motor_noise_floor) * practice * fatigue.noise_factor * noise
        self._motor_state = advance(self._motor_state, self._motor_memory, rng)
        command = self._stick + noise_std * self._motor_state
        self._command = max(-1.0, min(1.0, float(command)))
        return self._command

    def _co_adapt(self, seen) -> typing.Tuple[float, float, float, float]:
        """Look at the partner; return (gain, bandwidth, noise, lapse) factors, 1 when off."""
        co_adaptation = self.co_adaptation
        if co_adaptation is None:
            return 1.0, 1.0, 1.0, 1.0
        if self.dof == ROTATION:
            co_adaptation.observe(seen.slider, seen.slider_velocity, self._command)
        else:
            co_adaptation.observe(seen.pendulum, seen.pendulum_velocity, self._command)
        return (co_adaptation.stiffness, co_adaptation.bandwidth_factor,
                co_adaptation.noise_factor, co_adaptation.lapse_factor)

    def _lapsed(self, share: float, draw: float) -> bool:
        """Return whether attention lapses at this call (``draw``: uniform in [0, 1)).

        With ``lapse_duration`` 0 a lapse is one call, with chance ``share``. Otherwise a lapse
        lasts ``lapse_duration`` s (rounded to calls) and lapses start at the rate
        ``share / lapse_duration`` per s, so they fill the share ``share`` of the time at any
        call period (for small shares).
        """
        if self._lapse_calls <= 0.0:
            return draw < share
        if self._lapse_left > 0.0:
            self._lapse_left -= 1.0
            return True
        # A lapse cannot be shorter than a call: with calls longer than a lapse, each call
        # lapses with about the chance ``share``, which keeps the share of the time.
        calls = max(1.0, self._lapse_calls)
        start_chance = 1.0 - math.exp(-share / calls) if share < 1.0 else 1.0
        if draw < start_chance:
            self._lapse_left = max(0.0, round(self._lapse_calls) - 1.0)
            return True
        return False

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
