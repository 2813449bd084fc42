"""Tests of the sim node in its own process over DDS (fixtures: start_node, sim_client)."""

import math
import pathlib
import re
import time

from hrc_testing.nodes import wait_for
from hrc_msgs.msg import SessionStatus
from hrc_sim_node.body_geometry import body_poses
from hrc_sim_node.physics import PhysicsParams, SliderPendulumBall
from hrc_sim_node.sim_node import WARN_THROTTLE_S
import pytest

PARAMS_FILE = pathlib.Path(__file__).resolve().parents[3] / 'params' / 'sim.yaml'
# Lockstep tests wait for commands much longer than they need, so a slow machine never makes
# the sim time out on its own: holding means the sim got no complete answer.
PATIENT = {'lockstep_timeout': 60.0, 'marker_rate': 0.0}


def seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def printed(process, text: str, timeout: float = 30.0) -> bool:
    """Wait until the node process has printed ``text``."""
    return wait_for(lambda: text in process.output, timeout, interval=0.05)


def start_sim(start_node, sim_client, **parameters):
    """Start a sim; the human acts once a period unless ``human_period`` is given.

    (These tests are about the per-period protocol; slices: test_lockstep_at_the_human_rate.)
    """
    parameters.setdefault('human_period', parameters.get('control_period', 0.2))
    process = start_node('hrc_sim_node', 'sim_node', parameters=parameters)
    sim_client.connect()
    return process


def test_lockstep_advances_once_per_answered_step_and_holds_otherwise(start_node, sim_client):
    start_sim(start_node, sim_client, **PATIENT)
    response = sim_client.reset(seed=3, episode=4)
    assert response.success
    assert response.state.step == 0 and response.state.episode == 4
    state = sim_client.next_state(0)
    assert state.header.stamp == response.state.header.stamp

    # Only the robot answers: the sim holds.
    sim_client.answer('robot', state)
    sim_client.spin(0.5)
    assert len(sim_client.states) == 1
    # The human answers too: exactly one step.
    sim_client.answer('human', state)
    state = sim_client.next_state(1)
    assert state.step == 1
    # Commands carrying another state's stamp (stale) do not answer the current state.
    sim_client.answer('robot', sim_client.states[0])
    sim_client.answer('human', sim_client.states[0])
    sim_client.spin(0.5)
    assert len(sim_client.states) == 2

    # The robot drives translation (force.z), the human rotation (torque.x) by default; the
    # node must give exactly the physics core's trajectory for those commands.
    commands = [(1.0, 0.2), (-0.5, 0.1), (2.0, -0.3), (0.0, 0.0), (0.7, 0.5)]
    for index, (force, torque) in enumerate(commands):
        sim_client.answer('robot', state, force_z=force)
        sim_client.answer('human', state, torque_x=torque)
        state = sim_client.next_state(2 + index)
        assert state.step == 2 + index
        assert (state.applied_force, state.applied_torque) == (force, torque)
        assert not state.robot_command_missing and not state.human_command_missing
    sim_client.spin(0.3)
    assert [s.step for s in sim_client.states] == list(range(7))
    assert all(s.episode == 4 for s in sim_client.states)
    times = [seconds(s.header.stamp) for s in sim_client.states]
    assert all(b - a == pytest.approx(0.2) for a, b in zip(times, times[1:]))
    # /clock carries the simulation time of every state (lockstep).
    assert sim_client.wait(lambda: len(sim_client.clocks) >= 7)
    assert [seconds(c.clock) for c in sim_client.clocks][-7:] == pytest.approx(times)

    physics = SliderPendulumBall()
    expected = [physics.reset(seed=3), physics.step(0.0, 0.0)]
    expected += [physics.step(force, torque) for force, torque in commands]
    physics.close()
    assert len(expected) == len(sim_client.states)
    for published, reference in zip(sim_client.states, expected):
        assert published.slider_position == reference.slider_position
        assert published.pendulum_angle == reference.pendulum_angle
        assert published.ball_position == reference.ball_position


