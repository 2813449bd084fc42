"""The simulated human: profiles, determinism, and holding its subtask on the real physics."""

import dataclasses
import math
import re

import numpy
import pytest

from hrc_common.paths import params_dir
from hrc_common.params import ParameterError
from hrc_joystick_node.evaluation import human_episode, run_episode
from hrc_joystick_node.human_profile import (HumanProfile, load_profile, load_profiles,
                                             RETIRED_PROFILES)
from hrc_joystick_node.sim_human import normalize_subtasks, SimulatedHuman

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
REPO_PROFILES = params_dir() / 'sim_human.yaml'
PROFILES = load_profiles(REPO_PROFILES)
SEEDS = range(4)  # initial states and people per measurement: 4 episodes of 40 s


@pytest.fixture(scope='module')
def physics():
    from hrc_sim_node.physics import SliderPendulumBall

    with SliderPendulumBall() as model:
        yield model


def test_the_profiles_exist_and_are_valid():
    assert {'novice', 'skilled', 'paper', 'paper_symmetric', 'paper_co_adapting'} <= set(PROFILES)
    for name, profile in PROFILES.items():
        assert profile.description, f'{name} has no description'
        if '_symmetric' in name:
            continue  # the control profiles (test_human_model.py)
        # The paper's observation: the beam angle is judged worse than the slider height, as
        # seen on the monitor: a misjudged angle moves the end of the 0.5 m beam this far (m).
        # The misjudged reference (the horizontal) more than twice; the momentary noise worse
        # on the screen (`paper`: 5 mm at the beam's end against 3 mm; the other people more
        # than twice; human_profile.py, "The paper's person").
        assert profile.pendulum_bias * 0.5 > 2 * profile.slider_bias, name
        assert profile.pendulum_noise * 0.5 > profile.slider_noise, name
        if not name.startswith('paper'):
            assert profile.pendulum_noise * 0.5 > 2 * profile.slider_noise, name


def test_installed_profiles_are_the_repository_ones():
    assert load_profiles() == PROFILES


def test_bad_profiles_are_refused_with_the_reason(tmp_path):
    path = tmp_path / 'profiles.yaml'
    path.write_text('profiles:\n  bad:\n    reaction_delay: -1.0\n    mood: grumpy\n')
    with pytest.raises(ParameterError, match="profile 'bad'.*mood"):
        load_profiles(path)
    path.write_text('profiles:\n  bad:\n    reaction_delay: -1.0\n')
    with pytest.raises(ParameterError, match='reaction_delay: -1.0 is below the minimum'):
        load_profiles(path)
    path.write_text('people: {}\n')
    with pytest.raises(ParameterError, match='profiles'):
        load_profiles(path)
    with pytest.raises(ParameterError, match="unknown simulated-human profile 'expert'"):
        load_profile('expert', REPO_PROFILES)


@pytest.mark.parametrize('name', sorted(RETIRED_PROFILES))
def test_a_retired_profile_is_refused_with_the_commit_that_has_it(name):
    assert name not in PROFILES
    commit, (before, earlier_name) = RETIRED_PROFILES[name]
    with pytest.raises(ParameterError) as refused:
        load_profile(name, REPO_PROFILES)
    message = str(refused.value)
    assert f"profile '{name}' was retired; it lives at git {commit}" in message, message
    assert f"'{earlier_name}' at git {before}" in message, message
    # The human node's parameters say the same (human_core.resolve_profile).
    from hrc_joystick_node.human_core import HumanCore, HumanParams
    with pytest.raises(ParameterError, match=f"profile: simulated-human profile '{name}' was "
                       f'retired; it lives at git {commit}'):
        HumanCore(HumanParams(input='sim', profile=name), PROFILES)


def test_at_most_five_profiles_none_versioned():
    # novice, skilled, paper and its two controls (symmetric perception; co-adapting).
    assert len(PROFILES) <= 5, sorted(PROFILES)
    assert not [name for name in PROFILES if re.search(r'_v[0-9]+$', name)], sorted(PROFILES)


def test_subtask_ids_and_aliases():
    assert normalize_subtasks(['T2_2', 'ball', 'ball', 'juggle']) == (['pendulum', 'ball'],
                                                                     ['juggle'])


