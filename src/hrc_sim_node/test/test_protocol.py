"""The sim's step protocol core without ROS: plain wrenches, stamps and a clock in, orders out."""

from types import SimpleNamespace

from hrc_sim_node.protocol import (MAX_EPISODE, per_dof, ProtocolError, ProtocolSettings,
                                   roles, stamp_ns, StepProtocol)
from hrc_sim_node.sim_log import WarningThrottle
import pytest

PERIOD_NS = 200_000_000


def wrench(force_z=0.0, torque_x=0.0, **others):
    """Return a Wrench-like object (force/torque with x, y, z)."""
    values = {'force.z': force_z, 'torque.x': torque_x}
    values.update({name.replace('_', '.'): value for name, value in others.items()})

    def vector(part):
        return SimpleNamespace(**{axis: values.get(f'{part}.{axis}', 0.0) for axis in 'xyz'})

    return SimpleNamespace(force=vector('force'), torque=vector('torque'))


def started(mode='lockstep', expected=('robot', 'human'), robot_dof='translation'):
    """Return a protocol with episode 0 started and its first state published."""
    protocol = StepProtocol(ProtocolSettings(mode=mode, expected_actors=expected,
                                             robot_dof=robot_dof))
    protocol.start_episode(0)
    protocol.next_stamp(0, final=False)
    return protocol


def test_lockstep_steps_when_every_expected_actor_answered_the_awaited_stamp():
    protocol = started()
    first = protocol.on_command('robot', 0, wrench(force_z=1.5), now=0.0)
    assert first.kind == 'accepted' and first.order is None
    done = protocol.on_command('human', 0, wrench(torque_x=-0.25), now=0.0)
    assert done.order is not None
    assert (done.order.force, done.order.torque) == (1.5, -0.25)
    assert done.order.missing == {'robot': False, 'human': False}
    assert not protocol.waiting           # the next state arms the next wait
    assert protocol.next_stamp(1, final=False) == PERIOD_NS


def test_lockstep_stale_stamps_are_ignored_and_counted():
    protocol = started()
    assert protocol.on_command('robot', PERIOD_NS, wrench(force_z=1.0), 0.0).kind == 'stale'
    assert protocol.on_command('robot', -1, wrench(force_z=1.0), 0.0).kind == 'stale'
    assert protocol.counters['robot_stale'] == 2
    assert protocol.on_timeout().missing == {'robot': True, 'human': True}


def test_a_timeout_knows_how_many_stale_commands_came_while_it_waited():
    """The sim's warning then says a flood may have pushed the matching command out."""
    protocol = started()
    for _ in range(3):
        protocol.on_command('human', 12345 * 10 ** 9, wrench(), 0.0)
    protocol.on_command('robot', 0, wrench(force_z=1.0), 0.0)
    order = protocol.on_timeout()
    assert order.absent == ['human']
    assert protocol.stale_while_waiting == {'human': 3}
    protocol.next_stamp(1, final=False)         # the next wait starts from nothing
    assert protocol.stale_while_waiting == {}
    assert protocol.counters['human_stale'] == 3


def test_the_first_answer_to_a_state_stands():
    protocol = started(expected=('robot', 'human', ))
    protocol.on_command('robot', 0, wrench(force_z=1.0), 0.0)
    protocol.on_command('robot', 0, wrench(force_z=-2.0), 0.0)
    order = protocol.on_command('human', 0, wrench(), 0.0).order
    assert order.force == 1.0 and protocol.counters['robot_duplicate'] == 1


def test_timeout_counts_missing_and_refused_as_zero():
    protocol = started()
    assert protocol.on_command('robot', 0, wrench(force_z=float('nan')), 0.0).kind == 'refused'
    order = protocol.on_timeout()
    assert (order.force, order.torque) == (0.0, 0.0)
    assert order.missing == {'robot': True, 'human': True} and order.reason == 'timeout'
    assert protocol.counters['robot_missing'] == 1 and protocol.counters['robot_refused'] == 1


def test_clamped_where_the_limit_is_owned_and_off_axis_reported():
    protocol = started()
    result = protocol.on_command('robot', 0, wrench(force_z=7.0, torque_y=0.3), 0.0)
    assert result.command.clamped and result.command.value == 2.0 and result.limit == 2.0
    assert result.command.off_axis == {'torque.y': 0.3}
    order = protocol.on_command('human', 0, wrench(torque_x=-9.0), 0.0).order
    assert (order.force, order.torque) == (2.0, -0.5)
    assert protocol.counters['robot_clamped'] == 1 and protocol.counters['human_clamped'] == 1


def test_free_run_without_expected_actors():
    protocol = started(expected=())
    order = protocol.free_run()
    assert order.missing == {} and (order.force, order.torque) == (0.0, 0.0)


def test_human_not_involved_is_not_applied_and_reported():
    protocol = started()
    protocol.set_roles('translation', human_involved=False)
    # A human who sits out is not awaited; a command sent anyway before the robot's
    # is not applied and is reported, one after the step answers no awaited state: stale.
    assert protocol.on_command('human', 0, wrench(torque_x=0.2), 0.0).order is None
    order = protocol.on_command('robot', 0, wrench(force_z=0.5), 0.0).order
    assert (order.force, order.torque) == (0.5, 0.0)
    assert order.ignored == [('human', 0.2)] and protocol.counters['human_not_involved'] == 1
    assert protocol.on_command('human', 0, wrench(torque_x=0.2), 0.0).kind == 'stale'


