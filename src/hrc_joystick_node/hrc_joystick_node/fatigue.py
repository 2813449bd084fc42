"""Bounded, recovering fatigue of the simulated human on a simulation clock; pure, no rclpy.

The model
---------
A fatigue level ``F`` in [0, 1) grows with time on task and falls with rest, both as
exponential approaches (first-order kinetics)::

    on task for dt seconds:  F <- 1 - (1 - F) * exp(-dt / onset_time)        (toward 1)
    resting for dt seconds:  F <- F * exp(-dt / recovery_time)                (toward 0)

and scales the person's reaction delay, motor noise and lapse rate towards a ceiling::

    delay  * (1 + delay_ceiling * F)
    noise  * (1 + noise_ceiling * F)
    lapses * (1 + lapse_ceiling * F)

so no amount of time on task takes a person beyond ``1 + ceiling``. With episodes of ``W``
seconds on task separated by ``R`` seconds of rest, ``F`` settles where the two balance,
peaking at the end of each episode at
``F* = (1 - a) / (1 - a b)`` with ``a = exp(-W / onset_time)``, ``b = exp(-R / recovery_time)``
(:func:`steady_state_level`).

Facts and choices
-----------------
* Fact: sustained attention declines with time on task, the vigilance decrement. In
  Mackworth's clock test (1948) correct detections fell by 10-15 percentage points within the
  first 30 min and little more after; most of the decrement happens within the first 15-30
  min (reviews: Warm, Parasuraman & Matthews 2008, "Vigilance requires hard mental work and is
  stressful", Human Factors 50:433; Grier et al. 2003, Human Factors 45:349, who also found the
  workload of a vigil high). Reaction times lengthen and lapses become more frequent with time
  on task in the psychomotor vigilance task (Dinges & Powell 1985), by a few tens of percent
  in rested people, not by a factor of several. Rest breaks restore performance at least in
  part (e.g. Ross, Russell & Helton 2014; Ariga & Lleras 2011, brief diversions).
* Modelling choice: the saturating exponential form, a single level shared by delay, noise and
  lapses, the ceilings (+15 % delay, +30 % motor noise, x2 lapses by default), the onset time
  (20 min: most of the decrement within the first tens of minutes) and the recovery time (5
  min) are ours, chosen to reproduce those orders of magnitude; they are profile parameters.
* Time is the simulation's: the stamps of the states the person acts on, plus declared breaks
  between episodes; never wall time, so lockstep and in-process runs agree.
"""

import math
import typing


def steady_state_level(work_seconds: float, rest_seconds: float, onset_time: float,
                       recovery_time: float) -> float:
    """Return the level reached after many cycles of ``work_seconds`` on, ``rest_seconds`` off.

    The level at the end of each work period (its peak within a cycle).
    """
    grow = math.exp(-work_seconds / onset_time)
    keep = math.exp(-rest_seconds / recovery_time)
    if grow * keep >= 1.0:  # no work at all
        return 0.0
    return (1.0 - grow) / (1.0 - grow * keep)


class Fatigue:
    """The fatigue level of one person and the multipliers it implies (see the module)."""

    def __init__(self, onset_time: float, recovery_time: float, delay_ceiling: float,
                 noise_ceiling: float, lapse_ceiling: float, level: float = 0.0):
        if onset_time <= 0.0 or recovery_time <= 0.0:
            raise ValueError(f'fatigue time constants must be > 0 s, got onset {onset_time}, '
                             f'recovery {recovery_time}')
        self.onset_time = float(onset_time)  # s on task to go 1 - 1/e of the way to 1
        self.recovery_time = float(recovery_time)  # s of rest to fall to 1/e
        self.delay_ceiling = float(delay_ceiling)
        self.noise_ceiling = float(noise_ceiling)
        self.lapse_ceiling = float(lapse_ceiling)
        self.level = float(level)  # 0 = rested, towards 1 = as tired as this person gets
        self.seconds_on_task = 0.0
        self.seconds_rested = 0.0

    def work(self, seconds: float) -> None:
        """Spend ``seconds`` (simulation time) on task."""
        if seconds > 0.0:
            self.level = 1.0 - (1.0 - self.level) * math.exp(-seconds / self.onset_time)
            self.seconds_on_task += seconds

    def rest(self, seconds: float) -> None:
        """Rest for ``seconds`` (simulation time, or a declared break)."""
        if seconds > 0.0:
            self.level *= math.exp(-seconds / self.recovery_time)
            self.seconds_rested += seconds

    @property
    def delay_factor(self) -> float:
        """Multiplier (>= 1) of the reaction delay."""
        return 1.0 + self.delay_ceiling * self.level

    @property
    def noise_factor(self) -> float:
        """Multiplier (>= 1) of the motor noise."""
        return 1.0 + self.noise_ceiling * self.level

    @property
    def lapse_factor(self) -> float:
        """Multiplier (>= 1) of the lapse probability."""
        return 1.0 + self.lapse_ceiling * self.level

    def snapshot(self) -> typing.Dict[str, float]:
        """Return the state as plain values (to copy a person's tiredness, or log it)."""
        return {'level': self.level, 'seconds_on_task': self.seconds_on_task,
                'seconds_rested': self.seconds_rested}

    def restore(self, snapshot: typing.Dict[str, float]) -> None:
        """Take the state of :meth:`snapshot`."""
        self.level = float(snapshot['level'])
        self.seconds_on_task = float(snapshot['seconds_on_task'])
        self.seconds_rested = float(snapshot['seconds_rested'])
