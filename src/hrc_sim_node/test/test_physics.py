"""Unit tests of the physics core (real PyBullet, no ROS)."""

from dataclasses import replace
import math

import numpy
import pytest

from hrc_common.params import ParameterError
from hrc_sim_node.body_geometry import body_poses
from hrc_sim_node.physics import JOINTS, PhysicsParams, PhysicsState, SliderPendulumBall

# Everything starts exactly in the middle, at rest: effects are measured from zero.
CENTRED = replace(PhysicsParams(), initial_slider_spread=0.0, initial_angle_spread=0.0,
                  initial_ball_spread=0.0)


@pytest.fixture
def sim():
    physics = SliderPendulumBall(CENTRED)
    yield physics
    physics.close()


def run(physics, commands, seed=0):
    """Reset, apply (force, torque) pairs and return the list of states (step 0 first)."""
    states = [physics.reset(seed=seed)]
    for force, torque in commands:
        states.append(physics.step(force, torque))
    return states


def set_configuration(physics, slider=0.0, angle=0.0, ball=0.0):
    """Put the bodies at the given positions, at rest (for tests only)."""
    for joint, position in zip(JOINTS, (slider, angle, ball)):
        physics._bullet.resetJointState(physics._body, joint, position, 0.0,
                                        physicsClientId=physics._client)


def test_defaults_give_200_steps_of_0_2_s_and_documented_units():
    params = PhysicsParams()
    assert params.control_period == 0.2
    assert params.steps_per_episode == 200
    assert params.rod_length == 0.2 and params.pendulum_length == 0.5


def test_zero_command_keeps_slider_and_pendulum_where_they_are(sim):
    # Gravity compensation: with the ball in the middle nothing moves (the unstable ball
    # equilibrium is exact here), so a released joystick leaves the system as it was.
    states = run(sim, [(0.0, 0.0)] * 25)
    last = states[-1]
    assert abs(last.slider_position) < 1e-6
    assert abs(last.pendulum_angle) < 1e-6
    assert abs(last.ball_position) < 1e-6


def test_without_compensation_the_slider_drops_and_the_beam_falls():
    physics = SliderPendulumBall(replace(CENTRED, gravity_compensation=False))
    states = run(physics, [(0.0, 0.0)] * 10)
    physics.close()
    assert states[-1].slider_position == pytest.approx(-0.1, abs=2e-3)  # bottom stop
    assert states[-1].pendulum_angle < -1.0


def test_no_input_from_a_random_start_is_slow_bounded_and_finite():
    physics = SliderPendulumBall()
    states = run(physics, [(0.0, 0.0)] * 200, seed=7)
    physics.close()
    first = states[0]
    for state in states:
        values = [getattr(state, name) for name in PhysicsState.__dataclass_fields__
                  if isinstance(getattr(state, name), float)]
        assert all(math.isfinite(value) for value in values)
        assert abs(state.slider_position) <= 0.1 + 1e-3
        assert abs(state.pendulum_angle) <= math.pi / 2 + 1e-3
        assert abs(state.ball_position) <= 0.25 + 1e-3
    # The slider only feels the beam's reaction: it stays within a few mm.
    assert max(abs(s.slider_position - first.slider_position) for s in states) < 0.01
    # The ball rolls to a stop; its weight tips the beam slowly (well under 1 rad/s).
    assert abs(states[-1].ball_position) == pytest.approx(0.25, abs=1e-3)
    assert max(abs(s.pendulum_angular_velocity) for s in states) < 0.5
    assert abs(states[5].pendulum_angle - first.pendulum_angle) < 0.5


def test_translation_turns_the_pendulum(sim):
    # Pushing the slider up presses the east end (the beam's centre of mass) down.
    up = run(sim, [(sim.params.max_force, 0.0)])[-1]
    down = run(sim, [(-sim.params.max_force, 0.0)])[-1]
    assert up.slider_position > 0.01
    assert up.pendulum_angle < -0.01
    assert down.pendulum_angle > 0.01


def test_rotation_moves_the_slider(sim):
    # Lifting the east end accelerates the beam's centre of mass up: the slider is pushed down.
    lift = run(sim, [(0.0, sim.params.max_torque)])[-1]
    lower = run(sim, [(0.0, -sim.params.max_torque)])[-1]
    assert lift.pendulum_angle > 0.05
    assert lift.slider_position < -0.002
    assert lower.slider_position > 0.002