def states_of(physics, seed, steps=60):
    """Return a fixed state sequence (zero action) to feed people with."""
    states = [physics.reset(seed=seed)]
    for _ in range(steps - 1):
        states.append(physics.step_normalized(0.0, 0.0))
    return states


def commands(profile, dof, seed, states, subtasks, episode=0):
    human = SimulatedHuman(profile, dof, seed=seed, control_period=CONTROL_PERIOD)
    human.reset(episode)
    return [human.act(state, subtasks) for state in states]


def test_deterministic_with_a_seed_and_different_across_seeds(physics):
    states = states_of(physics, seed=5)
    profile = PROFILES['paper']
    first = commands(profile, 'rotation', 7, states, ['pendulum'])
    assert commands(profile, 'rotation', 7, states, ['pendulum']) == first
    assert commands(profile, 'rotation', 8, states, ['pendulum']) != first
    assert commands(profile, 'rotation', 7, states, ['pendulum'], episode=1) != first
    assert all(-1.0 <= value <= 1.0 for value in first)
    # An episode reproduces from (seed, episode) whatever the person did before.
    human = SimulatedHuman(profile, 'rotation', seed=7, control_period=CONTROL_PERIOD)
    human.reset(3)
    [human.act(state, ['pendulum']) for state in states]
    human.reset(0)
    assert human.practiced_episodes == 1
    person_state = human.snapshot()
    again = [human.act(state, ['pendulum']) for state in states]
    # Another instance in the same state (practice, fatigue, adaptation) acts the same.
    fresh = SimulatedHuman(profile, 'rotation', seed=7, control_period=CONTROL_PERIOD)
    fresh.restore(person_state)
    fresh.reset(0)
    assert again == [fresh.act(state, ['pendulum']) for state in states]
    # ... and one that did not practice, tire and adapt does not.
    assert again != commands(profile, 'rotation', 7, states, ['pendulum'])


def test_nothing_in_reach_means_no_action(physics):
    states = states_of(physics, seed=1, steps=20)
    quiet = dataclasses.replace(PROFILES['skilled'], motor_noise_floor=0.0)
    assert set(commands(quiet, 'translation', 0, states, ['pendulum'])) == {0.0}
    assert set(commands(quiet, 'rotation', 0, states, [])) == {0.0}


def test_learning_curve_moves_the_right_way():
    profile = PROFILES['novice']
    human = SimulatedHuman(profile, 'translation', seed=0, control_period=CONTROL_PERIOD)
    assert human.practice_factor == pytest.approx(profile.untrained_factor)
    assert SimulatedHuman(profile, 'translation', practiced_episodes=30,
                          control_period=CONTROL_PERIOD).practice_factor < 1.1
    assert human.fatigue_factor == 1.0


def mean_error(physics, subtask, dof, seeds, profile=None, subtasks=None):
    errors = []
    for seed in seeds:
        if profile is None:
            errors.append(run_episode(physics, dof, seed).errors[subtask])
        else:
            human = SimulatedHuman(profile, dof, seed=seed, control_period=CONTROL_PERIOD)
            errors.append(human_episode(physics, human, 0, seed, subtasks).errors[subtask])
    return float(numpy.mean(errors))


@pytest.fixture(scope='module')
def zero_action_error(physics):
    """Return {(subtask, dof): mean error with nobody acting}, each measured once per module.

    The same for every profile (the episodes of SEEDS with a zero action are deterministic),
    so the profiles' tests share it instead of running the same episodes again.
    """
    errors = {}

    def measure(subtask, dof):
        if (subtask, dof) not in errors:
            errors[subtask, dof] = mean_error(physics, subtask, dof, SEEDS)
        return errors[subtask, dof]
    return measure


@pytest.mark.parametrize('name', sorted(PROFILES))
@pytest.mark.parametrize('dof, subtask', [('translation', 'slider'), ('rotation', 'pendulum')])
def test_holds_its_own_subtask_better_than_zero_action(physics, zero_action_error, name, dof,
                                                       subtask):
    # The robot does nothing; first episode of a new person (the hardest case of the curve).
    zero = zero_action_error(subtask, dof)
    held = mean_error(physics, subtask, dof, SEEDS, PROFILES[name], [subtask])
    assert held < 0.75 * zero, f'{name} on {subtask}: {held:.4f} vs zero action {zero:.4f}'


