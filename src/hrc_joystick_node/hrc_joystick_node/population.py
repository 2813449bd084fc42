"""A population of simulated people around a profile; pure, no rclpy.

``sample_person(profile, seed)`` returns a :class:`~hrc_joystick_node.sim_human.HumanProfile`
for one person drawn from documented distributions around ``profile``: ten seeds give ten
different people, each reproducible from its seed. The profile is the population's typical
(median) person; seed ``-1`` by convention (:func:`person_or_profile`) means the profile itself.

Distributions (each value independent; positive quantities log-normal with the profile's value
as the median and the coefficient of variation below, clipped to the field's range; constant
perceptual offsets normal with the profile's per-episode bias as the standard deviation):

==========================  =====  ===========================================================
field(s)                    CV     source (fact) / choice
==========================  =====  ===========================================================
reaction_delay              0.15   Fact: between healthy adults, simple visual reaction time
                                   has a standard deviation of ~15 % of its mean (e.g. Der &
                                   Deary 2006, UK Health and Lifestyle Survey).
slider/pendulum/ball_noise, 0.3    Choice, of the order of the between-subject spread of
velocity_noise                     perceptual thresholds (e.g. orientation and speed
                                   discrimination vary by tens of percent between observers).
motor_noise,                0.3    Choice; motor variability differs between people by tens
motor_noise_floor                  of percent and predicts learning (Wu et al. 2014, Nature
                                   Neuroscience 17:312).
slider/pendulum_full_scale  0.2    Choice: operators' gains (crossover frequency) differ
(gains), lead_time                 between people by ~20 % (McRuer & Jex 1967 report ranges).
lapse_probability           0.5    Choice: lapse rates are strongly individual (Dinges &
                                   Powell 1985, PVT lapses differ several-fold).
fast/slow_learning_rate     0.4    Choice: adaptation rates differ widely between people
                                   (Wu et al. 2014).
learning_episodes           0.3    Choice: individual practice curves (Heathcote et al. 2000).
slider/pendulum/ball_offset normal Fact: a person's misjudgement of the middle is a stable
                                   individual bias (pseudoneglect, Jewell & McCourt 2000), and
                                   so is the horizontal (the subjective visual vertical of
                                   healthy adults lies within ~2 deg of the true one); its
                                   size here: the profile's per-episode bias std (choice), so
                                   offset and per-episode bias together are sqrt(2) times it
                                   (``paper``: 0.8 deg each, 1.1 deg together).
==========================  =====  ===========================================================

Everything else (physics-like constants of the person's strategy, retentions, fatigue) is
shared by the population. Seeds draw from their own random stream (``[seed, 2**40]``), apart
from the per-episode streams of :class:`~hrc_joystick_node.sim_human.SimulatedHuman`.
"""

import dataclasses
import math
import typing

import numpy

from hrc_common.params import spec_of, validate
from hrc_joystick_node.human_profile import HumanProfile

# Coefficient of variation (std / median) of each log-normally drawn field.
SPREAD: typing.Dict[str, float] = {
    'reaction_delay': 0.15,
    'slider_noise': 0.3, 'pendulum_noise': 0.3, 'ball_noise': 0.3, 'velocity_noise': 0.3,
    'motor_noise': 0.3, 'motor_noise_floor': 0.3,
    'slider_full_scale': 0.2, 'pendulum_full_scale': 0.2, 'lead_time': 0.2,
    'lapse_probability': 0.5,
    'fast_learning_rate': 0.4, 'slow_learning_rate': 0.4,
    'learning_episodes': 0.3,
}
# Constant offsets: field -> the per-episode bias field whose std they take.
OFFSETS: typing.Dict[str, str] = {'slider_offset': 'slider_bias',
                                  'pendulum_offset': 'pendulum_bias',
                                  'ball_offset': 'ball_bias'}
# Second seed word of the population stream (beyond any uint32 episode index).
POPULATION_STREAM = 1 << 40


def _range_of(name: str) -> typing.Tuple[float, float]:
    spec = spec_of({f.name: f for f in dataclasses.fields(HumanProfile)}[name])
    return (-math.inf if spec.low is None else spec.low,
            math.inf if spec.high is None else spec.high)


def sample_person(profile: HumanProfile, seed: int) -> HumanProfile:
    """Return the person number ``seed`` of the population around ``profile``."""
    if int(seed) < 0:
        raise ValueError(f'a person seed is >= 0, got {seed}')
    rng = numpy.random.default_rng([int(seed), POPULATION_STREAM])
    values = {}
    for name, cv in SPREAD.items():
        sigma = math.sqrt(math.log1p(cv * cv))
        low, high = _range_of(name)
        drawn = getattr(profile, name) * math.exp(rng.normal(0.0, sigma))
        values[name] = min(high, max(low, drawn))
    for name, bias_field in OFFSETS.items():
        low, high = _range_of(name)
        drawn = getattr(profile, name) + rng.normal(0.0, getattr(profile, bias_field))
        values[name] = min(high, max(low, drawn))
    person = dataclasses.replace(profile, description=f'person {seed} of the population '
                                 f'around: {profile.description}', **values)
    problems = validate(person)
    if problems:  # cannot happen with clipping; kept as a guard against new fields
        raise ValueError(f'person {seed}: {problems}')
    return person


def person_or_profile(profile: HumanProfile, seed: int) -> HumanProfile:
    """Return ``sample_person(profile, seed)``, or ``profile`` itself when ``seed`` is -1."""
    return profile if int(seed) == -1 else sample_person(profile, seed)
