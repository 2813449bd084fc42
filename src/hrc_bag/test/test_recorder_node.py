"""The recorder node over DDS: round trip, SIGKILL, write errors (real processes, real files)."""

import os
import pathlib
import random
import shutil
import signal
import subprocess
import sys
import tempfile

from hrc_common.executables import executable_path
from hrc_testing.nodes import wait_for
from hrc_msgs.msg import SessionStatus
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
import pytest
from rclpy.serialization import deserialize_message
from rosbags.rosbag2 import Reader
import yaml

from hrc_bag import bag_reader
from hrc_bag.format import EPISODE_RECORD, SESSION_RECORD
from hrc_bag.session_writer import contract_descriptions
from hrc_testing.bag_traffic import SyntheticSession
from hrc_testing.recorder_kill import kill_trial

EXIT_RECORDING_FAILED = 3


def start_recorder(start_node, isolation, output_dir, session_id, **parameters):
    values = {'output_dir': str(output_dir), 'session_id': session_id, 'flush_period': 0.2,
              'close_grace': 0.2}
    values.update(parameters)
    return start_node('hrc_bag', 'recorder_node', parameters=values,
                      ros_args=isolation.ros_args)


def listed_files(folder) -> list:
    return bag_reader.read_bag_metadata_yaml(folder).get('relative_file_paths', []) or []


def process_state(pid: int) -> str:
    """Return the scheduler state and wait channel of a process (to tell hung from slow)."""
    try:
        status = pathlib.Path(f'/proc/{pid}/status').read_text()
        state = next(line for line in status.splitlines() if line.startswith('State:'))
        wchan = pathlib.Path(f'/proc/{pid}/wchan').read_text()
        return f'{state.strip()}, waiting in {wchan or "-"}'
    except (OSError, StopIteration):
        return 'gone'


def wait_listed(folder, count, recorder, timeout=60.0):
    assert wait_for(lambda: len(listed_files(folder)) >= count
                    or recorder.process.poll() is not None, timeout), \
        (f'{folder} lists {listed_files(folder)}; recorder {process_state(recorder.process.pid)}'
         f'; output:\n{recorder.output}')
    assert recorder.process.poll() is None, recorder.output


def delivered(session, timeout: float = 60.0) -> bool:
    """Wait until every reader acknowledged all that ``session`` published (reliable QoS).

    A recorder stopped then still records it: at shutdown it takes what waits in DDS.
    """
    from rclpy.duration import Duration

    return all(publisher.wait_for_all_acked(Duration(seconds=timeout))
               for publisher in session.publishers.values())


def by_topic(messages) -> dict:
    result = {}
    for message in messages:
        result.setdefault(message.topic, []).append(message)
    return result


