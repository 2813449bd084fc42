"""A live session as the operator runs it: pause, resume and abort over DDS, then resume it.

The whole graph runs in separate processes started by the session runner (``ros2 run
hrc_bringup session``) in realtime mode, as with a person, with short episodes (5 s = 25 control
steps) and a short break between them; case 5 (learn together), so that the person acts in
every episode and every episode runs in realtime (in cases 1 and 2 the robot's lonely first
step runs in lockstep). The operator uses the ``operator`` CLI of hrc_live. The
test watches the graph through its own subscriptions and then checks what stays behind: bags
that an independent reader (rosbags) reads, the subject id and notes in the MCAP metadata (and
in no file name), and a checkpoint from which the resumed session continues the counters.
"""

import collections
import json
import os
import pathlib
import re
import shlex
import subprocess
import urllib.request

from hrc_bringup import cli
from hrc_common import qos, topics
from hrc_common.session_control import EXIT_OPERATOR_ABORT
from hrc_common.executables import executable_path
from hrc_testing.live import loose_task_tree, operator, plug_in
from hrc_testing.nodes import wait_for
from hrc_live.study import assign_orders, load_index, register, save_registry
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
from mcap.reader import make_reader
import pytest
import yaml

STEPS = 25  # control steps per episode here (episode_duration 5 s)
LIVE = ['--mode', 'realtime', '--case', '5', '--set', 'sim.episode_duration=5.0',
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
        # The nodes publishing /hrc/session, each time the set changed (sampled while waiting).
        self.session_publishers = []
        # Every status of /diagnostics: (name, level) in order of arrival.
        from diagnostic_msgs.msg import DiagnosticArray
        self.diagnostics = []
        self.node.create_subscription(DiagnosticArray, '/diagnostics', lambda message: (
            self.diagnostics.extend((status.name, status.level[0])
                                    for status in message.status)), 50)

    def sample_session_publishers(self):
        names = tuple(sorted(info.node_name for info in
                             self.node.get_publishers_info_by_topic(topics.SESSION)))
        if not self.session_publishers or self.session_publishers[-1] != names:
            self.session_publishers.append(names)

    def spin(self):
        self.executor.spin_once(0.05)
        self.sample_session_publishers()

    def wait(self, condition, timeout=120.0) -> bool:
        return wait_for(condition, timeout, spin=self.spin)

    def phase(self):
        return self.statuses[-1].phase if self.statuses else None

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()


def session_records(folder):
    """Return the hrc_session MCAP metadata record of every file of a bag folder."""
    records = {}
    for path in sorted(pathlib.Path(folder).glob('*.mcap')):
        with open(path, 'rb') as stream:
            for record in make_reader(stream).iter_metadata():
                if record.name == 'hrc_session':
                    records[path.name] = dict(record.metadata)
    return records


def run_to_the_end(watcher, command, log_path, timeout=300, during=None):
    """Run a session runner to its end while the watcher listens; return (exit code, output).

    ``during(output so far)`` is called while it runs (an operator's or a person's action).
    """
    with open(log_path, 'w+') as log:
        runner = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, text=True)

        def ended():
            if during is not None:
                log.seek(0)
                during(log.read())
            return runner.poll() is not None
        try:
            assert watcher.wait(ended, timeout=timeout)
        finally:
            if runner.poll() is None:
                runner.kill()
                runner.wait()
        log.seek(0)
        return runner.returncode, log.read()


@pytest.fixture
def watcher(rclpy_context):
    watcher = Watcher(rclpy_context)
    yield watcher
    watcher.close()


