"""The simulated human's fatigue, adaptation to the partner, population and control profile."""

import dataclasses
import math
import time

import numpy
import pytest

from hrc_common.paths import params_dir
from hrc_joystick_node.adaptation import steady_state_compensation, TwoRateAdaptation
from hrc_joystick_node.fatigue import Fatigue, steady_state_level
from hrc_joystick_node.population import (OFFSETS, person_or_profile, sample_person, SPREAD)
from hrc_joystick_node.human_profile import load_profiles
from hrc_joystick_node.sim_human import SimulatedHuman, StateView

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
REPO_PROFILES = params_dir() / 'sim_human.yaml'
PROFILES = load_profiles(REPO_PROFILES)
STEPS = 200  # control steps of a 40 s episode at 0.2 s


STILL = StateView(0, 0.0, 0.01, 0.0, 0.1, 0.0, 0.02, 0.0)


def run_episodes(human, episodes, first_episode=0, stamps=False, episode_stride=1):
    """Let ``human`` act ``episodes`` episodes of STEPS-1 answered states on a still state.

    ``stamps``: pass the session clock as the graph does (one period per state, the last state
    of each episode unanswered); ``episode_stride`` > 1: the person sits out the episodes in
    between (their time passes on the clock).
    """
    period = human.control_period
    for index in range(episodes):
        episode = first_episode + index * episode_stride
        human.reset(episode)
        for step in range(STEPS - 1):
            now = (episode * STEPS + step) * period if stamps else None
            human.act(STILL, ['pendulum'], now=now)


# -- fatigue -----------------------------------------------------------------------------
def test_fatigue_is_bounded_after_300_episodes():
    # Was: 1 + fatigue_per_minute * minutes = a delay of 1.25 s and 5x the noise after 300
    # episodes (paper profile). Now it approaches a ceiling and the breaks pull it back.
    profile = PROFILES['paper']
    human = SimulatedHuman(profile, 'rotation', seed=0, control_period=CONTROL_PERIOD)
    run_episodes(human, 300)
    delay = profile.reaction_delay * human.fatigue.delay_factor
    assert delay <= profile.reaction_delay * (1.0 + profile.fatigue_delay_ceiling)
    assert delay < 0.3, f'delay after 300 episodes {delay:.3f} s'
    assert human.fatigue.noise_factor < 1.0 + profile.fatigue_noise_ceiling
    # ... and it settles where work and rest balance (the closed form of the module).
    expected = steady_state_level((STEPS - 1) * 0.2, profile.rest_between_episodes,
                                  profile.fatigue_onset_minutes * 60,
                                  profile.recovery_minutes * 60)
    assert human.fatigue.level == pytest.approx(expected, rel=1e-6)


def test_vigilance_decrement_is_a_few_tens_of_percent_over_tens_of_minutes():
    fatigue = Fatigue(20 * 60.0, 5 * 60.0, delay_ceiling=0.15, noise_ceiling=0.3,
                      lapse_ceiling=1.0)
    fatigue.work(30 * 60.0)  # half an hour without a break
    assert 1.1 < fatigue.noise_factor < 1.3
    assert 1.05 < fatigue.delay_factor < 1.15
    fatigue.work(600 * 60.0)  # ten hours: never beyond the ceiling
    assert fatigue.noise_factor == pytest.approx(1.3, abs=1e-6)
    assert fatigue.noise_factor <= 1.3


def test_breaks_restore_part_of_the_fatigue():
    tired = Fatigue(20 * 60.0, 5 * 60.0, 0.15, 0.3, 1.0)
    tired.work(40 * 60.0)
    before = tired.level
    tired.rest(5 * 60.0)  # one recovery time constant
    assert tired.level == pytest.approx(before / math.e)
    assert 0.0 < tired.level < before
    # The same work with breaks between the episodes leaves the person less tired.
    with_breaks = SimulatedHuman(PROFILES['paper'], 'rotation', control_period=CONTROL_PERIOD)
    no_breaks = SimulatedHuman(dataclasses.replace(PROFILES['paper'], rest_between_episodes=0),
                               'rotation', control_period=CONTROL_PERIOD)
    run_episodes(with_breaks, 40)
    run_episodes(no_breaks, 40)
    assert with_breaks.fatigue.level < 0.8 * no_breaks.fatigue.level
    assert with_breaks.fatigue.seconds_on_task == no_breaks.fatigue.seconds_on_task