def test_round_trip_read_by_rosbags_and_mcap(start_node, test_node, tmp_path, isolation,
                                              rosbags_typestore):
    config = {'session_id': 'rt', 'case': 3, 'strategy': 'level_guided',
              'roles': {'robot': 'translation', 'human': 'rotation'},
              'seeds': {'session': 5}, 'package_version': '0.1.0',
              'parameters': {'sim': {'max_force': 10.0}, 'agent': {'horizon': 512}}}
    config_path = tmp_path / 'session.yaml'
    config_path.write_text(yaml.safe_dump(config))
    recorder = start_recorder(start_node, isolation, tmp_path / 'bags', 'rt',
                              session_config=str(config_path))
    session = SyntheticSession(test_node, 'rt', case_id=3, strategy='level_guided', seed=5,
                               prefix=isolation.prefix)
    assert session.wait_for_subscribers(), recorder.output
    folder = tmp_path / 'bags' / 'rt'
    session.publish_status(0, human_involved=True)
    session.publish_episode(0, steps=8, human_involved=True, step_period=0.01)
    wait_listed(folder, 1, recorder)
    session.publish_status(1, training_step=1, human_involved=True)
    session.publish_episode(1, steps=8, training_step=1, human_involved=True,
                            step_period=0.01)
    wait_listed(folder, 2, recorder)
    session.publish_status(2, SessionStatus.PHASE_EVALUATION, 1, True)
    session.publish_episode(2, steps=8, training_step=1, human_involved=True, evaluation=True,
                            step_period=0.01)
    wait_listed(folder, 3, recorder)
    session.publish_status(3, SessionStatus.PHASE_DONE, 1, True)
    assert delivered(session), recorder.output
    assert recorder.stop() == 0, recorder.output

    # recorded names carry the test's prefix (the recorder was remapped onto it)
    published = {isolation.name(topic): messages
                 for topic, messages in session.published.by_topic.items()}
    assert listed_files(folder) == ['rt_episode0001.mcap', 'rt_episode0002.mcap',
                                    'rt_episode0003.mcap', 'rt_end.mcap']
    # 1. rosbags on the session folder: exact counts and values per topic
    hashes = {topic: str(test_node.get_publishers_info_by_topic(topic)[0].topic_type_hash)
              for topic in published}
    with Reader(folder) as reader:
        assert {connection.topic: connection.msgcount for connection in reader.connections} \
            == {topic: len(messages) for topic, messages in published.items()}
        received = {}
        for connection, _, raw in reader.messages():
            received.setdefault(connection.topic, []).append(raw)
        for connection in reader.connections:
            assert connection.digest == hashes[connection.topic]
            assert connection.digest.startswith('RIHS01_')
            qos = connection.ext.offered_qos_profiles[0]
            assert qos.reliability.name == 'RELIABLE'
            expected_durability = ('TRANSIENT_LOCAL' if connection.topic in
                                   (isolation.name('/hrc/session'),
                                    isolation.name('/hrc/episode')) else 'VOLATILE')
            assert qos.durability.name == expected_durability
        states = received[isolation.name('/hrc/state')]
        state = rosbags_typestore.deserialize_cdr(states[3], 'hrc_msgs/msg/TaskState')
        assert (state.episode, state.step) == (0, 3)
        assert state.slider_position == published[isolation.name('/hrc/state')][3] \
            .slider_position
    for topic, messages in published.items():
        assert [deserialize_message(raw, type(messages[0])) for raw in received[topic]] \
            == messages, topic

    # 2. the mcap reader on each file: profile, statistics, decoded values
    summaries = []
    for name in listed_files(folder):
        with open(folder / name, 'rb') as stream:
            # (a factory caches decoders by schema id, which is per file: one per file)
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            assert reader.get_header().profile == 'ros2'
            statistics = reader.get_summary().statistics
            decoded = list(reader.iter_decoded_messages())
            assert statistics.message_count == len(decoded)
            # what the in-process SessionWriter writes for the graph's publishers
            descriptions = contract_descriptions()
            for channel in reader.get_summary().channels.values():
                expected = descriptions[channel.topic[len(isolation.prefix):]]
                assert yaml.safe_load(channel.metadata['offered_qos_profiles']) == list(
                    expected.offered_qos_profiles), channel.topic
                assert channel.metadata['topic_type_hash'] == expected.type_description_hash
            summaries += [message for _, channel, _, message in decoded
                          if channel.topic == isolation.name('/hrc/episode')]
            record = {metadata.name: metadata.metadata
                      for metadata in reader.iter_metadata()}[SESSION_RECORD]
            assert yaml.safe_load(record['session_config']) == config
            assert record['case_id'] == '3' and record['strategy'] == 'level_guided'
            assert yaml.safe_load(record['recorder_parameters'])['flush_period'] == 0.2
            # which input drove the human (the synthetic human: simulated, 7 answered steps)
            episode_record = {metadata.name: metadata.metadata
                              for metadata in reader.iter_metadata()}[EPISODE_RECORD]
            if name != 'rt_end.mcap':
                assert episode_record['human_source'] == 'simulated'
                assert yaml.safe_load(episode_record['human_engaged_steps']) == {'simulated': 7}
    assert [(summary.episode, summary.evaluation, summary.total_error) for summary in summaries] \
        == [(summary.episode, summary.evaluation, summary.total_error)
            for summary in published[isolation.name('/hrc/episode')]]
    # the status announcing episode 1 arrived between episodes: it opens episode 1's file
    first = by_topic(bag_reader.scan_file(folder / 'rt_episode0002.mcap').messages)
    assert [deserialize_message(message.data, SessionStatus).episode
            for message in first[isolation.name('/hrc/session')]] == [1]
    end = bag_reader.scan_file(folder / 'rt_end.mcap').messages
    assert [deserialize_message(message.data, SessionStatus).phase for message in end] == [
        SessionStatus.PHASE_DONE]