def test_pause_resume_abort_over_dds_then_resume_from_the_checkpoint(tmp_path, ros_domain_id,
                                                                     watcher,
                                                                     read_rosbag):
    session = [str(executable_path('hrc_bringup', 'hrc')), 'session']
    command = [*session, '--domain-id', str(ros_domain_id), '--bags-dir', str(tmp_path / 'bags'),
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
        # Normally during the first episode; a slow machine may start the command after its end.
        requested = re.search(r'pause: (pause requested: the session pauses when episode '
                              r'(\d+) ends|paused before episode (\d+))', said)
        assert requested, said
        # the operator reads episode numbers (from 1); paused_before is the next's index
        paused_before = (int(requested.group(2)) if requested.group(2) is not None
                         else int(requested.group(3)) - 1)
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
        # the number of the next episode (from 1), and the count of those done
        assert f'episode {paused_before + 1}; {paused_before} training episodes done' in said
        assert len(watcher.states) == states_when_paused

        # Resume: the next episode starts; abort as soon as it runs.
        code, said = operator(ros_domain_id, 'resume')
        assert code == 0, said
        assert f'resumed: episode {paused_before + 1} starts next' in said
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
        assert int(aborted.group(2) or aborted.group(3)) == finished + 1   # from 1
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
                       if line.strip().startswith('hrc session'))
    resume_args = shlex.split(resume_line)[2:]
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
    # With a subject id every output is owner-only, checkpoints and folders included.
    modes = {str(path.relative_to(tmp_path)): path.stat().st_mode & 0o777
             for root in (tmp_path / 'runs', tmp_path / 'bags')
             for path in [root, *root.rglob('*')]}
    assert modes['runs/checkpoints/live/latest.pt'] == 0o600, modes
    assert modes['runs/live'] == modes['runs/checkpoints/live'] == modes['bags/live'] == 0o700
    assert not {name: oct(mode) for name, mode in modes.items() if mode & 0o077}, {
        name: oct(mode) for name, mode in modes.items()}

    # Resume from the checkpoint, one more training episode: the counters continue.
    # Take in what is left of the first run: up to the last state its bags hold (one sim
    # sends them in order, so the earlier ones are in too).
    last = bag['/hrc/state'][-1]
    assert watcher.wait(lambda: any((s.episode, s.step) == (last.episode, last.step)
                                    for s in watcher.states), 60)
    first_state = len(watcher.states)
    code, text = run_to_the_end(watcher, [*session, *resume_args, '--episodes',
                                          str(finished + 1)], tmp_path / 'resumed.log')
    assert code == 0, text
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


# --------------------------------------------------------------------------- the person joins
# Case 2 learns the task first: the robot alone (lockstep, no wall time waited), then the person
# joins (realtime). A task tree with loose tolerances makes each training step converge after
# `convergence_window` (1) episode, so both steps come quickly.
SHORT_STEPS = 15  # control steps per episode (episode_duration 3 s)


def case2_command(tmp_path, domain_id, *extra):
    return [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id', str(domain_id),
            '--bags-dir', str(tmp_path / 'bags'), '--runs-dir', str(tmp_path / 'runs'),
            '--session-id', 'case2', '--case', '2', '--mode', 'realtime',
            '--set', 'sim.episode_duration=3.0', '--set', 'agent.horizon=64',
            '--set', 'agent.episode_break=0.5', '--set', 'agent.convergence_window=1',
            '--set', f'agent.task_tree_file={loose_task_tree(tmp_path)}',
            '--eval-episodes', '0', '--no-report', *extra]


def episode_durations(folder, typestore) -> dict:
    """Return {episode: wall s from its first to its last state}, from the condition's bag.

    The recorder's reception times (beside the sim) are the states' wall times. The bag holds
    the condition only (the practice is recorded apart), so nothing has to be told apart, and
    no state is missed by a busy test process.
    """
    from rosbags.rosbag2 import Reader

    times = collections.defaultdict(list)
    with Reader(folder) as reader:
        connections = [c for c in reader.connections if c.topic == topics.STATE]
        for connection, time_ns, raw in reader.messages(connections=connections):
            state = typestore.deserialize_cdr(raw, connection.msgtype)
            times[state.episode].append(time_ns / 1e9)
    return {episode: max(values) - min(values) for episode, values in times.items()}


def check_clock_switch(durations, summaries, sim_log: str):
    """Assert the robot's lonely episodes ran in lockstep, the person's at the control period.

    The clock of each episode is the one the sim's summary line names (lockstep runs as fast
    as the graph goes, which a busy machine makes as slow as it likes); realtime takes at
    least its periods of wall time.
    """
    alone = [s.episode for s in summaries if not s.human_involved]
    together = [s.episode for s in summaries if s.human_involved]
    assert alone and together and max(alone) < min(together), summaries
    modes = {int(episode): mode for episode, mode in re.findall(
        r'episode (\d+) (?:truncated|terminated) after .*\((lockstep|realtime)\)', sim_log)}
    assert all(modes.get(episode) == 'lockstep' for episode in alone), modes
    assert all(modes.get(episode) == 'realtime' for episode in together), modes
    # Realtime: 15 periods of 0.2 s = 3 s of wall time.
    assert all(durations[episode] > 2.5 for episode in together), \
        [durations[episode] for episode in together]
    return alone, together


