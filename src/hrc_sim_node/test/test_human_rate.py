"""The human's command at its own rate: physics slices, protocol slices, the stepper.

Pure cores (PyBullet, no ROS). A person's command that changes within a control period must
change the physics within that period; with ``human_period = control_period`` everything is as
before human slices existed; the commands recorded in the period's state are those applied.
"""

from types import SimpleNamespace

from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings, StepProtocol
from hrc_sim_node.stepper import SimStepper
import pytest

SLICED = PhysicsParams(human_period=0.02)
HELD = PhysicsParams(human_period=0.2)
POSITIONS = ('slider_position', 'slider_velocity', 'pendulum_angle',
             'pendulum_angular_velocity', 'ball_position', 'ball_velocity')


def wrench(force_z=0.0, torque_x=0.0):
    """Return a Wrench-like object."""
    return SimpleNamespace(force=SimpleNamespace(x=0.0, y=0.0, z=force_z),
                           torque=SimpleNamespace(x=torque_x, y=0.0, z=0.0))


def positions(state) -> tuple:
    return tuple(getattr(state, name) for name in POSITIONS)


def test_the_period_split_must_fit_the_substeps():
    assert SLICED.human_slices == 10 and SLICED.substeps_per_slice == 2
    assert HELD.human_slices == 1 and HELD.substeps_per_slice == 20
    problems = PhysicsParams(human_period=0.03).check()
    assert any('not a whole multiple of human_period' in reason for reason in problems)
    problems = PhysicsParams(human_period=0.05, substeps=10).check()
    assert any('cannot be split into 4 equal human slices' in reason for reason in problems)
    problems = PhysicsParams(human_period=0.4).check()
    assert any('exceeds control_period' in reason for reason in problems)


def test_slices_of_one_held_command_equal_one_whole_period_bit_for_bit():
    with SliderPendulumBall(SLICED) as sliced, SliderPendulumBall(SLICED) as whole:
        sliced.reset(seed=3)
        whole.reset(seed=3)
        for _ in range(5):
            for _ in range(SLICED.human_slices):
                sliced.advance(0.7, -0.2, SLICED.substeps_per_slice)
            by_slices = sliced.finish_period()
            at_once = whole.step(0.7, -0.2)
            assert by_slices == at_once


def test_a_command_changing_mid_period_changes_the_physics_within_the_period():
    with SliderPendulumBall(SLICED) as held, SliderPendulumBall(SLICED) as changed:
        held.reset(seed=1)
        changed.reset(seed=1)
        for slice_index in range(SLICED.human_slices):
            torque = 0.4 if slice_index < 5 else -0.4
            middle = changed.advance(0.0, torque, SLICED.substeps_per_slice)
            reference = held.advance(0.0, 0.4, SLICED.substeps_per_slice)
            if slice_index >= 5:
                assert middle.pendulum_angular_velocity < reference.pendulum_angular_velocity
            assert middle.step == 0 and middle.time == pytest.approx(
                (slice_index + 1) * 0.02)
        end_changed, end_held = changed.finish_period(), held.finish_period()
    assert end_changed.pendulum_angle < end_held.pendulum_angle
    # What the period reports as applied: the time-weighted mean (0 here), the held value.
    assert end_changed.applied_torque == pytest.approx(0.0, abs=1e-12)
    assert end_held.applied_torque == 0.4


def test_an_incomplete_period_cannot_end_and_slices_cannot_overrun_it():
    with SliderPendulumBall(SLICED) as physics:
        physics.reset(seed=0)
        physics.advance(0.0, 0.0, 18)
        with pytest.raises(RuntimeError, match='not complete'):
            physics.finish_period()
        with pytest.raises(ValueError, match='do not fit'):
            physics.advance(0.0, 0.0, 4)


def lockstep(params, human_involved=True):
    settings = ProtocolSettings(control_period=params.control_period,
                                human_period=params.human_period, robot_dof='translation')
    protocol = StepProtocol(settings)
    protocol.set_roles('translation', human_involved)
    return protocol


def run_period(params, human_torques, human_involved=True, seed=2):
    """Run one control period in lockstep; the human answers each (slice) state in turn."""
    with SliderPendulumBall(params) as physics:
        protocol = lockstep(params, human_involved)
        stepper = SimStepper(physics, protocol)
        advanced = stepper.start_episode(0, seed)
        seen = []
        order = protocol.on_command('robot', advanced.stamp, wrench(force_z=0.5), 0.0).order
        if human_involved:   # a human who sits out is not awaited and sends nothing
            assert order is None
            order = protocol.on_command('human', advanced.stamp,
                                        wrench(torque_x=human_torques[0]), 0.0).order
        answers = iter(human_torques[1:])
        while True:
            advanced = stepper.apply(order)
            if advanced.period_end:
                return advanced, seen, protocol
            seen.append((advanced.slice, advanced.stamp))
            order = protocol.on_command('human', advanced.stamp,
                                        wrench(torque_x=next(answers)), 0.0).order
            assert order is not None   # the robot's answer holds: only the human is awaited


