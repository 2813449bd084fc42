"""A person who co-adapts to the partner's predictability (optional, pure, no rclpy).

An optional part of the simulated human, off in every profile but ``paper_co_adapting``.

A model to test, not a result to produce: its parameters are choices (below), none was tuned
toward the paper's outcome (case 5 failing).

The model (one call of :meth:`CoAdaptation.observe` per call of the person, every T s)
---------------------------------------------------------------------------------------
1. **An internal model of the partner, and its surprise.** The person predicts how the
   partner's degree of freedom will move next: a forward model of the partner's mean
   acceleration over the next ``partner_sample_time`` s from what the person sees of it (its
   position and velocity) and their own last stick command (the efference copy),
   ``a_hat = w . [v, x, u_own, 1]``, fitted by recursive least squares with forgetting over
   ``partner_model_time`` s. The person looks at that interval, not at every call: a person
   corrects intermittently, two to three times a second (Loram et al. 2011, J Physiol
   589:307), and a finite difference of the noisy percept at the 0.02 s call period would
   measure the person's own perception noise, not the partner. The surprise is the squared
   prediction error over a reference scale (``*_surprise_scale``: the error of this model
   beside a smooth partner, measured by ``bench/co_adaptation.py``), averaged over
   ``surprise_time`` s: ``U`` is about 1 beside a partner as predictable as a smooth person,
   and grows with a partner that explores. Only the excess ``X = max(0, U - 1)`` drives what
   follows.
2. **Stiffness** (``stiffening_rate``). Unpredictable dynamics make people stiffer: they
   co-contract, raising the impedance that rejects what they cannot predict, and relax it
   again when the disturbance is learned or gone. On the stick the impedance is the feedback
   gain of the hold: ``K`` multiplies the person's intent (more effort), with
   ``dK/dt = stiffening_rate * X - (K - 1) / stiffness_decay_time``, at most
   ``1 + stiffness_ceiling``.
3. **Slowing** (``slowing``). A broadband disturbance lowers the operator's bandwidth: the stick
   moves more slowly and follows the intent with a longer lag, the factor
   ``B = max(bandwidth_floor, 1 / (1 + slowing * X))`` on the slew rate, ``1 / B`` on the
   neuromuscular time. The floor keeps the loss within the published regression: the
   crossover frequency falls to about half, not to nothing.
4. **Frustration** (``frustration_rate``). A partner that keeps doing the unexpected erodes the
   person's trust; the frustration ``F`` in [0, 1) builds with the excess surprise and
   recovers with time (on task and at rest), ``dF/dt = frustration_rate * X * (1 - F) - F /
   frustration_recovery_time``; it makes the person noisier and less attentive: motor noise
   ``x (1 + frustration_noise * F)``, lapses ``x (1 + frustration_lapses * F)``.

Facts and choices
-----------------
* Fact: the CNS uses internal forward models that predict the consequence of motor commands
  (Wolpert, Ghahramani & Jordan 1995, Science 269:1880); physically interacting people
  estimate their partner's goal and use it (Takagi et al. 2017, Nature Human Behaviour
  1:0054).
* Fact: people stabilize unstable, unpredictable dynamics by learning a higher impedance
  (Burdet et al. 2001, Nature 414:446), and a simple rule explains it: co-contraction rises
  with the size of the error and decays otherwise, while the feedforward follows its sign
  (Franklin et al. 2008, J Neurosci 28:11165). hrc's two-rate feedforward adaptation
  (:mod:`hrc_joystick_node.adaptation`) is the signed half; the stiffness is the other.
* Fact: the human operator's crossover frequency regresses (falls) as the bandwidth of the
  forcing input rises (McRuer & Jex 1967, IEEE Trans HFE 8:231, "crossover regression").
* Fact: trust in automation follows its performance with inertia, falls with its faults and
  recovers gradually, and low trust changes how people operate (Lee & Moray 1992, Ergonomics
  35:1243; Lee & See 2004, Human Factors 46:50; Hoff & Bashir 2015, Human Factors 57:407).
* Modelling choices: that surprise (not the team's error) drives all three; the linear
  predictor and its features; ``X = max(0, U - 1)``; the first-order dynamics; that stiffness
  is a gain on the whole intent; that slowing acts on bandwidth rather than gain; that
  frustration acts through noise and lapses; and every number in ``params/sim_human.yaml``.
"""

import math
import typing

import numpy

from hrc_common.dof import ROTATION, TRANSLATION

# The partner's degree of freedom, seen from the person's.
PARTNER_DOF = {TRANSLATION: ROTATION, ROTATION: TRANSLATION}
FEATURES = 4  # partner velocity, partner position, the person's own last command, 1
PRIOR_VARIANCE = 100.0  # initial RLS covariance (weights start at 0, loosely held)


def co_adapting(profile) -> bool:
    """Return whether ``profile`` switches on any co-adaptation mechanism."""
    return (profile.stiffening_rate > 0.0 or profile.slowing > 0.0
            or profile.frustration_rate > 0.0)


class PartnerForwardModel:
    """Recursive least squares prediction of the partner's acceleration (see the module)."""

    def __init__(self, forgetting: float):
        self.forgetting = float(forgetting)  # per call, exp(-T / partner_model_time)
        self.weights = numpy.zeros(FEATURES)
        self.covariance = numpy.eye(FEATURES) * PRIOR_VARIANCE

    def predict(self, features: numpy.ndarray) -> float:
        """Return the predicted acceleration for ``features``."""
        return float(self.weights @ features)

    def learn(self, features: numpy.ndarray, observed: float) -> float:
        """Update on one observation; return its prediction error (before the update)."""
        error = observed - self.predict(features)
        gain_vector = self.covariance @ features
        gain_vector /= self.forgetting + features @ gain_vector
        self.weights += gain_vector * error
        self.covariance = (self.covariance - numpy.outer(gain_vector, features @ self.covariance)
                           ) / self.forgetting
        return error