def test_fatigue_runs_on_the_simulation_clock_not_the_wall_clock(monkeypatch):
    profile = PROFILES['paper']
    # The state stamps: episodes the person sits out are rest.
    continuous = SimulatedHuman(profile, 'rotation', seed=1, control_period=CONTROL_PERIOD)
    run_episodes(continuous, 20, stamps=True)
    sitting_out = SimulatedHuman(profile, 'rotation', seed=1, control_period=CONTROL_PERIOD)
    run_episodes(sitting_out, 20, stamps=True, episode_stride=3)
    assert continuous.fatigue.seconds_on_task == pytest.approx(
        sitting_out.fatigue.seconds_on_task)
    assert sitting_out.fatigue.level < 0.7 * continuous.fatigue.level
    # Stamps of consecutive states = the periods acted: the same person as without stamps
    # (plus the one period of the unanswered last state per episode, as rest).
    without_stamps = SimulatedHuman(profile, 'rotation', seed=1, control_period=CONTROL_PERIOD)
    run_episodes(without_stamps, 20)
    assert continuous.fatigue.level == pytest.approx(without_stamps.fatigue.level, rel=0.01)

    # No wall clock anywhere in the model: a run with every clock broken is the same run.
    def broken_clock():
        raise AssertionError('the simulated human read the wall clock')

    first = SimulatedHuman(profile, 'rotation', seed=2, control_period=CONTROL_PERIOD)
    run_episodes(first, 3, stamps=True)
    for name in ('time', 'monotonic', 'perf_counter', 'time_ns', 'monotonic_ns'):
        monkeypatch.setattr(time, name, broken_clock)
    second = SimulatedHuman(profile, 'rotation', seed=2, control_period=CONTROL_PERIOD)
    run_episodes(second, 3, stamps=True)
    assert second.snapshot() == first.snapshot()


# -- adaptation ----------------------------------------------------------------------------
def test_two_rate_model_learns_a_constant_disturbance_and_settles():
    adaptation = TwoRateAdaptation(0.6, 0.2, 0.97, 0.05)
    disturbance, errors = 1.0, []
    for _ in range(300):
        error = disturbance - adaptation.compensation
        errors.append(error)
        adaptation.update(error)
    assert errors[0] == 1.0
    assert errors[20] < 0.5 * errors[0]
    assert all(later <= earlier + 1e-12 for earlier, later in zip(errors, errors[1:]))
    expected = steady_state_compensation(disturbance, 1.0, 0.6, 0.2, 0.97, 0.05)
    assert adaptation.compensation == pytest.approx(expected, rel=1e-6)
    assert abs(adaptation.fast) < abs(adaptation.slow)  # the slow process holds it in the end
    # A partner that changes: the error jumps, then falls again; the compensation follows.
    jump = -disturbance - adaptation.compensation
    for _ in range(300):
        adaptation.update(-disturbance - adaptation.compensation)
    assert adaptation.compensation == pytest.approx(-expected, rel=1e-3)
    assert abs(-disturbance - adaptation.compensation) < 0.2 * abs(jump)


def disturbed_episodes(physics, profile, disturbances, seed=1):
    """Let the person hold the slider while the partner pushes it with a constant command.

    Return, per episode, the mean feedback correction the person had to make (the error as
    the person corrects it, stick units: what adaptation learns from) and the mean |slider
    height| over the first 10 s (m).
    """
    human = SimulatedHuman(profile, 'translation', seed=seed, control_period=CONTROL_PERIOD)
    corrections, early_errors = [], []
    for episode, disturbance in enumerate(disturbances):
        human.reset(episode)
        state = physics.reset(seed=0)
        early = []
        while not (state.truncated or state.terminated):
            command = human.act(state, ['slider'])
            state = physics.step_normalized(max(-1.0, min(1.0, command + disturbance)), 0.0)
            if len(early) < 50:
                early.append(abs(state.slider_position))
        corrections.append(human.episode_correction)
        early_errors.append(float(numpy.mean(early)))
    return numpy.array(corrections), numpy.array(early_errors)