def test_a_late_role_change_during_a_wait_steps_or_waits_as_the_roles_now_say():
    # The human was involved when the state went out; the robot answered; an announcement
    # that comes late says the human sits out: the step is due at once.
    protocol = started()
    assert protocol.on_command('robot', 0, wrench(force_z=0.5), 0.0).order is None
    assert protocol.on_roles_changed() is None            # nothing changed yet
    protocol.set_roles('translation', human_involved=False)
    order = protocol.on_roles_changed()
    assert order is not None and order.missing == {'robot': False}
    assert (order.force, order.torque) == (0.5, 0.0) and order.reason == 'answered'
    # Only the human expected and sitting out: nothing awaited (free run); a late "involved"
    # makes the human awaited, and with no answer yet nothing is due (the node arms the wait).
    protocol = started(expected=('human',))
    protocol.set_roles('translation', human_involved=False)
    assert protocol.awaited_actors() == ()
    protocol.set_roles('translation', human_involved=True)
    assert protocol.on_roles_changed() is None and protocol.awaited_actors() == ('human',)
    assert protocol.on_command('human', 0, wrench(torque_x=0.1), 0.0).order is not None
    assert protocol.on_roles_changed() is None            # not waiting any more


def test_roles_swap_the_degrees_of_freedom():
    protocol = started(robot_dof='rotation')
    protocol.on_command('robot', 0, wrench(torque_x=0.1, force_z=1.0), 0.0)
    order = protocol.on_command('human', 0, wrench(force_z=1.0), 0.0).order
    assert (order.force, order.torque) == (1.0, 0.1)
    assert roles('rotation') == {'robot': 'rotation', 'human': 'translation'}


def test_realtime_applies_fresh_commands_on_the_tick_and_reports_old_ones():
    protocol = started(mode='realtime')
    assert protocol.on_command('robot', 0, wrench(force_z=1.0), now=10.0).order is None
    order = protocol.on_tick(now=10.3)
    assert order.force == 1.0 and order.missing == {'robot': False, 'human': True}
    protocol.next_stamp(1, final=False)
    order = protocol.on_tick(now=10.6)      # the command is 0.6 s old > command_timeout 0.5
    assert order.force == 0.0 and order.missing['robot']


def test_realtime_keeps_the_answer_to_the_newest_state_not_the_latest_arrival():
    """A flood with wrong stamps (another publisher) cannot replace the actor's command."""
    protocol = started(mode='realtime')
    protocol.next_stamp(1, final=False)
    protocol.on_command('human', PERIOD_NS, wrench(torque_x=0.2), now=1.0)
    for fake in (12345, 7 * PERIOD_NS, 0):   # no state / a future state / an older state
        protocol.on_command('human', fake, wrench(torque_x=-0.5), now=1.01)
    assert protocol.on_tick(now=1.05).torque == 0.2
    assert protocol.counters['human_stale'] == 2 and protocol.counters['human_superseded'] == 1


def test_counters_of_an_abandoned_episode_survive_a_reset_in_its_middle():
    protocol = started()
    protocol.on_command('robot', 0, wrench(force_z=float('inf')), 0.0)
    protocol.on_command('human', 99, wrench(), 0.0)
    abandoned = protocol.start_episode(1)
    assert abandoned == {'robot_refused': 1, 'human_stale': 1}
    assert protocol.counters == {}
    assert protocol.totals == {'robot_refused': 1, 'human_stale': 1}
    assert protocol.start_episode(2) == {}   # started but not yet stepped: nothing counted


def test_episode_indices_are_uint32_and_the_last_one_has_no_successor():
    protocol = started()
    protocol.start_episode(MAX_EPISODE)
    assert protocol.episode == 4294967295 and protocol.next_episode() is None
    with pytest.raises(ProtocolError, match='uint32'):
        protocol.start_episode(MAX_EPISODE + 1)
    with pytest.raises(ProtocolError):
        protocol.start_episode(-1)


def test_clock_mode_switches_between_episodes_only():
    protocol = started()
    with pytest.raises(ProtocolError, match='between episodes'):
        protocol.set_mode('realtime')
    with pytest.raises(ProtocolError, match='not one of'):
        protocol.set_mode('fast')
    protocol.hold()
    assert protocol.set_mode('realtime') and not protocol.set_mode('realtime')
    protocol.start_episode(1)
    protocol.next_stamp(0, final=False)
    assert protocol.on_timeout() is None    # a lockstep decision in realtime: none
    protocol.on_command('robot', protocol.sim_time_ns, wrench(force_z=1.0), now=5.0)
    assert protocol.on_tick(now=5.1).force == 1.0


def test_final_state_ends_the_episode_and_commands_then_count_between_episodes():
    protocol = started()
    protocol.next_stamp(1, final=True)
    assert not protocol.active and protocol.finished_episodes == 1
    assert protocol.on_command('robot', PERIOD_NS, wrench(), 0.0).kind == 'between_episodes'


def test_stamps_and_dispatch_helpers():
    assert stamp_ns(3, 400_000_000) == 3_400_000_000
    assert stamp_ns(0, 1_000_000_000) == -1 and stamp_ns(-1, 0) == -1
    assert per_dof({'robot': 0.5, 'human': -1.0}, roles('rotation')) == \
        {'translation': -1.0, 'rotation': 0.5}


def test_warning_throttle_says_how_many_were_suppressed():
    throttle = WarningThrottle(2.0)
    assert throttle.admit('a', 0.0) == ''
    assert throttle.admit('a', 1.0) is None and throttle.admit('b', 1.0) == ''
    assert throttle.admit('a', 2.5) == ' (1 more like this in the last 2.5 s)'