class CoAdaptation:
    """One person's internal model of the partner, stiffness, slowing and frustration."""

    def __init__(self, profile, dof: str, control_period: float):
        self.profile = profile
        self.partner_dof = PARTNER_DOF[dof]
        self.period = float(control_period)
        self.scale = (profile.slider_surprise_scale if self.partner_dof == TRANSLATION
                      else profile.beam_surprise_scale)  # m/s^2 or rad/s^2
        # One look every sample_calls calls, sample_time s apart (at least one call).
        self.sample_calls = max(1, round(profile.partner_sample_time / self.period))
        self.sample_time = self.sample_calls * self.period
        self._calls = 0
        self.model = PartnerForwardModel(math.exp(-self.sample_time
                                                  / profile.partner_model_time))
        self._surprise_memory = math.exp(-self.sample_time / profile.surprise_time)
        self.unpredictability = 1.0  # U: mean squared surprise over surprise_time (1 = smooth)
        self.stiffness = 1.0  # K: gain on the intent
        self.frustration = 0.0  # F in [0, 1)
        self._last = None  # (features, partner velocity) of the previous call
        self._squared_errors, self._errors = 0.0, 0  # this episode's, for the calibration

    @property
    def excess_surprise(self) -> float:
        """X = max(0, U - 1): unpredictability beyond a smooth partner's."""
        return max(0.0, self.unpredictability - 1.0)

    @property
    def bandwidth_factor(self) -> float:
        """B in (0, 1]: the share of the slew rate left (slowing)."""
        profile = self.profile
        return max(profile.bandwidth_floor,
                   1.0 / (1.0 + profile.slowing * self.excess_surprise))

    @property
    def noise_factor(self) -> float:
        """Multiplier (>= 1) of the motor noise from frustration."""
        return 1.0 + self.profile.frustration_noise * self.frustration

    @property
    def lapse_factor(self) -> float:
        """Multiplier (>= 1) of the lapse probability from frustration."""
        return 1.0 + self.profile.frustration_lapses * self.frustration

    @property
    def rms_prediction_error(self) -> float:
        """Root mean squared prediction error of this episode (m/s^2 or rad/s^2)."""
        return (self._squared_errors / self._errors) ** 0.5 if self._errors else 0.0

    def start_episode(self) -> None:
        """Forget the last observation (a reset moves the bodies; the model is kept)."""
        self._last = None
        self._calls = 0
        self._squared_errors, self._errors = 0.0, 0

    def observe(self, partner_position: float, partner_velocity: float,
                own_command: float) -> None:
        """Count one call of the person; every ``sample_calls`` calls, look at the partner.

        A look updates the internal model, the surprise and every mechanism.
        """
        self._calls += 1
        if (self._calls - 1) % self.sample_calls:
            return
        features = numpy.array([partner_velocity, partner_position, own_command, 1.0])
        if self._last is not None:
            last_features, last_velocity = self._last
            acceleration = (partner_velocity - last_velocity) / self.sample_time
            error = self.model.learn(last_features, acceleration)
            self._squared_errors += error * error
            self._errors += 1
            squared = (error / self.scale) ** 2
            memory = self._surprise_memory
            self.unpredictability = memory * self.unpredictability + (1.0 - memory) * squared
            self._adapt(self.sample_time)
        self._last = (features, float(partner_velocity))

    def _adapt(self, seconds: float) -> None:
        """Advance stiffness and frustration by ``seconds`` on task."""
        profile, excess = self.profile, self.excess_surprise
        stiffness = self.stiffness + seconds * (
            profile.stiffening_rate * excess
            - (self.stiffness - 1.0) / profile.stiffness_decay_time)
        self.stiffness = min(1.0 + profile.stiffness_ceiling, max(1.0, stiffness))
        frustration = self.frustration + seconds * (
            profile.frustration_rate * excess * (1.0 - self.frustration)
            - self.frustration / profile.frustration_recovery_time)
        self.frustration = min(0.999, max(0.0, frustration))

    def rest(self, seconds: float) -> None:
        """Rest ``seconds`` (no partner seen): stiffness relaxes, frustration recovers."""
        if seconds > 0.0:
            profile = self.profile
            self.stiffness = 1.0 + (self.stiffness - 1.0) * math.exp(
                -seconds / profile.stiffness_decay_time)
            self.frustration *= math.exp(-seconds / profile.frustration_recovery_time)

    def snapshot(self) -> typing.Dict[str, float]:
        """Return the levels as plain values (to log them or carry a person over)."""
        return {'unpredictability': self.unpredictability, 'stiffness': self.stiffness,
                'frustration': self.frustration, 'weights': self.model.weights.tolist(),
                'covariance': self.model.covariance.tolist()}

    def restore(self, snapshot: typing.Dict[str, float]) -> None:
        """Take the levels of :meth:`snapshot`."""
        self.unpredictability = float(snapshot['unpredictability'])
        self.stiffness = float(snapshot['stiffness'])
        self.frustration = float(snapshot['frustration'])
        self.model.weights = numpy.array(snapshot['weights'], dtype=float)
        self.model.covariance = numpy.array(snapshot['covariance'], dtype=float)
