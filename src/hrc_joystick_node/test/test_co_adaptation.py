"""The co-adapting person's mechanisms, each alone, against hand-made partners. Pure, seeded."""

import dataclasses
import math

import numpy
import pytest

from hrc_joystick_node.co_adaptation import co_adapting, CoAdaptation, PartnerForwardModel
from hrc_joystick_node.human_profile import load_profile, load_profiles
from hrc_joystick_node.sim_human import SimulatedHuman, StateView

PERIOD = 0.02  # s: the default human period
PROFILE = load_profile('paper_co_adapting')


def only(mechanism_field: str, **changes):
    """Return the co-adapting profile with only ``mechanism_field`` of the three on."""
    rates = {field: 0.0 for field in ('stiffening_rate', 'slowing', 'frustration_rate')
             if field != mechanism_field}
    return dataclasses.replace(PROFILE, **rates, **changes)


def partner_motion(seconds: float, noise: float, seed: int = 0):
    """Yield (position, velocity) of a partner swaying at 0.5 Hz plus acceleration noise."""
    rng = numpy.random.default_rng(seed)
    position, velocity = 0.0, 0.0
    for step in range(int(seconds / PERIOD)):
        time = step * PERIOD
        acceleration = -0.2 * math.sin(math.pi * time) - 2.0 * velocity - 4.0 * position
        acceleration += noise * rng.normal()
        velocity += acceleration * PERIOD
        position += velocity * PERIOD
        yield position, velocity


def watch(levels: CoAdaptation, seconds: float, noise: float, seed: int = 0) -> CoAdaptation:
    """Let ``levels`` watch the partner for ``seconds``; return it."""
    for position, velocity in partner_motion(seconds, noise, seed):
        levels.observe(position, velocity, 0.0)
    return levels


def test_the_forward_model_learns_a_linear_partner():
    rng = numpy.random.default_rng(1)
    true = numpy.array([-2.0, -4.0, 0.5, 0.1])
    model = PartnerForwardModel(forgetting=math.exp(-PERIOD / 10.0))
    errors = []
    for _ in range(500):
        features = numpy.append(rng.normal(size=3), 1.0)
        errors.append(abs(model.learn(features, float(true @ features))))
    # The prior (weights 0) is forgotten, not erased: within 1e-3 after 500 observations.
    assert numpy.allclose(model.weights, true, atol=1e-3)
    assert max(errors[-100:]) < 1e-3 < 0.1 < errors[0]


def test_a_smooth_partner_is_predictable_and_an_exploring_one_surprises():
    smooth = watch(CoAdaptation(only('stiffening_rate'), 'rotation', PERIOD), 40.0, 0.0)
    exploring = watch(CoAdaptation(only('stiffening_rate'), 'rotation', PERIOD), 40.0, 20.0)
    assert smooth.unpredictability < 1.0 and smooth.excess_surprise == 0.0
    assert exploring.unpredictability > 10.0


def test_stiffness_rises_with_surprise_within_its_ceiling_and_relaxes():
    levels = watch(CoAdaptation(only('stiffening_rate'), 'rotation', PERIOD), 40.0, 20.0)
    ceiling = 1.0 + PROFILE.stiffness_ceiling
    assert 1.0 + 0.7 * PROFILE.stiffness_ceiling < levels.stiffness <= ceiling
    assert levels.frustration == 0.0 and levels.bandwidth_factor == 1.0
    stiff = levels.stiffness
    levels.rest(PROFILE.stiffness_decay_time)  # one time constant: 1/e of the excess is left
    assert levels.stiffness - 1.0 == pytest.approx((stiff - 1.0) / math.e)


def test_slowing_narrows_the_bandwidth_only_while_the_partner_surprises():
    levels = watch(CoAdaptation(only('slowing'), 'rotation', PERIOD), 20.0, 20.0)
    # A partner this wild slows the person as far as the floor allows, no further.
    assert levels.excess_surprise > 10.0
    assert levels.bandwidth_factor == PROFILE.bandwidth_floor
    assert levels.stiffness == 1.0 and levels.frustration == 0.0
    watch(levels, 30.0, 0.0, seed=2)  # the partner is smooth again: U decays over seconds
    assert levels.bandwidth_factor > 0.95


def test_frustration_builds_with_surprise_and_recovers_at_rest():
    levels = watch(CoAdaptation(only('frustration_rate'), 'rotation', PERIOD), 40.0, 20.0)
    built = levels.frustration
    assert 0.3 < built < 1.0
    assert levels.noise_factor == pytest.approx(1.0 + PROFILE.frustration_noise * built)
    assert levels.lapse_factor == pytest.approx(1.0 + PROFILE.frustration_lapses * built)
    levels.rest(PROFILE.frustration_recovery_time)
    assert levels.frustration == pytest.approx(built / math.e)


def test_every_other_profile_has_no_co_adaptation_and_the_person_is_unchanged():
    profiles = load_profiles()
    assert [name for name, profile in profiles.items() if co_adapting(profile)] == [
        'paper_co_adapting']
    assert SimulatedHuman(profiles['paper'], 'rotation', control_period=PERIOD
                          ).co_adaptation is None


def person_commands(profile, noise: float, seconds: float = 20.0):
    """Return the commands of a person on rotation watching a swaying slider (hand-made)."""
    human = SimulatedHuman(profile, 'rotation', seed=3, control_period=PERIOD)
    commands = []
    for step, (position, velocity) in enumerate(partner_motion(seconds, noise)):
        state = StateView(step, step * PERIOD, position, velocity, 0.05, 0.0, 0.02, 0.0)
        commands.append(human.act(state, ['pendulum', 'ball']))
    return commands, human


def test_a_stiffer_person_pushes_harder_against_the_same_error():
    calm, _ = person_commands(alone_off(), 20.0)
    stiff, human = person_commands(only('stiffening_rate'), 20.0)
    gain = human.co_adaptation.stiffness
    assert gain > 1.0 + 0.7 * PROFILE.stiffness_ceiling
    pushed, calm_push = abs(numpy.mean(stiff[-100:])), abs(numpy.mean(calm[-100:]))
    assert pushed > (1.0 + 0.5 * (gain - 1.0)) * calm_push


def test_beside_a_smooth_partner_the_co_adapting_person_acts_as_the_paper_person():
    co_adapting_commands, human = person_commands(PROFILE, 0.0)
    paper_commands, _ = person_commands(alone_off(), 0.0)
    assert human.co_adaptation.excess_surprise == 0.0
    assert co_adapting_commands == paper_commands


def alone_off():
    """Return the co-adapting profile with every mechanism off (the paper person's numbers)."""
    return dataclasses.replace(PROFILE, stiffening_rate=0.0, slowing=0.0, frustration_rate=0.0)