def test_ball_is_more_sensitive_to_the_angle_than_to_the_slider(sim):
    # The same displacement in SI units (0.05 m vs 0.05 rad), then 1 s without input.
    sim.reset(seed=0)
    set_configuration(sim, angle=0.05)
    for _ in range(5):
        tilted = sim.step(0.0, 0.0)
    sim.reset(seed=0)
    set_configuration(sim, slider=0.05)
    for _ in range(5):
        shifted = sim.step(0.0, 0.0)
    assert abs(tilted.ball_position) > 0.05
    assert tilted.ball_position < 0  # east end up: the ball rolls west
    assert abs(shifted.ball_position) < 0.1 * abs(tilted.ball_position)

    # The same for the actions: two control steps of full rotation vs full translation.
    rotated = run(sim, [(0.0, sim.params.max_torque)] * 2 + [(0.0, 0.0)] * 3)[-1]
    translated = run(sim, [(sim.params.max_force, 0.0)] * 2 + [(0.0, 0.0)] * 3)[-1]
    assert abs(rotated.ball_position) > 3 * abs(translated.ball_position)
    assert abs(rotated.ball_position) > 0.05


def test_slider_stops_at_the_rod_ends(sim):
    up = run(sim, [(sim.params.max_force, 0.0)] * 15)
    assert up[-1].slider_position == pytest.approx(0.1, abs=1e-3)
    assert max(s.slider_position for s in up) <= 0.1 + 1e-3
    down = run(sim, [(-sim.params.max_force, 0.0)] * 15)
    assert down[-1].slider_position == pytest.approx(-0.1, abs=1e-3)
    assert min(s.slider_position for s in down) >= -0.1 - 1e-3


def test_ball_stops_at_the_pendulum_ends_and_the_hinge_at_its_limits(sim):
    lifted = run(sim, [(0.0, sim.params.max_torque)] * 15)
    assert lifted[-1].ball_position == pytest.approx(-0.25, abs=1e-3)
    assert min(s.ball_position for s in lifted) >= -0.25 - 1e-3
    assert lifted[-1].pendulum_angle == pytest.approx(math.pi / 2, abs=1e-2)
    assert max(s.pendulum_angle for s in lifted) <= math.pi / 2 + 1e-2
    lowered = run(sim, [(0.0, -sim.params.max_torque)] * 15)
    assert lowered[-1].ball_position == pytest.approx(0.25, abs=1e-3)
    assert max(s.ball_position for s in lowered) <= 0.25 + 1e-3
    assert lowered[-1].pendulum_angle == pytest.approx(-math.pi / 2, abs=1e-2)


def test_same_seed_same_episode_across_instances_and_resets():
    rng = numpy.random.default_rng(5)
    commands = [tuple(pair) for pair in rng.uniform(-1, 1, (60, 2)) * (2.0, 0.5)]
    first, second = SliderPendulumBall(), SliderPendulumBall()
    run_a = run(first, commands, seed=11)
    run(first, commands, seed=12)  # another episode in between
    run_b = run(first, commands, seed=11)
    run_c = run(second, commands, seed=11)
    other = run(second, commands, seed=12)
    first.close()
    second.close()
    assert run_a == run_b == run_c  # bit for bit
    assert run_a[0] != other[0]


def test_reset_without_seed_continues_the_seeded_sequence():
    one, two = SliderPendulumBall(), SliderPendulumBall()
    starts_one = [one.reset(seed=3)] + [one.reset() for _ in range(3)]
    starts_two = [two.reset(seed=3)] + [two.reset() for _ in range(3)]
    one.close()
    two.close()
    assert starts_one == starts_two
    assert len({state.slider_position for state in starts_one}) == 4
    params = PhysicsParams()
    for state in starts_one:
        assert abs(state.slider_position) <= params.initial_slider_spread
        assert abs(state.pendulum_angle) <= params.initial_angle_spread
        assert abs(state.ball_position) <= params.initial_ball_spread
        assert state.slider_velocity == state.ball_velocity == 0.0


@pytest.mark.parametrize('force, torque', [(math.nan, 0.0), (0.0, math.inf),
                                           (-math.inf, 0.0)])
def test_non_finite_commands_are_refused(sim, force, torque):
    before = sim.reset(seed=0)
    with pytest.raises(ValueError, match='finite'):
        sim.step(force, torque)
    assert sim.state == before  # nothing applied
    with pytest.raises(ValueError, match='finite'):
        sim.step_normalized(force, torque)


def test_commands_beyond_the_limits_are_clamped(sim):
    limits = sim.params.max_force, sim.params.max_torque
    clamped = run(sim, [(100.0, -50.0)] * 3)
    at_limit = run(sim, [(limits[0], -limits[1])] * 3)
    assert clamped == at_limit
    assert clamped[-1].applied_force == limits[0]
    assert clamped[-1].applied_torque == -limits[1]
    sim.reset(seed=0)
    state = sim.step_normalized(3.0, -0.5)
    assert state.applied_force == limits[0]
    assert state.applied_torque == pytest.approx(-0.5 * limits[1])


