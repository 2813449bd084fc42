"""What the simulated person sees, and when: perception and the reaction delay; pure, no rclpy.

One :class:`Perception` per :class:`hrc_joystick_node.sim_human.SimulatedHuman`, advanced once
per call of the person (``control_period`` s):

1. **Perception.** The person sees the slider height, the beam angle and the ball position on a
   monitor. Each percept is the true value plus a per-episode misjudgement of the zero (a bias,
   drawn at reset: "where is the middle", "what is horizontal") plus a noise that wanders in
   time: a unit Ornstein-Uhlenbeck process per percept (correlation time
   ``perception_noise_time``) scaled by the profile's standard deviation. Velocities are
   perceived with a relative (Weber) error plus a floor, as processes of the same kind. The
   noise and the bias are per watched quantity, and the beam angle is perceived worse than the
   slider height: the paper (Sec. V.B) reports that its subjects judged translation better
   than rotation and "struggled to identify if the pendulum was in the horizontal direction".
   **The ball as a cue to the tilt**: people also see the ball roll, which tells them the beam
   is not level. A complementary filter takes the beam angle from the eye for fast changes and
   pulls it, with time constant ``ball_cue_time``, toward the tilt the ball's rolling speed
   shows (``-ball_speed_tilt * speed``: a ball rolling east means the east end is low; the
   person's learned internal model, 0.2 rad per m/s, the default physics' m_b g / c_b = 4.9
   m/s per rad); a ball at or near an end stop (``BALL_CUE_RANGE``) shows nothing. So a
   misjudged horizontal fades while the ball rolls freely, as a person corrects a beam that
   looks level when the ball keeps rolling.
2. **Reaction delay.** The person acts on what they perceived ``reaction_delay`` s ago (a
   buffer of percepts, :meth:`Perception.delayed`, linearly interpolated between calls; the
   buffer keeps ``HISTORY_SECONDS``).

Facts the perception numbers rest on (documented defaults in ``params/sim_human.yaml``)
-------------------------------------------------------------------------------------
* Bisecting a line (finding "the middle") is precise to ~1-3 % of its length with a small
  constant bias (Jewell & McCourt 2000, pseudoneglect): on the 0.2 m rod, a few mm.
* Orientation judgments are best near horizontal/vertical (~1-2 degrees, Appelle 1972, the
  oblique effect). The subjective visual vertical (SVV) of healthy adults lies within ~2
  degrees of the true vertical (the clinical normal range, e.g. Friedmann 1970; Dieterich &
  Brandt 1993), with a within-person standard deviation of ~1 degree from setting to setting.
  Used here (choice within those facts): the beam-angle noise is 0.57-1.7 degrees
  (``paper`` 0.57, ``skilled`` 0.86, ``novice`` 1.7), the per-episode bias 0.57-1.15 degrees
  (``paper`` 0.97: the SVV's setting-to-setting SD, :mod:`hrc_joystick_node.human_profile`),
  and the population's constant offset (:mod:`hrc_joystick_node.population`) has the
  per-episode bias's standard deviation, so bias and offset together are within ~1.6
  degrees (SD).
* The noise's correlation time ``perception_noise_time`` = 0.05 s is a choice of the order of
  the visual system's temporal integration (tens of ms to ~0.1 s, Bloch's law); what the
  plant feels is its low-frequency power (std^2 * tau), which the crossover bench validates
  through the remnant.
* Velocity discrimination has a Weber fraction of ~0.1-0.2 (McKee 1981).
* Visual reaction time to a display ~0.2-0.3 s; the effective delay of a human operator in
  compensatory tracking 0.1-0.3 s (McRuer & Jex 1967, crossover model; Welford 1980).

Choices without a direct source: first-order (Ornstein-Uhlenbeck) noise processes and their
correlation times, the ball cue as a complementary filter with its time constant (2 s: the
person needs to see the ball roll for a while) and its end-stop range.
"""

import collections
import math
import typing

from hrc_joystick_node.human_profile import HumanProfile

# Time over which a person integrates motion to judge a speed (s): the velocity noise floor is
# the position noise per this time.
MOTION_INTEGRATION_TIME = 0.5
# Percepts kept for the delay line (s): far beyond any reaction delay (64 calls at 0.2 s).
HISTORY_SECONDS = 12.8
# A ball this far from the middle of the beam (m) is at or near an end stop (the default
# beam's stops are at +-0.25 m): resting there it says nothing about the tilt, so the ball
# cue is not updated (a choice).
BALL_CUE_RANGE = 0.2
# Perception channels with their own noise process, in the order of Percept.
PERCEPT_CHANNELS = 6


class Percept(typing.NamedTuple):
    """What the person perceives at one call (m, m/s, rad, rad/s)."""

    slider: float
    slider_velocity: float
    pendulum: float
    pendulum_velocity: float
    ball: float
    ball_velocity: float


def memory(period: float, time_constant: float) -> float:
    """Return the share of a first-order process kept over ``period`` (0 for tau = 0)."""
    return math.exp(-period / time_constant) if time_constant > 0.0 else 0.0