def test_case2_robot_alone_in_lockstep_then_realtime_with_the_simulated_human(
        tmp_path, ros_domain_id, watcher, read_rosbag, rosbags_typestore):
    study = tmp_path / 'study'
    subjects = []
    register(subjects, 'P07', 'yes', '2026-11-30')
    assign_orders(subjects, [5, 2])
    save_registry(study, subjects)
    answered = []

    def person_answers_the_tlx(output):
        # After the condition the page asks the NASA-TLX; the runner waits for the answer.
        if answered or 'for the NASA-TLX on the page' not in output:
            return
        log = (tmp_path / 'runs' / 'case2' / 'logs' / 'display.log').read_text()
        port = re.search(r'serving the display on http://127\.0\.0\.1:(\d+)/', log).group(1)
        # As the page does: its origin and the session secret it was served with.
        with urllib.request.urlopen(f'http://127.0.0.1:{port}/', timeout=10) as page:
            token = re.search(r'name="hrc-token" content="([^"]+)"',
                              page.read().decode()).group(1)
        request = urllib.request.Request(
            f'http://127.0.0.1:{port}/tlx', method='POST', data=json.dumps(
                {'mental': 40, 'physical': 10, 'temporal': 30, 'performance': 20,
                 'effort': 50, 'frustration': 15, 'condition': 'case2'}).encode(),
            headers={'Origin': f'http://127.0.0.1:{port}', 'X-HRC-Token': token})
        with urllib.request.urlopen(request, timeout=10) as reply:
            answered.append(reply.read().decode())

    code, text = run_to_the_end(watcher, case2_command(
        tmp_path, ros_domain_id, '--episodes', '8', '--practice', '1', '--subject-id', 'P07',
        '--study-dir', str(study), '--display', '--display-port', '0', '--tlx'),
        tmp_path / 'runner.log', during=person_answers_the_tlx)
    assert code == 0, text
    assert answered == ['Thank you. Stored (raw TLX 27.5).'], text
    assert 'NASA-TLX stored in' in text
    tlx_file = tmp_path / 'runs' / 'case2' / 'tlx.yaml'
    assert tlx_file.stat().st_mode & 0o777 == 0o600
    assert yaml.safe_load(tlx_file.read_text())[0]['session_id'] == 'case2'
    # Practice first: one episode of the person alone (realtime, no robot), recorded apart.
    assert 'practice done: 1 of 1 episodes' in text, text
    # The agent runs the practice too: the one publisher of /hrc/session, practice or not.
    # (a writer seen before its node's name is discovered reads '_NODE_NAME_UNKNOWN_')
    named = {name for names in watcher.session_publishers for name in names}
    assert named - {'_NODE_NAME_UNKNOWN_'} == {'agent'}, watcher.session_publishers
    assert max(map(len, watcher.session_publishers)) == 1, watcher.session_publishers
    practice_statuses = [s for s in watcher.statuses if s.strategy == 'practice']
    assert practice_statuses and all(
        s.session_id == 'case2-practice' and list(s.human_subtasks) == ['slider']
        for s in practice_statuses)
    assert practice_statuses[-1].message == ('practice: episode 1 of 1, the person alone (the '
                                             'robot does not act)')
    assert '[session] the human side is driven by: simulated (paper)' in text
    practice = read_rosbag(tmp_path / 'bags' / 'case2-practice')
    assert [(s.episode, s.step) for s in practice['/hrc/state']] == [
        (0, step) for step in range(SHORT_STEPS + 1)]
    # Case 2: the person drives the slider (force), engaged; the robot (idle here) nothing.
    assert all(w.wrench.torque.x == 0.0 for w in practice['/hrc/human/cmd_wrench'])
    actions = practice['/hrc/human/action']
    assert len(actions) == SHORT_STEPS and all(
        (a.dof, a.source, a.engaged) == (HumanAction.DOF_TRANSLATION,
                                         HumanAction.SOURCE_SIMULATED, True) for a in actions)
    assert not practice.get('/hrc/robot/cmd_wrench')
    # Labelled practice, and not learned from: no AgentStep, one summary of kind practice.
    assert not practice.get('/hrc/agent/step')
    assert [(e.episode, e.kind, e.steps) for e in practice['/hrc/episode']] == [
        (0, EpisodeSummary.KIND_PRACTICE, SHORT_STEPS)]
    assert '| practice]' in text
    assert not (tmp_path / 'runs' / 'checkpoints' / 'case2-practice').exists()
    index = load_index(study)
    assert [(e.subject_id, e.session_id, e.kind, e.position, e.exit_code) for e in index] == [
        ('P07', 'case2-practice', 'practice', 2, 0), ('P07', 'case2', 'condition', 2, 0)]
    assert index[1].tlx_file == str(tlx_file.resolve())
    watcher.summaries[:] = [s for s in watcher.summaries if s.session_id == 'case2']
    alone, together = check_clock_switch(
        episode_durations(tmp_path / 'bags' / 'case2', rosbags_typestore), watcher.summaries,
        (tmp_path / 'runs' / 'case2' / 'logs' / 'sim.log').read_text())
    match = re.search(r'the person joins now, at episode (\d+), \d+ s after the start; the robot '
                      r'practised alone: (\d+) episodes in (?:at most )?(\d+) s', text)
    assert match, text
    assert int(match.group(1)) == min(together) + 1 and int(match.group(2)) == len(alone)
    # One continuous session: one bag folder, consecutive episodes, one checkpoint folder.
    bag = read_rosbag(tmp_path / 'bags' / 'case2')
    assert [s.episode for s in bag['/hrc/episode']] == list(range(len(watcher.summaries)))
    assert {a.source for a in bag['/hrc/human/action']} <= {HumanAction.SOURCE_SIMULATED,
                                                             HumanAction.SOURCE_NONE}
    assert (tmp_path / 'runs' / 'checkpoints' / 'case2' / 'latest.pt').is_file()