def test_a_skilled_rotation_actor_also_holds_the_ball(physics):
    profile = PROFILES['skilled']
    level2 = mean_error(physics, 'ball', 'rotation', SEEDS, profile, ['pendulum'])
    with_ball = mean_error(physics, 'ball', 'rotation', SEEDS, profile, ['pendulum', 'ball'])
    assert with_ball < 0.6 * level2, f'ball error {with_ball:.4f} vs {level2:.4f} without'


def test_translation_actor_nudges_the_beam_through_the_coupling(physics):
    # Holding the ball, the translation actor pushes the slider up when the beam is above the
    # angle the ball needs (up-acceleration presses the east end down): check the sign.
    state = physics.reset(seed=0)
    quiet = dataclasses.replace(PROFILES['skilled'], motor_noise_floor=0.0, slider_noise=0.0,
                                slider_bias=0.0, pendulum_noise=0.0, pendulum_bias=0.0,
                                ball_noise=0.0, ball_bias=0.0, lapse_probability=0.0)
    tilted = dataclasses.replace(state, slider_position=0.0, pendulum_angle=0.3,
                                 ball_position=0.0)
    human = SimulatedHuman(quiet, 'translation', seed=0, control_period=CONTROL_PERIOD)
    assert human.act(tilted, ['slider', 'ball']) > 0.0
    human.reset(1)
    assert human.act(tilted, ['slider']) == 0.0


def test_profile_defaults_are_valid():
    from hrc_common.params import validate

    assert validate(HumanProfile()) == []


# -- a person grounded in tilt perception, the same at any call period -------------------------
def synthetic_states(steps=200, period=0.2):
    """Return a fixed, physics-free state sequence (smooth sines on every quantity)."""
    import math
    from hrc_joystick_node.sim_human import StateView

    states = []
    for step in range(steps):
        time = step * period
        states.append(StateView(
            step, time, 0.03 * math.sin(0.7 * time), 0.021 * math.cos(0.7 * time),
            0.1 * math.sin(1.3 * time + 0.4), 0.13 * math.cos(1.3 * time + 0.4),
            0.05 * math.sin(0.5 * time + 1.0), 0.025 * math.cos(0.5 * time + 1.0)))
    return states


def test_the_current_profiles_judge_the_beam_within_human_ranges():
    # Subjective visual vertical of healthy adults: within ~2 deg, within-person SD ~1 deg.
    # The person's total misjudgement of the horizontal (the per-episode bias and a
    # population offset of the same SD) and the noise stay within 2 deg.
    two_degrees = math.radians(2.0)

    def within(profile):
        return (profile.pendulum_noise <= two_degrees
                and math.sqrt(2.0) * profile.pendulum_bias <= two_degrees)

    # (the earlier paper person, 4 deg of noise and 3.4 deg of bias, was outside)
    assert not within(dataclasses.replace(PROFILES['paper'], pendulum_noise=0.07,
                                          pendulum_bias=0.06))
    for name, profile in PROFILES.items():
        assert within(profile), name
        assert profile.perception_noise_time > 0.0 and profile.motor_noise_time > 0.0
        assert profile.lapse_duration > 0.0 and profile.ball_cue_time > 0.0


def quiet_profile(**changes):
    """Return the skilled person with every noise, bias, lapse and fatigue off, then changes."""
    silent = dict(slider_noise=0.0, pendulum_noise=0.0, ball_noise=0.0, slider_bias=0.0,
                  pendulum_bias=0.0, ball_bias=0.0, velocity_noise=0.0, motor_noise=0.0,
                  motor_noise_floor=0.0, lapse_probability=0.0, untrained_factor=1.0,
                  fatigue_delay_ceiling=0.0, fatigue_noise_ceiling=0.0, fatigue_lapse_ceiling=0.0)
    silent.update(changes)
    return dataclasses.replace(PROFILES['skilled'], **silent)


def lag_correlation(values, lag):
    values = numpy.asarray(values) - numpy.mean(values)
    return float(numpy.mean(values[:-lag] * values[lag:]) / numpy.var(values))