def test_the_batched_recorder_records_every_published_message_in_its_episodes_file(
        start_node, test_node, tmp_path, isolation):
    """A recorder (drained in batches) of one synthetic session, published fast.

    Every message published, in the file of its episode, in order within each topic, with its
    bytes, source timestamp and sequence number; the log times are the recorder's DDS
    reception times, in order within each topic.
    """
    batched = start_recorder(start_node, isolation, tmp_path / 'batched', 'eq')
    session = SyntheticSession(test_node, 'eq', case_id=5, seed=4, prefix=isolation.prefix,
                               history_depth=1000)
    assert session.wait_for_subscribers(), batched.output
    for episode in range(3):
        session.publish_status(episode, human_involved=True)
        session.publish_episode(episode, steps=20, human_involved=True, step_period=0.002)
        wait_listed(tmp_path / 'batched' / 'eq', episode + 1, batched)
    session.publish_status(3, SessionStatus.PHASE_DONE, human_involved=True)
    assert delivered(session), batched.output
    assert batched.stop() == 0, batched.output
    assert 'drained every 0.05 s' in batched.output

    def files(folder) -> dict:
        recorded = {}
        for name in listed_files(folder):
            topics = by_topic(bag_reader.scan_file(folder / name).messages)
            for messages in topics.values():
                log_times = [message.log_time for message in messages]
                assert log_times == sorted(log_times)
            recorded[name] = {topic: [(message.data, message.publish_time, message.sequence)
                                      for message in messages]
                              for topic, messages in topics.items()}
        return recorded

    from_batches = files(tmp_path / 'batched' / 'eq')
    assert list(from_batches) == ['eq_episode0001.mcap', 'eq_episode0002.mcap',
                                  'eq_episode0003.mcap', 'eq_end.mcap']
    published = {isolation.name(topic): messages
                 for topic, messages in session.published.by_topic.items()}
    everything = {}
    for topics in from_batches.values():
        for topic, messages in topics.items():
            everything.setdefault(topic, []).extend(messages)
    for topic, messages in published.items():
        assert [deserialize_message(data, type(messages[0])) for data, _, _ in
                everything[topic]] == messages, topic
        assert [sequence for _, _, sequence in everything[topic]] == list(
            range(1, len(messages) + 1)), topic