@pytest.fixture(scope='module')
def physics():
    from hrc_sim_node.physics import SliderPendulumBall

    with SliderPendulumBall() as model:
        yield model


@pytest.mark.slow
def test_the_person_adapts_to_a_partner_that_leaves_a_constant_disturbance(physics):
    profile = PROFILES['paper']
    frozen = dataclasses.replace(profile, fast_learning_rate=0.0, slow_learning_rate=0.0)
    # The partner keeps pushing the slider up (30 % of full force) for 20 episodes, then
    # changes and pushes it down for 12.
    disturbances = [0.3] * 20 + [-0.3] * 12
    corrections, early = disturbed_episodes(physics, profile, disturbances)
    frozen_corrections, frozen_early = disturbed_episodes(physics, frozen, disturbances)
    # The error falls over the episodes and settles ...
    assert corrections[15:20].mean() < 0.6 * corrections[0]
    assert abs(corrections[15:20].mean() - corrections[10:15].mean()) < 0.1 * corrections[0]
    # ... where a person who does not adapt keeps correcting the whole disturbance.
    assert frozen_corrections[15:20].mean() > 0.9 * frozen_corrections[0]
    assert early[10:20].mean() < 0.8 * frozen_early[10:20].mean()
    # The partner changes: the error jumps, the person tracks it and it falls again.
    assert corrections[20] < -0.3
    assert abs(corrections[-3:].mean()) < 0.7 * abs(corrections[20])
    assert abs(frozen_corrections[-3:].mean()) > 0.9 * abs(frozen_corrections[20])


# -- population ----------------------------------------------------------------------------
def test_ten_seeds_are_ten_different_reproducible_people():
    profile = PROFILES['paper']
    people = [sample_person(profile, seed) for seed in range(10)]
    assert len({person.reaction_delay for person in people}) == 10
    assert len({person.pendulum_offset for person in people}) == 10
    assert [sample_person(profile, seed) for seed in range(10)] == people
    assert person_or_profile(profile, -1) is profile
    assert person_or_profile(profile, 4) == people[4]
    from hrc_common.params import validate
    for person in people:
        assert validate(person) == []
        assert person.slow_retention == profile.slow_retention
    # Different people act differently in the same episode of the same states.
    commands = []
    for person in people[:3]:
        human = SimulatedHuman(person, 'rotation', seed=0, control_period=CONTROL_PERIOD)
        commands.append([human.act(STILL, ['pendulum']) for _ in range(20)])
    assert commands[0] != commands[1] != commands[2]


def test_the_population_has_the_documented_distributions():
    profile = PROFILES['paper']
    people = [sample_person(profile, seed) for seed in range(2000)]
    for name, cv in SPREAD.items():
        values = numpy.array([getattr(person, name) for person in people])
        median = getattr(profile, name)
        assert numpy.median(values) == pytest.approx(median, rel=0.05), name
        spread = numpy.std(numpy.log(values))
        assert spread == pytest.approx(math.sqrt(math.log1p(cv * cv)), rel=0.1), name
    for name, bias_field in OFFSETS.items():
        values = numpy.array([getattr(person, name) for person in people])
        assert abs(values.mean()) < 0.1 * getattr(profile, bias_field), name
        assert values.std() == pytest.approx(getattr(profile, bias_field), rel=0.1), name


# -- the control profile -------------------------------------------------------------------
def test_the_asymmetry_is_the_judged_horizontal_and_the_control_removes_it():
    # The paper's person has the asymmetry where the paper's subjects reported it, in the
    # reference (the horizontal): the beam's bias is worse than the slider's relative to the
    # push scale; its momentary noise is not, so the control profile equalizes the bias only.
    paper, control = PROFILES['paper'], PROFILES['paper_symmetric']
    slider_bias = paper.slider_bias / paper.slider_full_scale
    assert paper.pendulum_bias / paper.pendulum_full_scale > 1.5 * slider_bias
    assert (paper.pendulum_noise / paper.pendulum_full_scale
            <= paper.slider_noise / paper.slider_full_scale)
    assert control.pendulum_bias / control.pendulum_full_scale == pytest.approx(slider_bias)
    differing = {field.name for field in dataclasses.fields(paper)
                 if getattr(paper, field.name) != getattr(control, field.name)}
    assert differing == {'description', 'pendulum_bias'}