def test_lockstep_timeout_counts_the_missing_command_as_zero(start_node, sim_client):
    # 5 s: the robot's answer must come within it, from a test process a loaded machine may
    # keep waiting for the CPU; the human's never comes
    process = start_sim(start_node, sim_client, lockstep_timeout=5.0, marker_rate=0.0)
    sim_client.reset(seed=1)
    state = sim_client.next_state(0)
    sim_client.answer('robot', state, force_z=1.0)
    state = sim_client.next_state(1)
    assert state.step == 1
    assert state.human_command_missing and not state.robot_command_missing
    assert state.applied_force == 1.0 and state.applied_torque == 0.0
    assert printed(process, 'no command from human within lockstep_timeout')


def test_non_finite_commands_are_refused_and_big_ones_clamped(start_node, sim_client):
    process = start_sim(start_node, sim_client, **PATIENT)
    sim_client.reset(seed=2)
    state = sim_client.next_state(0)
    sim_client.answer('robot', state, force_z=math.nan)
    sim_client.answer('human', state, torque_x=0.1)
    state = sim_client.next_state(1)
    assert state.robot_command_missing and not state.human_command_missing
    assert state.applied_force == 0.0 and state.applied_torque == 0.1
    assert printed(process, 'refused robot command at step 0: non-finite component(s) '
                            'force.z=nan')
    # A NaN in an unused component refuses the whole command too.
    sim_client.answer('robot', state, force_z=1.0)
    sim_client.answer('human', state, torque_x=0.1, force_y=math.inf)
    state = sim_client.next_state(2)
    assert state.human_command_missing and state.applied_torque == 0.0
    assert state.applied_force == 1.0
    # Beyond the limits: clamped to max_force = 2 N and max_torque = 0.5 N*m.
    sim_client.answer('robot', state, force_z=100.0)
    sim_client.answer('human', state, torque_x=-7.0)
    state = sim_client.next_state(3)
    assert state.applied_force == 2.0 and state.applied_torque == -0.5
    assert not state.robot_command_missing and not state.human_command_missing
    assert printed(process, 'clamped robot translation command +100 to +2 N')
    assert printed(process, 'clamped human rotation command -7 to -0.5 N*m')


def test_wrong_axis_components_are_ignored_and_reported(start_node, sim_client):
    process = start_sim(start_node, sim_client, **PATIENT)
    sim_client.reset(seed=2)
    state = sim_client.next_state(0)
    sim_client.answer('robot', state, force_z=0.5, torque_x=0.3, force_y=1.0)
    sim_client.answer('human', state, torque_x=0.1, force_z=0.7)
    state = sim_client.next_state(1)
    assert state.applied_force == 0.5 and state.applied_torque == 0.1
    assert printed(process, 'ignored off-axis components of the robot command (robot drives '
                            'translation only): force.y=+1, torque.x=+0.3')
    assert printed(process, 'ignored off-axis components of the human command (human drives '
                            'rotation only): force.z=+0.7')

    # The session swaps the roles: now the robot's torque.x and the human's force.z count.
    session = SessionStatus(session_id='t', robot_dof=SessionStatus.DOF_ROTATION,
                            human_dof=SessionStatus.DOF_TRANSLATION, human_involved=True)
    sim_client.session.publish(session)
    assert printed(process, 'robot drives rotation, human drives translation')
    sim_client.answer('robot', state, force_z=0.5, torque_x=0.3)
    sim_client.answer('human', state, force_z=0.7, torque_x=0.1)
    state = sim_client.next_state(2)
    assert state.applied_force == 0.7 and state.applied_torque == 0.3
    # A human not involved now is not waited for: the robot's answer alone steps,
    # nothing is missing. (A human command sent anyway is not applied: test_protocol.py.)
    session.human_involved = False
    sim_client.session.publish(session)
    assert printed(process, 'human involved: False')
    sim_client.answer('robot', state, torque_x=0.3)
    state = sim_client.next_state(3)
    assert state.applied_force == 0.0 and state.applied_torque == 0.3
    assert not state.human_command_missing and not state.robot_command_missing


