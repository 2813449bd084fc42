"""Trial-by-trial adaptation of the simulated human to its partner; pure, no rclpy.

The model
---------
A two-rate linear state-space model of motor adaptation (Smith, Ghazizadeh & Shadmehr 2006,
PLoS Biology 4:e179; the single-rate form: Thoroughman & Shadmehr 2000, Nature 407:742). The
person carries a feedforward compensation ``x = x_fast + x_slow`` (here: a steady stick offset,
in normalized command units, added against the error the team leaves on the person's own
subtask) and after each trial ``n`` (an episode the person took part in) updates it from the
error ``e_n`` they experienced::

    x_fast <- A_fast * x_fast + B_fast * e_n
    x_slow <- A_slow * x_slow + B_slow * e_n       with A_fast < A_slow, B_fast > B_slow

The fast process learns quickly and forgets quickly, the slow one learns slowly and retains.
With a constant error source ``d`` that the compensation cancels (``e_n = g (d - x_n)``) the
compensation converges geometrically to ``x* = d * S / (1 + S)``, ``S = g (B_f / (1 - A_f) +
B_s / (1 - A_s))`` (:func:`steady_state_compensation`), so the error falls and settles at a
residual ``d / (1 + S)``; when the partner changes, the error jumps and the person re-adapts.

Facts and choices
-----------------
* Fact: the two-rate model with fast retention well below 1 and slow retention close to 1
  (about 0.99 per trial) describes adaptation, savings and spontaneous recovery in reaching
  (Smith et al. 2006) and learning trial by trial from the last error describes force-field
  adaptation (Thoroughman & Shadmehr 2000).
* Fact: a feedforward command can be learned from the feedback command that corrected the
  error (feedback-error learning, Kawato, Furukawa & Suzuki 1987, Biological Cybernetics
  57:169); the feedback command is the error as the controller expresses it.
* Modelling choice: what is adapted (a steady feedforward offset on the person's own degree of
  freedom), the error signal (the mean over the episode of the person's feedback correction on
  their own level-2 subtask, in stick units: the proportional, derivative and integral parts of
  the hold, which with a constant disturbance ``d`` equals ``d - x``, so ``g`` is about 1), and
  the per-episode rates (an episode is 40 s of continuous control, not one reach: the default
  slow retention 0.97 and learning rates 0.2 / 0.05 make a partner's steady push mostly
  compensated within about ten episodes). Individual differences in the rates are drawn by
  :mod:`hrc_joystick_node.population`.
"""

import typing


def steady_state_compensation(disturbance: float, error_gain: float, fast_retention: float,
                              fast_rate: float, slow_retention: float,
                              slow_rate: float) -> float:
    """Return the compensation learned against ``disturbance`` (see the module docstring)."""
    sensitivity = error_gain * (fast_rate / (1.0 - fast_retention)
                                + slow_rate / (1.0 - slow_retention))
    return disturbance * sensitivity / (1.0 + sensitivity)


class TwoRateAdaptation:
    """The fast and slow states of one person's adaptation (see the module docstring)."""

    def __init__(self, fast_retention: float, fast_rate: float, slow_retention: float,
                 slow_rate: float):
        for name, value in (('fast_retention', fast_retention),
                            ('slow_retention', slow_retention)):
            if not 0.0 <= value < 1.0:
                raise ValueError(f'{name} must be in [0, 1), got {value}')
        self.fast_retention = float(fast_retention)
        self.fast_rate = float(fast_rate)
        self.slow_retention = float(slow_retention)
        self.slow_rate = float(slow_rate)
        self.fast = 0.0
        self.slow = 0.0
        self.trials = 0

    @property
    def compensation(self) -> float:
        """The learned feedforward (normalized command units, subtracted from the push)."""
        return self.fast + self.slow

    def update(self, error: float) -> None:
        """Learn from the error of one trial (normalized command units)."""
        self.fast = self.fast_retention * self.fast + self.fast_rate * error
        self.slow = self.slow_retention * self.slow + self.slow_rate * error
        self.trials += 1

    def snapshot(self) -> typing.Dict[str, float]:
        """Return the state as plain values."""
        return {'fast': self.fast, 'slow': self.slow, 'trials': self.trials}

    def restore(self, snapshot: typing.Dict[str, float]) -> None:
        """Take the state of :meth:`snapshot`."""
        self.fast = float(snapshot['fast'])
        self.slow = float(snapshot['slow'])
        self.trials = int(snapshot['trials'])