def test_episode_is_truncated_after_40_s_and_never_terminates(sim):
    states = run(sim, [(0.0, 0.0)] * 200)
    assert [s.truncated for s in states].index(True) == 200
    assert not any(s.terminated for s in states)
    assert states[-1].time == pytest.approx(40.0)
    with pytest.raises(RuntimeError, match='reset'):
        sim.step(0.0, 0.0)


def test_step_before_reset_is_an_error():
    physics = SliderPendulumBall()
    with pytest.raises(RuntimeError, match='reset'):
        physics.step(0.0, 0.0)
    physics.close()


def pd_team(state):
    """Return (translation, rotation) of a cascaded PD pair: ball -> target angle -> torque."""
    target_angle = 1.0 * state.ball_position + 0.5 * state.ball_velocity
    rotation = 2.0 * (target_angle - state.pendulum_angle) - 1.0 * state.pendulum_angular_velocity
    translation = -20.0 * state.slider_position - 2.0 * state.slider_velocity
    return float(numpy.clip(translation, -1, 1)), float(numpy.clip(rotation, -1, 1))


@pytest.mark.parametrize('delay_steps', [0, 1])
def test_the_limits_let_a_5_hz_controller_hold_every_subtask(delay_steps):
    # Evidence for the chosen limits: a simple controller acting every 0.2 s, even one that
    # reacts a whole control period late (as a person does), keeps the ball near the middle,
    # where zero input lets it hit an end stop.
    physics = SliderPendulumBall()
    errors = []
    for seed in range(3):
        state = physics.reset(seed=seed)
        pending = [(0.0, 0.0)] * delay_steps
        ball_error = []
        while not state.truncated:
            pending.append(pd_team(state))
            state = physics.step_normalized(*pending.pop(0))
            ball_error.append(abs(state.ball_position))
        errors.append((numpy.mean(ball_error), abs(state.slider_position),
                       abs(state.pendulum_angle)))
    physics.close()
    mean_ball, final_slider, final_angle = numpy.max(errors, axis=0)
    assert mean_ball < 0.03
    assert final_slider < 0.02
    assert final_angle < 0.1


def test_parameters_that_do_not_fit_together_are_rejected():
    with pytest.raises(ParameterError, match='not a multiple'):
        SliderPendulumBall(replace(PhysicsParams(), episode_duration=40.1))
    with pytest.raises(ParameterError, match='unstable'):
        SliderPendulumBall(replace(PhysicsParams(), ball_damping=50.0))
    with pytest.raises(ParameterError, match='half length'):
        SliderPendulumBall(replace(PhysicsParams(), initial_ball_spread=0.3))
    with pytest.raises(ParameterError, match='below the minimum'):
        SliderPendulumBall(replace(PhysicsParams(), max_force=-1.0))


def test_body_poses_match_pybullet(sim):
    sim.reset(seed=0)
    set_configuration(sim, slider=0.04, angle=0.3, ball=-0.1)
    state = sim.step(0.0, 0.0)
    poses = body_poses(state, sim.params)
    links = sim._bullet.getLinkStates(sim._body, JOINTS, computeForwardKinematics=True,
                                     physicsClientId=sim._client)
    # linkWorldPosition (index 0) is each link's centre of mass.
    assert poses['pendulum'][0] == pytest.approx(links[1][0], abs=1e-6)
    assert poses['ball'][0] == pytest.approx(links[2][0], abs=1e-6)
    assert poses['slider'][0][2] == pytest.approx(links[0][0][2], abs=1e-6)
    assert poses['pendulum'][1] == pytest.approx(links[1][1], abs=1e-6)


def test_render_shows_the_bodies_and_follows_the_state(sim):
    sim.reset(seed=0)
    level = sim.render(96, 64)
    assert level.shape == (64, 96, 3) and level.dtype == numpy.uint8
    assert len(numpy.unique(level.reshape(-1, 3), axis=0)) > 3  # not a blank frame
    set_configuration(sim, angle=1.0)
    tilted = sim.render(96, 64)
    assert numpy.abs(tilted.astype(int) - level.astype(int)).sum() > 1000


def test_several_instances_live_in_one_process():
    sims = [SliderPendulumBall() for _ in range(3)]
    states = [physics.reset(seed=1) for physics in sims]
    states = [physics.step(1.0, 0.1) for physics in sims]
    for physics in sims:
        physics.close()
    assert states[0] == states[1] == states[2]