def test_realtime_steps_every_control_period_and_reports_silent_actors(start_node,
                                                                       sim_client):
    # command_timeout: a command stays fresh for 60 s, so a test process kept from the CPU
    # cannot make a commanded step count as missing (an actor never heard from is missing)
    start_sim(start_node, sim_client, mode='realtime', control_period=0.1,
              command_timeout=60.0, marker_rate=0.0)
    began = time.monotonic()
    sim_client.reset(seed=0)
    assert sim_client.wait(lambda: len(sim_client.states) >= 10, 60)   # nobody commands
    elapsed = time.monotonic() - began
    silent = list(sim_client.states)
    # Paced by the clock (the sim does not hold, nor run as fast as it can): ten states take
    # at least nine periods, whatever the load (load only makes them later).
    assert elapsed >= 9 * 0.1 * 0.9, elapsed
    assert all(s.robot_command_missing and s.human_command_missing for s in silent[1:])
    assert [s.step for s in silent] == list(range(len(silent)))
    times = [seconds(s.header.stamp) for s in silent]
    assert all(b - a == pytest.approx(0.1) for a, b in zip(times, times[1:]))

    # Now both actors command at a higher rate than the sim steps: from the first state that
    # applies both, nothing is missing and the latest commands are applied.
    def command_both():
        latest = sim_client.states[-1]
        sim_client.answer('robot', latest, force_z=0.4)
        sim_client.answer('human', latest, torque_x=-0.1)

    def applied(state):
        return (state.applied_force, state.applied_torque) == (0.4, -0.1)

    def first_applied():
        return next((index for index, s in enumerate(sim_client.states) if applied(s)), None)

    assert sim_client.wait(lambda: (command_both(), first_applied() is not None)[1], 60)
    start = first_applied()
    assert sim_client.wait(lambda: (command_both(), len(sim_client.states) >= start + 8)[1], 60)
    commanded = sim_client.states[start:]
    assert all(not s.robot_command_missing and not s.human_command_missing for s in commanded)
    assert all(applied(s) for s in commanded)


def test_episode_ends_by_truncation_then_holds_until_reset(start_node, sim_client):
    process = start_sim(start_node, sim_client, episode_duration=0.6, **PATIENT)
    sim_client.reset(seed=4, episode=0)
    state = sim_client.next_state(0)
    for index in range(3):
        sim_client.answer('robot', state)
        sim_client.answer('human', state)
        state = sim_client.next_state(index + 1)
    assert state.step == 3 and state.truncated and not state.terminated
    assert [s.truncated for s in sim_client.states] == [False, False, False, True]
    assert printed(process, 'episode 0 truncated after 3 steps')
    assert printed(process, 'holding until /hrc/sim/reset')
    sim_client.answer('robot', state)
    sim_client.answer('human', state)
    sim_client.spin(0.5)
    assert len(sim_client.states) == 4

    response = sim_client.reset(seed=4, episode=1)
    first = sim_client.next_state(4)
    assert first.episode == 1 and first.step == 0 and not first.truncated
    assert seconds(first.header.stamp) > seconds(state.header.stamp)  # stamps stay unique
    # The same seed gives the same initial state; -1 continues the sim's own sequence.
    assert response.state.slider_position == sim_client.states[0].slider_position
    assert response.state.ball_position == sim_client.states[0].ball_position
    other = sim_client.reset(seed=-1, episode=2)
    assert other.state.ball_position != response.state.ball_position


def test_free_run_with_no_expected_actors_runs_one_episode_and_exits(start_node):
    # The main job's standalone run: the repository's YAML plus overrides on the command line
    # (an empty list given with -p overrides the file's list).
    process = start_node('hrc_sim_node', 'sim_node', params_file=PARAMS_FILE, parameters={
        'expected_actors': [], 'start_on_launch': True, 'max_episodes': 1})
    assert process.wait(timeout=60) == 0, process.output
    assert 'expected actors: none (free run)' in process.output
    assert 'episode 0 truncated after 200 steps (40.0 s sim)' in process.output
    assert 'missing commands robot 0, human 0' in process.output


