"""A live session as the operator runs it: pause, resume and abort over DDS, then resume it.

The whole graph runs in separate processes started by the session runner (``ros2 run
hrc_bringup session``) in realtime mode, as with a person, with short episodes (4 s = 20 control
steps) and a short break between them. The operator uses the ``operator`` CLI of hrc_live. The
test watches the graph through its own subscriptions and then checks what stays behind: bags
that an independent reader (rosbags) reads, the subject id and notes in the MCAP metadata (and
in no file name), and a checkpoint from which the resumed session continues the counters.
"""

import collections
import pathlib
import re
import shlex
import subprocess

from hrc_common import qos, topics
from hrc_common.session_control import EXIT_OPERATOR_ABORT
from hrc_common.testing import executable_path, wait_for
from hrc_msgs.msg import EpisodeSummary, SessionStatus, TaskState
from mcap.reader import make_reader
import pytest
import yaml

STEPS = 25  # control steps per episode here (episode_duration 5 s)
LIVE = ['--mode', 'realtime', '--case', '1', '--set', 'sim.episode_duration=5.0',
        '--set', 'agent.horizon=80', '--set', 'agent.episode_break=0.5', '--no-report']
SUBJECT, NOTES = 'P07', 'left-handed; first session'


class Watcher:
    """The test's view of the graph: every state, session status and episode summary."""

    def __init__(self, context):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node('test_live_watcher', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.states, self.statuses, self.summaries = [], [], []
        self.node.create_subscription(TaskState, topics.STATE, self.states.append,
                                      qos.STATE_QOS)
        self.node.create_subscription(SessionStatus, topics.SESSION, self.statuses.append,
                                      qos.SESSION_QOS)
        self.node.create_subscription(EpisodeSummary, topics.EPISODE, self.summaries.append,
                                      qos.EPISODE_QOS)

    def wait(self, condition, timeout=120.0) -> bool:
        return wait_for(condition, timeout, spin=lambda: self.executor.spin_once(0.05))

    def phase(self):
        return self.statuses[-1].phase if self.statuses else None

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()


def operator(domain_id, command):
    """Run ``ros2 run hrc_live operator <command>``; return (exit code, output)."""
    result = subprocess.run([str(executable_path('hrc_live', 'operator')), command,
                             '--domain-id', str(domain_id), '--timeout', '30'],
                            capture_output=True, text=True, timeout=120)
    return result.returncode, result.stdout + result.stderr


def session_records(folder):
    """Return the hrc_session MCAP metadata record of every file of a bag folder."""
    records = {}
    for path in sorted(pathlib.Path(folder).glob('*.mcap')):
        with open(path, 'rb') as stream:
            for record in make_reader(stream).iter_metadata():
                if record.name == 'hrc_session':
                    records[path.name] = dict(record.metadata)
    return records


@pytest.fixture
def watcher(rclpy_context):
    watcher = Watcher(rclpy_context)
    yield watcher
    watcher.close()


def test_pause_resume_abort_over_dds_then_resume_from_the_checkpoint(tmp_path, ros_domain_id,
                                                                     watcher,
                                                                     read_rosbag):
    session = str(executable_path('hrc_bringup', 'session'))
    command = [session, '--domain-id', str(ros_domain_id), '--bags-dir', str(tmp_path / 'bags'),
               '--runs-dir', str(tmp_path / 'runs'), '--session-id', 'live', *LIVE,
               '--episodes', '20', '--eval-episodes', '0', '--subject-id', SUBJECT,
               '--notes', NOTES]
    log = open(tmp_path / 'runner.log', 'w+')
    runner = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, text=True)

    def output():
        log.seek(0)
        return log.read()

    try:
        # Episode 0 runs; the operator asks for a pause: it comes when the episode ends.
        assert watcher.wait(lambda: any(s.episode == 0 and s.step >= 2
                                        for s in watcher.states)), output()
        code, said = operator(ros_domain_id, 'pause')
        assert code == 0, said
        # Normally during episode 0; a slow machine may start the command after its end.
        requested = re.search(r'pause: (pause requested: the session pauses when episode '
                              r'(\d+) ends|paused before episode (\d+))', said)
        assert requested, said
        paused_before = (int(requested.group(2)) + 1 if requested.group(2) is not None
                         else int(requested.group(3)))
        assert watcher.wait(lambda: watcher.phase() == SessionStatus.PHASE_PAUSED), output()
        paused = watcher.statuses[-1]
        assert paused.episode == paused.total_episodes == paused_before
        # It took effect at the episode boundary: the episode ran to its final state.
        assert any(s.episode == paused_before - 1 and s.truncated for s in watcher.states)
        # Paused: the agent does not reset the sim, so no state comes.
        states_when_paused = len(watcher.states)
        watcher.wait(lambda: False, timeout=1.5)
        assert len(watcher.states) == states_when_paused
        code, said = operator(ros_domain_id, 'status')
        assert code == 0 and 'phase paused' in said, said
        assert f'episode {paused_before}; {paused_before} training episodes done' in said
        assert len(watcher.states) == states_when_paused

        # Resume: the next episode starts; abort as soon as it runs.
        code, said = operator(ros_domain_id, 'resume')
        assert code == 0, said
        assert f'resumed: episode {paused_before} starts next' in said
        assert watcher.wait(lambda: any(s.episode == paused_before and s.step >= 1
                                        for s in watcher.states)), output()
        code, said = operator(ros_domain_id, 'abort')
        assert code == 0, said
        aborted = re.search(r'abort: aborted (in episode (\d+) at step \d+[^;]*|before episode '
                            r'(\d+)); resume from \S+latest.pt \((\d+) training episodes\)',
                            said)
        assert aborted, said
        finished = int(aborted.group(4))   # training episodes in the checkpoint
        mid_episode = aborted.group(2) is not None
        assert int(aborted.group(2) or aborted.group(3)) == finished
        assert runner.wait(timeout=120) == EXIT_OPERATOR_ABORT, output()
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()
    text = output()
    assert 'the operator aborted the session' in text
    assert 'recorder exit code 0' in text, text
    assert watcher.wait(lambda: watcher.phase() == SessionStatus.PHASE_ABORTED, 30)
    # After the abort the sim held: the aborted episode has no final state.
    assert not any(s.episode == finished and (s.truncated or s.terminated)
                   for s in watcher.states)
    checkpoint = tmp_path / 'runs' / 'checkpoints' / 'live' / 'latest.pt'
    assert checkpoint.is_file()
    resume_line = next(line.strip() for line in text.splitlines()
                       if line.strip().startswith('ros2 run hrc_bringup session'))
    resume_args = shlex.split(resume_line)[4:]
    assert resume_args[-4:] == ['--session-id', 'live', '--resume-from', str(checkpoint)]
    assert resume_args.count('--subject-id') == 1 and NOTES in resume_args

    # The bags: closed, readable by rosbags; the aborted episode ends with zero commands.
    bags = tmp_path / 'bags' / 'live'
    bag = read_rosbag(bags)
    episodes = collections.Counter(s.episode for s in bag['/hrc/state'])
    assert all(episodes[episode] == STEPS + 1 for episode in range(finished)), episodes
    if mid_episode:
        assert 0 < episodes[finished] < STEPS + 1, episodes
    assert bag['/hrc/session'][-1].phase == SessionStatus.PHASE_ABORTED
    assert [s.episode for s in bag['/hrc/episode']] == list(range(finished))
    last_robot = bag['/hrc/robot/cmd_wrench'][-1].wrench
    assert (last_robot.force.z, last_robot.torque.x) == (0.0, 0.0)
    assert any(p.phase == SessionStatus.PHASE_PAUSED for p in bag['/hrc/session'])

    # Subject id and notes travel in every file's metadata, never in a file name.
    records = session_records(bags)
    assert records and all(yaml.safe_load(record['session_config'])['subject_id'] == SUBJECT
                           and yaml.safe_load(record['session_config'])['notes'] == NOTES
                           for record in records.values()), records
    names = [path.name for path in tmp_path.rglob('*')]
    assert not [name for name in names if SUBJECT.lower() in name.lower()]

    # Resume from the checkpoint, one more training episode: the counters continue.
    watcher.wait(lambda: False, timeout=1.0)  # take in what is left of the first run
    first_state = len(watcher.states)
    resumed_log = open(tmp_path / 'resumed.log', 'w+')
    resumed = subprocess.Popen([session, *resume_args, '--episodes', str(finished + 1)],
                               stdout=resumed_log, stderr=subprocess.STDOUT, text=True)
    try:
        assert watcher.wait(lambda: resumed.poll() is not None, timeout=300)
    finally:
        if resumed.poll() is None:
            resumed.kill()
            resumed.wait()
    resumed_log.seek(0)
    text = resumed_log.read()
    assert resumed.returncode == 0, text
    assert 'the agent finished the session' in text
    assert watcher.wait(lambda: watcher.phase() == SessionStatus.PHASE_DONE, 30)
    new_states = watcher.states[first_state:]
    assert new_states and new_states[0].episode == finished and new_states[0].step == 0
    assert {s.episode for s in new_states} == {finished}
    done = watcher.statuses[-1]
    assert (done.total_episodes, done.episode) == (finished + 1, finished + 1)
    bag = read_rosbag(bags)
    assert [s.episode for s in bag['/hrc/episode']] == list(range(finished + 1))
    truncated = [s.episode for s in bag['/hrc/state'] if s.truncated]
    assert truncated == list(range(finished + 1))
    resumed_logs = list((tmp_path / 'runs' / 'live').glob('logs-resumed-*'))
    assert len(resumed_logs) == 1 and (tmp_path / 'runs' / 'live' / 'logs' / 'agent.log').is_file()
    # The resumed run records into the same session folder, with the same metadata.
    assert len(session_records(bags)) > len(records)