def advance(value: typing.Optional[float], kept: float, rng) -> float:
    """Advance a unit-variance first-order (Ornstein-Uhlenbeck) process by one call.

    Exact discretization: x' = m * x + sqrt(1 - m^2) * N(0, 1) keeps the variance at 1 for any
    call period; ``kept`` (m) 0, or no value yet (the stationary draw), is a fresh N(0, 1)
    sample: one draw either way.
    """
    draw = rng.standard_normal()
    if value is None or kept == 0.0:
        return float(draw)
    return kept * value + math.sqrt(1.0 - kept * kept) * float(draw)


def _interpolate(older: Percept, newer: Percept, weight_newer: float) -> Percept:
    return Percept(*(o + weight_newer * (n - o) for o, n in zip(older, newer)))


class Perception:
    """The person's percepts of one episode: biases, noise processes, ball cue, delay line.

    ``control_period``: s between two calls of :meth:`remember` (the person's call period).
    The random draws come from the generator given to :meth:`reset` (the person's, reseeded
    per episode), so an episode reproduces from its seed.
    """

    def __init__(self, profile: HumanProfile, control_period: float):
        self.profile = profile
        self.control_period = float(control_period)
        # Calls of the delay line kept: HISTORY_SECONDS at this call rate (64 at 0.2 s).
        self._history_length = max(2, int(math.ceil(HISTORY_SECONDS / self.control_period
                                                    - 1e-9)))
        # One call advances every noise process by control_period seconds: the factor of a
        # first-order process of time constant tau is exp(-period / tau).
        self._memory = memory(self.control_period, profile.perception_noise_time)
        self._ball_cue_gain = (1.0 - memory(self.control_period, profile.ball_cue_time)
                               if profile.ball_cue_time > 0.0 else 0.0)
        self._rng = None

    def reset(self, rng, practice: float) -> None:
        """Start an episode: draw its misjudged zeros (``practice``: the noise multiplier)."""
        profile = self.profile
        self._rng = rng
        self.bias = Percept(
            slider=profile.slider_offset + rng.normal(0.0, profile.slider_bias * practice),
            slider_velocity=0.0,
            pendulum=profile.pendulum_offset + rng.normal(0.0, profile.pendulum_bias * practice),
            pendulum_velocity=0.0,
            ball=profile.ball_offset + rng.normal(0.0, profile.ball_bias * practice),
            ball_velocity=0.0)
        self._history: typing.Deque[Percept] = collections.deque(maxlen=self._history_length)
        # Unit-variance noise states of the channels, None until the first call of the
        # episode draws them from their stationary distribution.
        self._noise_state: typing.Optional[typing.List[float]] = None
        self._ball_cue = 0.0  # correction of the judged beam angle from the ball's rolling (rad)

    def remember(self, state, practice: float) -> None:
        """Perceive ``state`` now and keep it in the delay line."""
        self._history.append(self.perceive(state, practice))

    def perceive(self, state, practice: float) -> Percept:
        """Return what the person sees now: biased, noisy values (noise correlated in time)."""
        profile, rng, bias = self.profile, self._rng, self.bias
        noise_state = self._noise_state or [None] * PERCEPT_CHANNELS
        kept = self._memory
        values = []
        for channel, (position, velocity, noise, offset) in enumerate((
                (state.slider_position, state.slider_velocity, profile.slider_noise,
                 bias.slider),
                (state.pendulum_angle, state.pendulum_angular_velocity, profile.pendulum_noise,
                 bias.pendulum),
                (state.ball_position, state.ball_velocity, profile.ball_noise, bias.ball))):
            noise *= practice
            position_noise = advance(noise_state[2 * channel], kept, rng)
            velocity_noise = advance(noise_state[2 * channel + 1], kept, rng)
            noise_state[2 * channel:2 * channel + 2] = position_noise, velocity_noise
            values.append(position - offset + noise * position_noise)
            velocity_std = (profile.velocity_noise * practice * abs(velocity)
                            + noise / MOTION_INTEGRATION_TIME)
            values.append(velocity + velocity_std * velocity_noise)
        self._noise_state = noise_state
        percept = Percept(*values)
        if self._ball_cue_gain > 0.0:
            percept = self._with_ball_cue(percept)
        return percept

    def _with_ball_cue(self, percept: Percept) -> Percept:
        """Correct the judged beam angle slowly toward the tilt the rolling ball shows.

        A complementary filter: the eye's angle for fast changes, the ball's rolling speed
        (``-ball_speed_tilt * speed``: rolling east means the east end is low) for the slow
        part, so a misjudged horizontal fades over ``ball_cue_time`` while the ball rolls
        freely. A ball at or near an end stop shows nothing and leaves the correction as is.
        """
        if abs(percept.ball) < BALL_CUE_RANGE:
            tilt_from_ball = -self.profile.ball_speed_tilt * percept.ball_velocity
            self._ball_cue += self._ball_cue_gain * (tilt_from_ball - percept.pendulum
                                                     - self._ball_cue)
        return percept._replace(pendulum=percept.pendulum + self._ball_cue)

    def delayed(self, lag_steps: float) -> Percept:
        """Return the percept of ``lag_steps`` calls ago (interpolated)."""
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