def test_auto_reset_runs_episodes_back_to_back(start_node, tmp_path):
    # The empty actor list from a YAML file this time (rcl reads it as an untyped value).
    params_file = tmp_path / 'free.yaml'
    params_file.write_text('sim:\n  ros__parameters:\n    expected_actors: []\n')
    process = start_node('hrc_sim_node', 'sim_node', params_file=params_file, parameters={
        'start_on_launch': True, 'auto_reset': True, 'max_episodes': 3,
        'episode_duration': 1.0})
    assert process.wait(timeout=60) == 0, process.output
    assert 'expected actors: none (free run)' in process.output
    for episode in range(3):
        assert f'episode {episode} truncated after 5 steps' in process.output
    assert 'episode 3' not in process.output


@pytest.mark.parametrize('parameters, reasons', [
    ({'mode': 'bogus'}, ["mode: 'bogus' is not one of ['lockstep', 'realtime']"]),
    ({'control_period': -1.0}, ['control_period', 'out of range']),
    ({'expected_actors': ['robot', 'alien']}, ["expected_actors: ['alien'] not among"]),
    ({'episode_duration': 40.1}, ['not a multiple of control_period']),
    ({'gui': True}, ['gui: the PyBullet GUI needs a display']),
])
def test_bad_parameters_are_rejected_with_the_reason(start_node, ros_env, parameters, reasons):
    # No display here, whatever the machine has: the GUI request must be refused, not crash.
    env = {name: value for name, value in ros_env.items() if name != 'DISPLAY'}
    process = start_node('hrc_sim_node', 'sim_node', parameters=parameters, env=env)
    assert process.wait(timeout=30) == 2, process.output
    for reason in reasons:
        assert reason in process.output


def test_markers_and_camera_image_when_enabled(start_node, sim_client):
    start_sim(start_node, sim_client, camera_rate=5.0, image_width=64, image_height=48,
              marker_rate=10.0, lockstep_timeout=60.0)
    state = sim_client.reset(seed=6).state
    assert sim_client.wait(lambda: sim_client.images and sim_client.markers, 60.0)
    image = sim_client.images[-1]
    assert (image.width, image.height, image.encoding, image.step) == (64, 48, 'rgb8', 192)
    assert len(image.data) == 64 * 48 * 3
    assert len(set(bytes(image.data))) > 3  # a picture, not a blank frame
    markers = sim_client.markers[-1].markers
    assert [m.id for m in markers] == [0, 1, 2, 3]
    assert all(m.header.frame_id == 'world' for m in markers)
    poses = body_poses(state, PhysicsParams())
    ball = markers[3].pose.position
    assert (ball.x, ball.y, ball.z) == pytest.approx(poses['ball'][0])
    assert markers[1].pose.position.z == pytest.approx(state.slider_position)


def test_a_reset_switches_the_clock_mode_and_reports_what_the_sim_owns(start_node, sim_client):
    """Lockstep while the robot trains alone, realtime when the human joins (and back)."""
    process = start_sim(start_node, sim_client, control_period=0.1, episode_duration=20.0,
                        command_timeout=1.0, **PATIENT)
    bad = sim_client.reset(seed=0, episode=0, clock_mode='fast')
    assert not bad.success and "clock_mode 'fast' is not one of" in bad.message
    response = sim_client.reset(seed=0, episode=0)
    assert response.success and response.clock_mode == 'lockstep'
    assert (response.control_period, response.max_force, response.max_torque) == (0.1, 2.0, 0.5)
    sim_client.spin(0.5)
    assert len(sim_client.states) == 1          # lockstep: holds without commands

    # Realtime from the next episode on (the running one is abandoned by the reset).
    sim_client.answer('robot', sim_client.states[0], force_z=5.0)   # clamped: counted
    assert printed(process, 'clamped robot translation command')
    response = sim_client.reset(seed=1, episode=1, clock_mode='realtime')
    assert response.success and response.clock_mode == 'realtime'
    assert printed(process, 'episode 0 abandoned after 0 steps')
    assert printed(process, 'robot_clamped 1')  # counters of the abandoned episode kept
    # steps on the clock, without commands
    assert sim_client.wait(lambda: sum(s.episode == 1 for s in sim_client.states) >= 5, 60)
    realtime = [s for s in sim_client.states if s.episode == 1]
    assert realtime[-1].human_command_missing

    # Back to lockstep: the sim holds again.
    response = sim_client.reset(seed=2, episode=2, clock_mode='lockstep')
    assert response.clock_mode == 'lockstep'
    assert sim_client.wait(lambda: sim_client.states[-1].episode == 2)
    count = len(sim_client.states)
    sim_client.spin(0.5)
    assert len(sim_client.states) == count
    assert printed(process, 'clock mode switched to lockstep')


