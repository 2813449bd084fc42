"""The whole graph as separate processes over DDS: sessions run by the session runner.

Each test runs `hrc session` (the same executable a user runs) on its own
ROS_DOMAIN_ID with short episodes (8 s = 40 control steps) so that the suite stays quick, then
checks what a user would: the exit, every step answered, the bags read by an independent reader
(rosbags) with exact counts, and the report.
"""

import collections
import os
import signal
import struct
import subprocess
import time


from hrc_common.executables import executable_path
from hrc_testing.system_topics import check_the_system_is_recorded

STEPS = 40  # control steps per episode in these tests (episode_duration 8 s)
SHORT = ['--set', 'sim.episode_duration=8.0', '--set', 'agent.horizon=80']


def session_command(tmp_path, domain_id, *args):
    """Return the session runner command line for a test session under tmp_path."""
    return [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id', str(domain_id),
            '--bags-dir', str(tmp_path / 'bags'), '--runs-dir', str(tmp_path / 'runs'),
            '--session-id', 'test', *SHORT, *args]


def stamp_of(message):
    """Return the header stamp of a message as a hashable pair."""
    return (message.header.stamp.sec, message.header.stamp.nanosec)


def test_short_session_completes_answered_recorded_and_reported(tmp_path, ros_domain_id,
                                                                read_rosbag):
    result = subprocess.run(session_command(tmp_path, ros_domain_id, '--case', '3',
                                            '--episodes', '2', '--eval-episodes', '1'),
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'the agent finished the session' in result.stdout
    assert 'recorder exit code 0' in result.stdout

    bag = read_rosbag(tmp_path / 'bags' / 'test')
    states = bag['/hrc/state']
    episodes = collections.Counter(state.episode for state in states)
    assert episodes == {0: STEPS + 1, 1: STEPS + 1, 2: STEPS + 1}, episodes
    assert sum(state.truncated for state in states) == 3
    # Every non-final state was answered by both actors, with its stamp, in time.
    asked = {stamp_of(state) for state in states if not state.truncated}
    for topic in ('/hrc/robot/cmd_wrench', '/hrc/human/cmd_wrench'):
        answered = {stamp_of(command) for command in bag[topic]}
        assert asked <= answered, f'{topic}: {len(asked - answered)} steps unanswered'
    assert not any(s.robot_command_missing or s.human_command_missing for s in states)
    assert len(bag['/hrc/agent/step']) == 3 * STEPS
    assert len(bag['/hrc/human/action']) == 3 * STEPS
    summaries = bag['/hrc/episode']
    assert [s.episode for s in summaries] == [0, 1, 2]
    assert [s.evaluation for s in summaries] == [False, False, True]
    assert summaries[-1].steps == STEPS
    assert bag['/hrc/session'][-1].phase == bag['/hrc/session'][-1].PHASE_DONE
    # The system as ROS viewers expect it: joint states with every state, the URDF per file.
    check_the_system_is_recorded(tmp_path / 'bags' / 'test', bag)

    table = (tmp_path / 'runs' / 'test' / 'report' / 'table2.md').read_text()
    row = '| 3 | human first | translation | 1 |'    # case 3's Table II row, one seed
    assert row in table, table
    for figure in ('fig5_training.png', 'fig6_actions.png', 'fig7_three_factor.png'):
        data = (tmp_path / 'runs' / 'test' / 'report' / figure).read_bytes()
        assert data.startswith(b'\x89PNG\r\n\x1a\n') and len(data) > 5000, figure
    assert row in result.stdout, 'the Table II row is printed at the end'


def test_a_node_killed_mid_session_stops_the_session_with_bags_intact(tmp_path, ros_domain_id,
                                                                    read_rosbag):
    runner = subprocess.Popen(session_command(tmp_path, ros_domain_id, '--case', '1',
                                              '--episodes', '50', '--no-report'),
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    logs = tmp_path / 'runs' / 'test' / 'logs'
    bags = tmp_path / 'bags' / 'test'
    deadline = time.monotonic() + 120
    # Wait until two episodes are recorded, then kill the human node hard.
    while len(list(bags.glob('*.mcap'))) < 3:
        assert time.monotonic() < deadline and runner.poll() is None, runner.stdout.read()
        time.sleep(0.2)
    # This session's human node: its command line names this test's parameter file.
    human_pid = int(subprocess.run(
        ['pgrep', '-f', f'human_node --ros-args --params-file {tmp_path}'],
        capture_output=True, text=True).stdout.split()[0])
    os.kill(human_pid, signal.SIGKILL)
    output, _ = runner.communicate(timeout=120)
    assert runner.returncode == 1, output
    assert 'node human stopped unexpectedly (killed by SIGKILL)' in output
    assert 'recorder exit code 0' in output, output
    assert (logs / 'human.log').exists()
    bag = read_rosbag(bags)
    finished = collections.Counter(s.episode for s in bag['/hrc/state'] if s.truncated)
    assert finished[0] == 1 and finished[1] == 1
    assert collections.Counter(s.episode for s in bag['/hrc/state'])[0] == STEPS + 1
    # No process of the session is left behind.
    leftover = subprocess.run(['pgrep', '-f', f'--params-file {tmp_path}'], capture_output=True,
                              text=True).stdout.split()
    assert leftover == [], f'orphan processes: {leftover}'


def js_event(time_ms, value, kind, number):
    """Return one Linux joystick event record (struct js_event)."""
    return struct.pack('IhBB', time_ms, value, kind, number)


def test_a_joystick_fifo_drives_the_human_side(tmp_path, ros_domain_id, read_rosbag):
    fifo = tmp_path / 'js0'
    os.mkfifo(fifo)
    # Hold the FIFO open read-write (never blocks, keeps a writer present), and queue the
    # events a joystick sends: the initial state of axis 1, then the stick pulled half-way
    # down (+16384 raw; the device reports down as +, the node uses the Joy convention up = +).
    writer = os.open(fifo, os.O_RDWR | os.O_NONBLOCK)
    os.write(writer, js_event(0, 0, 0x82, 1) + js_event(10, 16384, 0x02, 1))
    runner = subprocess.Popen(session_command(
        tmp_path, ros_domain_id, '--case', '5', '--human', 'device', '--episodes', '1',
        '--eval-episodes', '0', '--no-report', '--set', f'human.device={fifo}',
        '--set', 'human.axis=1', '--set', 'human.on_input_lost=zero'),
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        output, _ = runner.communicate(timeout=180)
    finally:
        os.close(writer)
    assert runner.returncode == 0, output
    bag = read_rosbag(tmp_path / 'bags' / 'test')
    actions = bag['/hrc/human/action']
    assert len(actions) == STEPS
    assert all(action.source == action.SOURCE_DEVICE for action in actions)
    assert all(str(fifo) in action.source_detail for action in actions)
    # Case 5 (learn together): the human is involved and holds the deflection: half-way down
    # is -(0.5 - deadzone) / (1 - deadzone) with the default deadzone 0.05.
    involved = [action.command for action in actions if action.engaged]
    assert len(involved) == STEPS
    expected = -(16384 / 32767 - 0.05) / 0.95
    assert all(abs(command - expected) < 1e-3 for command in involved), involved[:5]
    wrench = bag['/hrc/human/cmd_wrench'][-1].wrench
    assert wrench.torque.x < 0.0 and wrench.force.z == 0.0  # case 5: the human rotates


def test_a_partners_first_session_is_pre_trained_by_the_runner(tmp_path, ros_domain_id,
                                                               read_rosbag):
    """Case 8: the runner pre-trains (no person) and the graph continues from that checkpoint.

    With 3 episodes the robot alone does not converge, so the pre-training runs out of episodes
    before the person's step and the runner says so; the graph's first episode is the one after
    the pre-training's (the checkpoint was resumed), an evaluation.
    """
    result = subprocess.run(session_command(tmp_path, ros_domain_id, '--case', '8',
                                            '--episodes', '3', '--eval-episodes', '1',
                                            '--set', 'sim.episode_duration=1.0'),
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert '[session] pre-trained with simulated partners (no person): 3 episodes' \
        in result.stdout, result.stdout
    assert 'ran out of episodes before the person' in result.stdout
    run_dir = tmp_path / 'runs' / 'test'
    assert (run_dir / 'pretrain.json').is_file() and (run_dir / 'pretrained.pt').is_file()
    assert f"resume_from: {run_dir / 'pretrained.pt'}" in (run_dir / 'parameters.yaml').read_text()
    summaries = read_rosbag(tmp_path / 'bags' / 'test')['/hrc/episode']
    assert [(summary.episode, summary.evaluation) for summary in summaries] == [(3, True)]