def test_lockstep_asks_the_human_every_slice_and_records_what_it_applied():
    torques = [0.1 * (index - 5) for index in range(10)]
    advanced, seen, protocol = run_period(SLICED, torques)
    assert [index for index, _ in seen] == list(range(1, 10))
    assert [stamp for _, stamp in seen] == [index * 20_000_000 for index in range(1, 10)]
    assert advanced.human_applied == pytest.approx(torques)
    assert advanced.human_applied == [max(-0.5, min(0.5, value)) for value in torques]
    assert advanced.state.applied_force == 0.5          # the robot's answer held all period
    assert advanced.stamp == 200_000_000 and advanced.state.step == 1
    assert protocol.counters['human_missing'] == 0


def test_a_human_who_sits_out_or_acts_once_a_period_steps_whole_periods_as_before():
    for params, involved in ((SLICED, False), (HELD, True)):
        advanced, seen, protocol = run_period(params, [0.3], human_involved=involved)
        assert seen == [] and advanced.period_end
        assert len(advanced.human_applied) == 1
        assert protocol.counters['human_missing'] == 0


def test_a_human_who_sits_out_is_neither_awaited_nor_missing():
    """The robot's answer alone steps a robot-alone period; nothing is missing."""
    protocol = lockstep(SLICED, human_involved=False)
    assert not protocol.awaits_human and protocol.awaited_actors() == ('robot',)
    protocol.start_episode(0)
    stamp = protocol.next_stamp(0, False)
    order = protocol.on_command('robot', stamp, wrench(force_z=0.5), 0.0).order
    assert order is not None and order.missing == {'robot': False} and order.final
    assert not protocol.waiting
    # realtime: a silent human who sits out is not counted missing
    realtime = StepProtocol(ProtocolSettings(mode='realtime', control_period=0.2,
                                             robot_dof='translation'))
    realtime.set_roles('translation', False)
    realtime.start_episode(0)
    stamp = realtime.next_stamp(0, False)
    realtime.on_command('robot', stamp, wrench(force_z=0.5), 1.0)
    order = realtime.on_tick(1.1)
    assert order.missing == {'robot': False}
    assert realtime.counters['human_missing'] == 0
    # only a human who acts is awaited again
    protocol.set_roles('translation', True)
    assert protocol.awaits_human and protocol.awaited_actors() == ('robot', 'human')


def test_at_the_old_rate_the_stepper_equals_the_plain_physics_step():
    advanced, _, _ = run_period(HELD, [0.3])
    with SliderPendulumBall(HELD) as physics:
        physics.reset(seed=2)
        plain = physics.step(0.5, 0.3)
    assert positions(advanced.state) == positions(plain)
    assert (advanced.state.applied_force, advanced.state.applied_torque) == (0.5, 0.3)


def test_a_missing_slice_answer_counts_as_zero_and_once_for_the_period():
    with SliderPendulumBall(SLICED) as physics:
        protocol = lockstep(SLICED)
        stepper = SimStepper(physics, protocol)
        advanced = stepper.start_episode(0, 0)
        protocol.on_command('robot', advanced.stamp, wrench(force_z=0.5), 0.0)
        order = protocol.on_command('human', advanced.stamp, wrench(torque_x=0.2), 0.0).order
        for _ in range(9):
            advanced = stepper.apply(order)
            order = protocol.on_timeout()       # the human never answers a slice state
        advanced = stepper.apply(order)
    assert advanced.period_end and advanced.missing == {'robot': False, 'human': True}
    assert advanced.human_applied == [0.2] + [0.0] * 9
    assert protocol.counters['human_missing'] == 1


def test_realtime_ticks_per_slice_with_the_newest_human_command():
    settings = ProtocolSettings(mode='realtime', control_period=0.2, human_period=0.02,
                                robot_dof='translation')
    protocol = StepProtocol(settings)
    with SliderPendulumBall(SLICED) as physics:
        stepper = SimStepper(physics, protocol)
        advanced = stepper.start_episode(0, 0)
        protocol.on_command('robot', advanced.stamp, wrench(force_z=0.5), 0.0)
        protocol.on_command('human', advanced.stamp, wrench(torque_x=0.1), 0.0)
        applied = []
        for tick in range(10):
            order = protocol.on_tick(0.02 * (tick + 1))
            applied.append(order.human_value)
            advanced = stepper.apply(order)
            if not advanced.period_end:
                # the person moved the stick: a command answering the newest slice state
                protocol.on_command('human', advanced.stamp, wrench(torque_x=0.1 + 0.01 * tick),
                                    0.02 * (tick + 1))
    assert advanced.period_end and advanced.human_applied == applied
    assert applied == pytest.approx([0.1] + [0.1 + 0.01 * tick for tick in range(9)])


def test_the_sim_parameters_reach_the_protocol():
    from hrc_sim_node.sim_params import SimParams

    assert ProtocolSettings.of(SimParams()).human_slices == 10       # the default: 0.02 s
    assert ProtocolSettings.of(SimParams(human_period=0.2)).human_slices == 1
    assert ProtocolSettings().human_slices == 1   # a bare protocol: once a period