def test_a_reset_waits_until_the_state_writer_has_matched_the_readers_asked_for(
        start_node, sim_client):
    """A reader the agent sees but the sim has not matched yet would miss the first states.

    Seen under load: the recorder matched the sim's /hrc/state writer 0.5 s after the agent's
    topics, and the five lockstep episodes the robot ran alone meanwhile were not in the bag.
    The agent's first reset now names the readers it sees; the sim starts no episode (and
    publishes nothing) until its writer has matched that many, and says retry.
    """
    start_sim(start_node, sim_client, control_period=0.1, episode_duration=20.0, **PATIENT)
    waiting = sim_client.reset(seed=0, episode=0, state_readers=5)
    assert not waiting.success and waiting.retry
    assert waiting.state_readers_matched == 1      # this test's reader of /hrc/state
    assert 'not started: 1 of 5 readers of /hrc/state matched' in waiting.message
    sim_client.spin(0.5)
    assert sim_client.states == []                 # no episode started, no state published
    started = sim_client.reset(seed=0, episode=0, state_readers=1)
    assert started.success and not started.retry and started.state_readers_matched == 1
    assert sim_client.wait(lambda: len(sim_client.states) == 1)


def test_the_last_uint32_episode_index_holds_instead_of_wrapping(start_node, sim_client):
    process = start_sim(start_node, sim_client, episode_duration=0.2, auto_reset=True,
                        expected_actors=[], marker_rate=0.0)
    response = sim_client.reset(seed=0, episode=4294967295)
    assert response.success
    assert printed(process, 'episode 4294967295 is the last index a uint32 holds')
    sim_client.spin(0.3)
    assert [s.episode for s in sim_client.states] == [4294967295, 4294967295]


FLOOD = pathlib.Path(__file__).with_name('flood.py')
# Commands per second of the hostile publisher. The sim's queue (COMMAND_SUBSCRIPTION_DEPTH,
# 1000) holds depth / rate seconds of flood: a sim kept from the CPU longer loses the matching
# command to any flood. At the hardening report's 10k/s that was 0.1 s, which a busy machine
# exceeded (a held step); at 2k/s it is 0.5 s, and the sim without its fix (depth 1, one
# command per executor turn) still loses commands within a few steps. (A flood faster than the
# sim drains its queue, about 25k/s on a loaded 2-core machine, pushes commands out of any
# bounded queue.)
FLOOD_RATE = 2000


def stale_commands_reported(output: str, actor: str) -> int:
    """Return how many stale commands of ``actor`` the sim's throttled warnings account for.

    Each warning stands for its command plus the ``N more like this`` suppressed before it.
    """
    lines = [line for line in output.splitlines()
             if f'{actor} command stamped (12345, 0) answers no state' in line]
    return sum(1 + int(match.group(1)) if (match := re.search(r'\((\d+) more like this', line))
               else 1 for line in lines)


