"""What the robot infers about its partner from the recent interaction. Pure (numpy).

A partner-aware observation (``partner_inference``): besides the state and the partner's
current action, the robot sees a model of the partner fitted to the last seconds of the
episode. The model predicts the partner's next action from what the partner saw and did:

    a_h(t) = theta . x(t - 1),   x = [B_y, P_z, S_x (normalized, as observed), a_h, 1]

fitted by recursive least squares with exponential forgetting (Ljung 1999, ch. 11: the
standard on-line estimator; written here because it is a few lines of numpy and no
well-kept library offers it per step without a model object per call). ``theta`` is a latent
of the partner's style in the spirit of LILI (Xie et al. 2020): how strongly they react to
the ball, the beam and the slider (their gains), how much of their last command they keep
(their smoothness, reaction lag), and their bias; the prediction of their next action is the
E3T idea (Yan et al. 2023: a partner-action predictor inside the policy); the residual's
spread is their noise and lapses. Two partners who differ in one trait get different
``theta`` within seconds (``test_partner_model.py``).

Choices: forgetting 0.95 per 0.2 s step (a memory of about 1 / (1 - 0.95) = 20 steps, 4 s);
the model restarts at each episode (the partner may be another person: the population of
partners first draws one per episode); features clipped to +-10 as the observation.
"""

import numpy as np

FORGETTING = 0.95          # per control step: a memory of ~20 steps (4 s at 0.2 s)
PRIOR_VARIANCE = 100.0     # of each weight before any data (a weak prior at 0)
REGRESSORS = 5             # ball, pendulum, slider, the partner's action, 1
# prediction, the five weights, the residual's standard deviation
FEATURE_SIZE = 1 + REGRESSORS + 1
FEATURE_NAMES = ('predicted_action', 'gain_ball', 'gain_pendulum', 'gain_slider',
                 'persistence', 'bias', 'residual_std')


class PartnerModel:
    """Recursive least squares of the partner's next action on what they saw and did."""

    def __init__(self, forgetting: float = FORGETTING):
        self.forgetting = float(forgetting)
        self.reset()

    def reset(self) -> None:
        """Forget the partner (a new episode: maybe another person)."""
        self.theta = np.zeros(REGRESSORS)
        self.covariance = np.eye(REGRESSORS) * PRIOR_VARIANCE
        self.previous = None            # x(t - 1)
        self.residual_power = 0.0       # forgetting-weighted mean squared residual
        self.weight = 0.0               # sum of the forgetting weights so far
        self.step = None                # the step of the last update

    def update(self, step: int, state_features, partner_action: float) -> np.ndarray:
        """Take the partner's action at ``step``; return the features of the model after it.

        ``state_features``: the normalized (B_y, P_z, S_x) the robot observes at ``step``;
        ``partner_action``: the partner's normalized action it observes there. A step already
        taken (the same step asked again, e.g. the final state's observation) changes nothing.
        """
        if self.step is not None and step <= self.step:
            return self.features()
        regressor = np.array([*state_features, partner_action, 1.0], dtype=float)
        if self.previous is not None:
            self._fit(self.previous, float(partner_action))
        self.previous = regressor
        self.step = int(step)
        return self.features()

    def _fit(self, regressor: np.ndarray, target: float) -> None:
        """One recursive least-squares step with forgetting (gain, weights, covariance)."""
        covariance_x = self.covariance @ regressor
        gain = covariance_x / (self.forgetting + regressor @ covariance_x)
        residual = target - self.theta @ regressor
        self.theta = self.theta + gain * residual
        self.covariance = (self.covariance - np.outer(gain, covariance_x)) / self.forgetting
        self.weight = self.forgetting * self.weight + 1.0
        self.residual_power += (residual * residual - self.residual_power) / self.weight

    def predict(self) -> float:
        """Return the predicted next action of the partner (0 before any step)."""
        return float(self.theta @ self.previous) if self.previous is not None else 0.0

    def features(self) -> np.ndarray:
        """Return [predicted next action, the five weights, residual std] (clipped to +-10)."""
        values = np.concatenate([[self.predict()], self.theta, [np.sqrt(self.residual_power)]])
        return np.clip(values, -10.0, 10.0).astype(np.float32)