class PageWords:
    """Polls the person's page's words (status.json) in a thread; keeps each change."""

    def __init__(self):
        import threading
        self.seen = []              # (banner, notice, episode label), each change once
        self._stop = threading.Event()
        self._thread = None

    def start(self, address: str):
        import threading

        def poll():
            while not self._stop.is_set():
                try:
                    with urllib.request.urlopen(address + 'status.json', timeout=5) as answer:
                        words = json.loads(answer.read())
                    item = (words['banner'], words['notice'], words['episode_label'])
                    if not self.seen or self.seen[-1] != item:
                        self.seen.append(item)
                except OSError:
                    pass
                self._stop.wait(0.1)
        self._thread = threading.Thread(target=poll, daemon=True)
        self._thread.start()

    def stop(self):
        self._stop.set()
        if self._thread is not None:
            self._thread.join(10)

    def banners(self) -> list:
        return [banner for banner, _, _ in self.seen]


def test_case2_with_a_fifo_joystick_that_is_unplugged_mid_episode(tmp_path, ros_domain_id,
                                                                  watcher, read_rosbag,
                                                                  rosbags_typestore):
    fifo = str(tmp_path / 'js0')
    os.mkfifo(fifo)
    log = open(tmp_path / 'runner.log', 'w+')
    runner = subprocess.Popen(case2_command(
        tmp_path, ros_domain_id, '--episodes', '8', '--human', 'device', '--set',
        f'human.device={fifo}', '--set', 'human.reopen_period=0.2', '--input-wait', '120',
        '--display', '--display-port', '0', '--set', 'agent.episode_break=2.0'),
        stdout=log, stderr=subprocess.STDOUT, text=True)

    def output():
        log.seek(0)
        return log.read()

    writer = None
    page_words = PageWords()
    try:
        # Nobody writes to the FIFO yet: the runner waits, says why and how to fix it.
        assert watcher.wait(lambda: 'waiting for the person' in output(), 60), output()
        assert 'no program writes to it' in output() and 'Fix: plug the joystick in' in output()
        assert not watcher.statuses, 'no node may start before the input is there'
        # operator status says what the runner waits for while no agent speaks
        code, said = operator(ros_domain_id, 'status')
        assert code == 0 and "the session runner: waiting for the person's input" in said, said
        # The page is served from the start, its address printed.
        address = re.search(r"the person's page: (http://127\.0\.0\.1:\d+/)", output())
        assert address and output().index("person's page") < output().index('waiting for'), \
            output()
        page_words.start(address.group(1))
        assert watcher.wait(lambda: page_words.seen, 30)
        writer = plug_in(fifo)
        # The person joins (realtime); unplug in the middle of their first episode.
        assert watcher.wait(lambda: any(s.human_involved for s in watcher.statuses), 120), \
            output()
        first = watcher.statuses[-1].total_episodes
        assert watcher.wait(lambda: any(s.episode == first and s.step >= 5
                                        for s in watcher.states), 60), output()
        os.close(writer)
        writer = None
        assert watcher.wait(lambda: 'joystick disconnected' in output(), 30), output()
        assert watcher.wait(lambda: watcher.phase() == SessionStatus.PHASE_PAUSED, 30), output()
        assert 'joystick disconnected' in watcher.statuses[-1].message
        code, said = operator(ros_domain_id, 'status')
        assert code == 0 and 'phase paused' in said and 'joystick disconnected' in said, said
        # The sim holds: the interrupted episode gets no final state and no state comes.
        states_when_paused = len(watcher.states)
        watcher.wait(lambda: False, timeout=1.5)
        assert len(watcher.states) == states_when_paused
        assert not any(s.episode == first and s.truncated for s in watcher.states)
        # Resume while unplugged: refused, with the reason.
        code, said = operator(ros_domain_id, 'resume')
        assert code == 1 and 'still disconnected' in said, said
        writer = plug_in(fifo)
        # Back: said on /hrc/session, by operator status and on the page before any resume.
        assert watcher.wait(lambda: 'connected again' in watcher.statuses[-1].message, 30), \
            output()
        code, said = operator(ros_domain_id, 'status')
        assert code == 0 and 'connected again' in said, said
        assert watcher.wait(lambda: any('The joystick is connected again' in banner
                                        for banner in page_words.banners()), 30), \
            page_words.banners()
        code, said = operator(ros_domain_id, 'resume')
        assert code == 0 and 'resumed' in said, said
        # /diagnostics: the human node's input went to ERROR while unplugged, and back to OK
        lost_at = next(index for index, item in enumerate(watcher.diagnostics)
                       if item == ('human: input', 2))
        assert watcher.wait(lambda: ('human: input', 0) in watcher.diagnostics[lost_at:], 30), \
            watcher.diagnostics
        assert watcher.wait(lambda: runner.poll() is not None, timeout=240), output()
    finally:
        page_words.stop()
        if writer is not None:
            os.close(writer)
        if runner.poll() is None:
            runner.kill()
            runner.wait()
    text = output()
    assert runner.returncode == 0, text
    assert {'sim: timing', 'recorder: writing', 'human: input', 'agent: learner'} <= {
        name for name, _ in watcher.diagnostics}, watcher.diagnostics
    # The terminal says a pause for the joystick, never an operator's abort.
    assert 'phase aborted' not in text and 'session aborted by the operator' not in text, text
    assert 'the joystick is connected again' in text, text
    # The agent held the session in its own process: no second agent was started.
    assert 'resumed by the operator: the agent goes on in its process' in text, text
    logs = tmp_path / 'runs' / 'case2' / 'logs'
    assert not list(logs.glob('agent-before-resume-*')), list(logs.iterdir())
    assert 'held for the lost input in episode' in (logs / 'agent.log').read_text()
    # What the person read, in order: the lost joystick (never "stopped by the
    # operator", no FIFO detail), then the countdown of the resume, then their turn again.
    from hrc_live.display_words import INPUT_LOST_BANNER, INPUT_LOST_NOTICE
    banners = page_words.banners()
    assert banners[0] == 'Please wait: the session is starting', banners
    lost = banners.index(INPUT_LOST_BANNER)
    assert not any('Stopped by the operator' in banner for banner in banners), banners
    assert all('FIFO' not in notice for _, notice, _ in page_words.seen), page_words.seen
    assert (INPUT_LOST_BANNER, INPUT_LOST_NOTICE) in {(b, n) for b, n, _ in page_words.seen}
    after = banners[lost:]
    countdown = next(i for i, b in enumerate(after) if b.startswith('Get ready: the next '
                                                                   'round starts in'))
    assert any(b.startswith('Your turn') for b in after[countdown:]), after
    # (a label shown before the display has read the agent's plan has no maximum: "Round N")
    assert all(int(re.search(r'of at most (\d+)', label).group(1)) >= int(
        re.search(r'Round (\d+)', label).group(1)) for _, _, label in page_words.seen
        if label.startswith('Round ') and 'of at most' in label), page_words.seen
    summaries = watcher.summaries
    check_clock_switch(episode_durations(tmp_path / 'bags' / 'case2', rosbags_typestore),
                       summaries, (tmp_path / 'runs' / 'case2' / 'logs' / 'sim.log').read_text())
    # The interrupted episode ran again from its start; the counters continue.
    assert [s.episode for s in summaries] == list(range(len(summaries)))
    assert any(s.episode == first and s.step == 0 for s in watcher.states[states_when_paused:])
    # No simulated input recorded as the subject's: the device or zero (lost / not involved).
    bag = read_rosbag(tmp_path / 'bags' / 'case2')
    sources = collections.Counter((a.source, a.engaged) for a in bag['/hrc/human/action'])
    assert HumanAction.SOURCE_SIMULATED not in {source for source, _ in sources}, sources
    assert sources[(HumanAction.SOURCE_DEVICE, True)] >= SHORT_STEPS, sources
    assert [s.episode for s in bag['/hrc/episode']] == list(range(len(summaries)))
    # Each attempt of the interrupted episode is filed as itself: the dropped one in
    # its own file, the complete re-run in <id>_ep<n>_attempt2.mcap, both in metadata.yaml;
    # the report counts the re-run and says so.
    from hrc_bag import bag_reader
    folder = tmp_path / 'bags' / 'case2'
    dropped = folder / f'case2_episode{first + 1:04d}.mcap'
    rerun = folder / f'case2_episode{first + 1:04d}_attempt2.mcap'

    def states_of(path):
        decoder = bag_reader.MessageDecoder()
        decoded = (decoder.decode(m) for m in bag_reader.scan_file(path, ['/hrc/state']).messages)
        return [s for s in decoded if s.episode == first]
    assert 0 < len(states_of(dropped)) < SHORT_STEPS + 1
    assert [s.step for s in states_of(rerun)] == list(range(SHORT_STEPS + 1))
    if (folder / 'case2_end.mcap').exists():
        assert not states_of(folder / 'case2_end.mcap')
    listed = bag_reader.read_bag_metadata_yaml(folder)['relative_file_paths']
    assert dropped.name in listed and rerun.name in listed, listed
    assert bag_reader.scan_file(rerun).metadata['hrc_episode']['attempt'] == '2'
    from hrc_bag.report.loading import load_session
    report = load_session(folder)
    assert report.files_by_episode[first] == [rerun] and report.attempts[first] == [dropped,
                                                                                    rerun]
    assert any(f'episode {first + 1} was recorded 2 times' in notice   # a number from 1
               and f'its time and errors are from {rerun.name}' in notice
               for notice in report.notices), report.notices