@pytest.mark.parametrize('period', [0.2, 0.02])
def test_motor_noise_is_one_process_in_seconds_at_any_call_period(period):
    # Nothing in reach: the command is the motor noise floor alone.
    profile = quiet_profile(motor_noise_floor=0.05, motor_noise_time=0.1)
    human = SimulatedHuman(profile, 'rotation', seed=0, control_period=period)
    still = synthetic_states(1)[0]
    # 1000 s: ~5000 independent samples of a 0.1 s process (std within ~1 %, the lag
    # correlation within ~0.015 of its value: both well inside the tolerances)
    commands = [human.act(still, []) for _ in range(int(round(1000.0 / period)))]
    assert numpy.std(commands) == pytest.approx(0.05, rel=0.05)
    # The correlation over 0.2 s is exp(-0.2 / 0.1) at both periods: the same process.
    calls = int(round(0.2 / period))
    assert lag_correlation(commands, calls) == pytest.approx(math.exp(-2.0), abs=0.04)
    # Correlation time 0: fresh noise at every call, uncorrelated even 0.02 s apart.
    white = SimulatedHuman(dataclasses.replace(profile, motor_noise_time=0.0), 'rotation',
                           seed=0, control_period=period)
    commands = [white.act(still, []) for _ in range(20000)]
    assert abs(lag_correlation(commands, 1)) < 0.03


@pytest.mark.parametrize('period', [0.2, 0.02])
def test_perception_noise_is_correlated_over_its_time_constant(period):
    profile = quiet_profile(pendulum_noise=0.02, perception_noise_time=0.5, ball_cue_time=0.0)
    human = SimulatedHuman(profile, 'rotation', seed=1, control_period=period)
    still = synthetic_states(1)[0]
    seen = [human.perception.perceive(still, 1.0).pendulum - still.pendulum_angle
            for _ in range(int(round(4000.0 / period)))]
    assert numpy.std(seen) == pytest.approx(0.02, rel=0.08)
    calls = int(round(0.4 / period))  # 0.4 s apart: exp(-0.4 / 0.5) at both periods
    assert lag_correlation(seen, calls) == pytest.approx(math.exp(-0.8), abs=0.05)


@pytest.mark.parametrize('period', [0.2, 0.02])
def test_lapses_fill_their_share_of_the_time_and_last_their_duration(period):
    profile = quiet_profile(lapse_probability=0.05, lapse_duration=0.2)
    human = SimulatedHuman(profile, 'rotation', seed=2, control_period=period)
    rng = numpy.random.default_rng(0)
    # 5000 s: ~1250 lapses (their share and mean length within ~3 %, tolerance 15 %)
    lapsed = [human._lapsed(0.05, rng.random()) for _ in range(int(round(5000.0 / period)))]
    assert numpy.mean(lapsed) == pytest.approx(0.05, rel=0.15)
    starts = sum(1 for before, now in zip([False] + lapsed, lapsed) if now and not before)
    assert sum(lapsed) * period / starts == pytest.approx(0.2, rel=0.15)


@pytest.mark.parametrize('cue_time, judged_tilt', [(0.0, 0.05 - 0.03), (2.0, 0.05)])
def test_the_rolling_ball_corrects_a_misjudged_horizontal(cue_time, judged_tilt):
    from hrc_joystick_node.sim_human import StateView

    # The beam is tilted 0.05 rad (east end up), the ball rolls west at the speed that tilt
    # gives; the person misjudges the horizontal by 0.03 rad.
    profile = quiet_profile(pendulum_offset=0.03, ball_cue_time=cue_time,
                            ball_speed_tilt=0.2)
    human = SimulatedHuman(profile, 'rotation', seed=0, control_period=0.02)
    rolling = StateView(0, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0, -0.05 / 0.2)
    for _ in range(1000):  # 20 s, ten cue time constants
        percept = human.perception.perceive(rolling, 1.0)
    assert percept.pendulum == pytest.approx(judged_tilt, abs=1e-3)
    # A ball resting at an end stop says nothing: the correction stays where it was.
    at_stop = rolling._replace(ball_position=0.25, ball_velocity=0.0)
    assert human.perception.perceive(at_stop, 1.0).pendulum == pytest.approx(judged_tilt, abs=1e-3)