def test_sigkill_keeps_finished_episodes_and_the_open_one_up_to_its_last_chunk(
        start_node, test_node, tmp_path, isolation):
    recorder = start_recorder(start_node, isolation, tmp_path, 'kill')
    session = SyntheticSession(test_node, 'kill', case_id=1, seed=2, prefix=isolation.prefix)
    assert session.wait_for_subscribers(), recorder.output
    folder = tmp_path / 'kill'
    session.publish_status(0)
    session.publish_episode(0, steps=8, step_period=0.01)
    wait_listed(folder, 1, recorder)
    before = session.published.count()
    session.publish_status(1)
    session.publish_episode(1, steps=6, final=False, step_period=0.01)  # running ...
    open_file = folder / 'kill_episode0002.mcap'
    # ... written to disk by a flush (every 0.2 s here) ...
    assert wait_for(lambda: open_file.exists() and len(bag_reader.scan_file(open_file).messages)
                    == session.published.count() - before, 60.0), recorder.output
    os.killpg(recorder.process.pid, signal.SIGKILL)     # ... when the recorder is killed
    recorder.process.wait(timeout=30)

    finished = folder / 'kill_episode0001.mcap'
    with Reader(finished) as reader:
        assert reader.message_count == before
    with Reader(folder) as reader:                      # metadata.yaml lists closed files only
        assert sum(1 for _ in reader.messages()) == before
    assert not bag_reader.is_complete(open_file)
    scan = bag_reader.scan_file(open_file)
    assert not scan.complete
    assert len(scan.messages) == session.published.count() - before
    assert SESSION_RECORD in scan.metadata

    # the report runs on the session as it is
    report = subprocess.run([str(executable_path('hrc_bringup', 'hrc')),
                             'bag', 'report', str(folder),
                             '--out', str(tmp_path / 'report')], capture_output=True,
                            text=True, timeout=120)
    assert report.returncode == 0, report.stderr
    assert 'was not closed' in report.stderr
    assert (tmp_path / 'report' / 'table2.md').is_file()

    # a new recorder of the same session finishes the open file and lists it
    again = start_recorder(start_node, isolation, tmp_path, 'kill')
    assert wait_for(lambda: 'kill_episode0002.mcap' in listed_files(folder), 60.0), again.output
    assert again.stop() == 0, again.output
    with Reader(folder) as reader:
        assert sum(1 for _ in reader.messages()) == session.published.count()


# s: the kill comes this long after the recorder closed an episode of the trial, drawn at
# random (the episode running then is cut anywhere: its state, commands or summary)
KILL_AFTER_CLOSE = (0.0, 1.5)
TRIALS = 4


def test_sigkill_at_random_moments_keeps_every_finished_episode(start_node, test_node,
                                                                tmp_path, isolation):
    """Every episode closed before the kill stays closed and whole; the open ones recover.

    The kill waits for a close (metadata.yaml lists the file), not for a time: how soon a
    finished episode closes is the recorder's own timing, checked on a fake clock
    (test_recorder_durability.py) and measured by bench/recorder_sigkill.py.
    """
    chance = random.Random(20261130)
    for trial in range(TRIALS):
        isolation = type(isolation)()     # topics of the trial's own
        session_id = f'kill{trial}'
        recorder = start_node('hrc_bag', 'recorder_node',
                              parameters={'output_dir': str(tmp_path), 'session_id': session_id},
                              ros_args=isolation.ros_args)
        # (deep publisher histories: what DDS fails to deliver under load is not the point)
        session = SyntheticSession(test_node, session_id, case_id=1, seed=trial,
                                   prefix=isolation.prefix, history_depth=1000)
        assert session.wait_for_subscribers(), recorder.output
        folder = tmp_path / session_id
        result = kill_trial(session, recorder.process.pid, folder,
                            chance.uniform(*KILL_AFTER_CLOSE))
        recorder.process.wait(timeout=30)
        assert result.closed_before_kill, (trial, result.closed)
        for episode in result.closed_before_kill:
            name = f'{session_id}_episode{episode + 1:04d}.mcap'
            assert name in result.closed, (trial, episode, result.closed)
            assert bag_reader.is_complete(folder / name)
        # the files left open were finished by recovery
        assert all(bag_reader.is_complete(path) for path in folder.glob('*.mcap')), trial
        assert result.misplaced == {} and result.undelivered == {}, (
            trial, result.misplaced, result.undelivered)