# --------------------------------------------------------------------------- refusals
def test_a_domain_id_outside_the_dds_range_is_refused_before_anything_starts(tmp_path, capsys):
    # In this process (the `hrc` command's entry point; a process of its own spends seconds on
    # imports only to refuse): a traceback would fail the test, as would a started session.
    code = cli.main(['session', '--domain-id', '233', '--runs-dir', str(tmp_path / 'runs'),
                     '--bags-dir', str(tmp_path / 'bags')])
    output = capsys.readouterr()
    assert code == 2, output.out + output.err
    assert '--domain-id 233 is outside the range of DDS domain ids 0..232' in output.err
    assert 'Traceback' not in output.err and not (tmp_path / 'runs').exists()


def test_a_robot_that_does_not_converge_is_said_and_the_pages_addresses_printed(
        tmp_path, ros_domain_id, watcher):
    """Case 2 with a cap of 2 episodes: the robot alone never converges (paper tolerances)."""
    command = [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id',
               str(ros_domain_id), '--bags-dir', str(tmp_path / 'bags'), '--runs-dir',
               str(tmp_path / 'runs'), '--session-id', 'nc', '--case', '2',
               '--set', 'sim.episode_duration=3.0', '--set', 'agent.horizon=64',
               '--episodes', '2', '--eval-episodes', '1', '--no-report', '--display',
               '--display-port', '0']
    code, text = run_to_the_end(watcher, command, tmp_path / 'runner.log')
    assert code == 0, text
    page = re.search(r"\[session\] the person's page: (http://127\.0\.0\.1:\d+/)   the "
                     r"experimenter's console: (http://127\.0\.0\.1:\d+/console)", text)
    assert page and page.group(2) == page.group(1) + 'console', text
    # printed before the session's first word on the terminal (under load the runner's session
    # reader can match after the first announcements, once after the whole 10 s session: the
    # first line is then a later step's status, or the agent's end)
    positions = [text.find(words) for words in (
        '[session] case 2 responsibility_guided: training step',
        '[session] the agent finished the session')]           # always said on exit 0
    first_word = min(position for position in positions if position >= 0)
    assert text.index("the person's page") < first_word, text
    assert ('[session] the robot did not converge in 2 episodes (training step 1 of 2, at '
            'most 2); the person never trained with the robot; the test episodes start'
            in text), text