@pytest.mark.parametrize('topic, actor, frame_id_bytes, at_least', [
    ('/hrc/human/cmd_wrench', 'human', 8, 100),              # a flood of small commands
    ('/hrc/robot/cmd_wrench', 'robot', 1024 * 1024, 1),     # giant commands (1 MiB)
])
def test_a_second_publisher_cannot_push_out_the_actors_matching_command(
        start_node, sim_client, ros_env, topic, actor, frame_id_bytes, at_least):
    """Without draining the queue (and a deeper one) matching commands were lost.

    The steps start once the sim has reported ``at_least`` flood commands of the episode, so
    the flood is under way whatever the machine's load (the flooder, a process of its own,
    may get the CPU late); it goes on during the steps.
    """
    import subprocess
    import sys

    process = start_sim(start_node, sim_client, episode_duration=6.0, **PATIENT)
    flooder = subprocess.Popen([sys.executable, str(FLOOD), topic, str(frame_id_bytes),
                                str(FLOOD_RATE)],
                               env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True)
    try:
        assert sim_client.wait(lambda: sim_client.node.count_publishers(topic) >= 2, 60)
        episode_began = time.monotonic()
        sim_client.reset(seed=0)
        state = sim_client.next_state(0)
        # The flood reaches the sim (reported at WARN, throttled, naming the topic's
        # publishers): wait until the sim accounts for enough of it in this episode (before
        # the reset the sim counts commands as between episodes and does not warn).
        assert wait_for(lambda: stale_commands_reported(process.output, actor) >= at_least,
                        120, interval=0.1), \
            f'the sim reported {stale_commands_reported(process.output, actor)} flood commands'
        for step in range(30):
            sim_client.answer('robot', state, force_z=0.5)
            sim_client.answer('human', state, torque_x=-0.1)
            state = sim_client.next_state(step + 1)
        episode_ended = time.monotonic()
    finally:
        flooder.terminate()
        flooder.wait(timeout=30)
    missing = [s.step for s in sim_client.states
               if s.robot_command_missing or s.human_command_missing]
    assert missing == [], f'matching commands lost in steps {missing}'
    assert all((s.applied_force, s.applied_torque) == (0.5, -0.1) for s in sim_client.states[1:])
    assert printed(process, f'2 publisher(s) on {topic}: ') and 'gid 010f' in process.output
    assert printed(process, 'episode 0 truncated after 30 steps')
    flood = int(re.search(f'{actor}_stale ([0-9]+)', process.output).group(1))
    assert flood >= at_least, f'only {flood} flood commands reached the sim'
    # Throttled: one warning per WARN_THROTTLE_S at most while the episode ran (stale
    # commands are warned about only during an episode; it ran within these wall seconds).
    warnings = process.output.count('answers no state')
    assert warnings <= 1 + (episode_ended - episode_began) / WARN_THROTTLE_S, warnings


def test_lockstep_at_the_human_rate_asks_the_human_every_slice(start_node, sim_client):
    """Ten slice states per step on /hrc/sim/slice_state.

    The period's state holds the human's ten applied commands (clamped to the sim's
    max_torque) and the robot's one.
    """
    start_sim(start_node, sim_client, human_period=0.02, **PATIENT)
    sim_client.wait(lambda: sim_client.slice_subscription.get_publisher_count() > 0)
    first = sim_client.reset(seed=2).state
    sim_client.answer('robot', first, force_z=1.0)
    sim_client.answer('human', first, torque_x=0.05)
    sent = [0.05]
    for index in range(1, 10):
        assert sim_client.wait(lambda: len(sim_client.slice_states) >= index), index
        slice_state = sim_client.slice_states[index - 1]
        assert (slice_state.step, slice_state.slice) == (0, index)
        assert slice_state.header.stamp.nanosec == index * 20_000_000
        assert not sim_client.states[1:]        # the step waits for the human's answers
        torque = 0.1 * index if index != 9 else 3.0   # the last beyond the limit: clamped
        sim_client.answer('human', slice_state, torque_x=torque)
        sent.append(min(torque, 0.5))
    state = sim_client.next_state(1)
    assert (state.step, state.slice) == (1, 0)
    assert list(state.human_applied) == pytest.approx(sent)
    assert state.applied_force == 1.0
    assert state.applied_torque == pytest.approx(sum(sent) / 10)