def _stop(process):
    """Stop a recorder this test started (its own process group) if it still runs."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=10)


def _run_recorder(env, output_dir, command_prefix=(), preexec_fn=None, ros_args=()):
    command = [*command_prefix, str(executable_path('hrc_bag', 'recorder_node')),
               '--ros-args', '-p', f'output_dir:={output_dir}', '-p', 'session_id:=denied',
               *ros_args]
    return subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, preexec_fn=preexec_fn,
                            start_new_session=True)


def test_a_read_only_output_dir_stops_the_recorder_with_a_clear_error(ros_env):
    """Root ignores file modes, so as root the recorder runs as user nobody (setpriv)."""
    # pytest's tmp_path is private to root (0700): nobody could not even reach it
    top = pathlib.Path(tempfile.mkdtemp(prefix='hrc_bag_read_only_'))
    try:
        top.chmod(0o755)
        read_only = top / 'read_only'
        read_only.mkdir()
        read_only.chmod(0o555)
        env = dict(ros_env)
        prefix = ()
        if os.geteuid() == 0:
            log_dir = top / 'ros_log'
            log_dir.mkdir()
            log_dir.chmod(0o777)
            env.update(ROS_LOG_DIR=str(log_dir), HOME=str(log_dir))
            prefix = ('setpriv', '--reuid=65534', '--regid=65534', '--clear-groups')
        process = _run_recorder(env, read_only, prefix)
        try:
            output, _ = process.communicate(timeout=60)
        finally:
            _stop(process)
        assert process.returncode == EXIT_RECORDING_FAILED, output
        assert 'Permission denied (EACCES)' in output, output
        assert f'cannot create the session folder {read_only}/denied' in output, output
        assert not (read_only / 'denied').exists()
    finally:
        shutil.rmtree(top, ignore_errors=True)


def _limit_file_size():
    import resource
    # each file the recorder writes may grow to 40 kB: a long episode fails as a full disk
    resource.setrlimit(resource.RLIMIT_FSIZE, (40_000, 40_000))


def test_a_full_disk_stops_the_recorder_and_keeps_earlier_episodes(ros_env, test_node,
                                                                    tmp_path, isolation):
    """A tmpfs of 100 kB when this machine may mount one (ENOSPC), else a file size limit."""
    mount_point = tmp_path / 'small_disk'
    mount_point.mkdir()
    mounted = subprocess.run(['mount', '-t', 'tmpfs', '-o', 'size=100k', 'tmpfs',
                              str(mount_point)], capture_output=True).returncode == 0
    process = None
    try:
        process = _run_recorder(ros_env, mount_point,
                                preexec_fn=None if mounted else _limit_file_size,
                                ros_args=isolation.ros_args)
        session = SyntheticSession(test_node, 'denied', seed=4, prefix=isolation.prefix)
        assert session.wait_for_subscribers(), 'the recorder did not subscribe'
        session.publish_status(0)
        session.publish_episode(0, steps=8, step_period=0.01)
        folder = mount_point / 'denied'
        assert wait_for(lambda: len(listed_files(folder)) == 1, 60.0)
        first = session.published.count()
        session.publish_episode(1, steps=600, step_period=0.002)
        output, _ = process.communicate(timeout=60)
        assert process.returncode == EXIT_RECORDING_FAILED, output
        expected = 'No space left on device (ENOSPC)' if mounted else 'File too large (EFBIG)'
        assert f'cannot write {folder}/denied_episode0002.mcap: {expected}' in output, output
        assert 'the session must stop' in output
        with Reader(folder) as reader:
            assert sum(1 for _ in reader.messages()) == first
    finally:
        if process is not None:
            _stop(process)
        if mounted:
            subprocess.run(['umount', '-l', str(mount_point)], check=False)


def test_bad_parameters_exit_2_with_the_reason(start_node, tmp_path, isolation):
    recorder = start_recorder(start_node, isolation, tmp_path, 'bad/name')
    assert recorder.wait(timeout=60) == 2
    assert "session_id 'bad/name' is not valid" in recorder.output
    assert not any(tmp_path.iterdir())


if __name__ == '__main__':
    sys.exit(pytest.main([__file__, '-q']))
