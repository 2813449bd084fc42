"""The episode recorder core without ROS: boundaries, file format, metadata.yaml, recovery."""

import dataclasses
import shutil

from geometry_msgs.msg import WrenchStamped
from hrc_common.params import validate
from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from mcap.reader import make_reader
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.rosbag2 import Reader
import yaml

from hrc_bag import bag_reader
from hrc_bag.format import RawMessage, RecordingError, SESSION_RECORD, TopicDescription
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.boundaries import boundary_event, boundary_event_of_cdr
from hrc_bag.recording import EpisodeRecorder
from hrc_testing.bag_traffic import (ManualClock, QOS_PROFILE, record_in_process, RecorderFeeder,
                                     strategy_plan, SyntheticSession, type_name_of)

PROFILE = QOS_PROFILE


@pytest.mark.parametrize('changes, reason', [
    ({'session_id': '../escape'}, 'session_id'),
    ({'compression': 'gzip'}, 'compression'),
    ({'flush_period': 0.0}, 'flush_period'),
    ({'topics': []}, 'topics'),
    ({'topics': ['/a', '/a']}, 'topics'),
])
def test_bad_parameters_are_rejected_with_a_reason(changes, reason):
    reasons = validate(dataclasses.replace(RecorderParams(), **changes))
    assert reasons and all(reason in text for text in reasons), reasons


FakeClock = ManualClock
Feeder = RecorderFeeder


def make_recorder(tmp_path, clock, **changes):
    params = dataclasses.replace(RecorderParams(output_dir=str(tmp_path), session_id='s',
                                                close_grace=0.5, summary_timeout=3.0),
                                 **changes)
    return EpisodeRecorder(params, lambda topic, type_name: TopicDescription(
        type_name, (PROFILE,), 'RIHS01_' + '0' * 64), clock=clock)


def file_topics(path):
    return [message.topic for message in bag_reader.scan_file(path).messages]


def test_boundaries_grace_timeout_and_end_file(tmp_path):
    clock = FakeClock()
    recorder = make_recorder(tmp_path, clock)
    feed = Feeder(recorder)
    feed.send('/hrc/session', SessionStatus(session_id='s', episode=0))      # before episode 0
    for step in range(3):
        feed.send('/hrc/state', TaskState(episode=0, step=step, truncated=step == 2))
    feed.send('/hrc/episode', EpisodeSummary(episode=0))
    clock.now += 0.4                                                         # within the grace
    feed.send('/hrc/agent/step', AgentStep(episode=0, step=1))               # late, episode 0
    clock.now += 0.2
    recorder.tick()                                                          # grace over
    assert [info.name for info in recorder.closed_files] == ['s_episode0001.mcap']
    feed.send('/hrc/session', SessionStatus(session_id='s', episode=1, phase=1))  # between
    # episode 1 has no summary: closes summary_timeout after its final state
    feed.send('/hrc/state', TaskState(episode=1, step=0))
    feed.send('/hrc/state', TaskState(episode=1, step=1, terminated=True))
    clock.now += 2.9
    recorder.tick()
    assert len(recorder.closed_files) == 1
    clock.now += 0.2
    recorder.tick()
    assert len(recorder.closed_files) == 2
    # episode 2 is interrupted by a state of episode 3 (no final state, no summary); its
    # file stays open for the grace: a late message of episode 2 still goes to it
    feed.send('/hrc/state', TaskState(episode=2, step=0))
    feed.send('/hrc/state', TaskState(episode=3, step=0))
    feed.send('/hrc/agent/step', AgentStep(episode=2, step=0))
    assert sorted(recorder.open_files) == [2, 3] and recorder.current_episode == 3
    feed.send('/hrc/session', SessionStatus(session_id='s', phase=SessionStatus.PHASE_DONE))
    clock.now += 0.6
    recorder.tick()                                      # the session finished: file closes
    feed.send('/hrc/session', SessionStatus(session_id='s', phase=SessionStatus.PHASE_DONE))
    recorder.close()

    folder = tmp_path / 's'
    assert file_topics(folder / 's_episode0001.mcap') == [
        '/hrc/session', '/hrc/state', '/hrc/state', '/hrc/state', '/hrc/episode',
        '/hrc/agent/step']
    assert file_topics(folder / 's_episode0002.mcap') == ['/hrc/session', '/hrc/state',
                                                     '/hrc/state']
    assert file_topics(folder / 's_episode0003.mcap') == ['/hrc/state', '/hrc/agent/step']
    assert file_topics(folder / 's_episode0004.mcap') == ['/hrc/state', '/hrc/session']
    assert file_topics(folder / 's_end.mcap') == ['/hrc/session']
    listed = bag_reader.read_bag_metadata_yaml(folder)['relative_file_paths']
    assert listed == ['s_episode0001.mcap', 's_episode0002.mcap', 's_episode0003.mcap',
                      's_episode0004.mcap', 's_end.mcap']


def test_messages_are_handled_in_reception_order_after_the_reorder_window(tmp_path):
    """A lagging executor serves one topic late: the window puts it back in order."""
    clock = FakeClock()
    wall = [0]
    recorder = EpisodeRecorder(
        RecorderParams(output_dir=str(tmp_path), session_id='w', reorder_window=0.5,
                       close_grace=0.2),
        lambda topic, type_name: TopicDescription(type_name, (PROFILE,), ''), clock=clock,
        wall_clock=lambda: wall[0])
    second = 1_000_000_000

    def receive(topic, message, received_at):
        type_name = type_name_of(message)
        recorder.record(RawMessage(topic, type_name, serialize_message(message),
                                   received_at, received_at), boundary_event(type_name, message))

    receive('/hrc/state', TaskState(episode=0, step=0), 1 * second)
    receive('/hrc/state', TaskState(episode=0, step=1, truncated=True), 2 * second)
    receive('/hrc/episode', EpisodeSummary(episode=0), 3 * second)
    # DDS received state (1, 0) at 4 s and the human's answer at 5 s, but the executor
    # served the answer first
    receive('/hrc/human/action', SessionStatus(), 5 * second)
    wall[0] = 5 * second + second // 10
    recorder.tick()
    assert recorder.current_episode == 0                  # 4 s, 5 s: still in the window
    receive('/hrc/state', TaskState(episode=1, step=0), 4 * second)
    wall[0] = 6 * second
    clock.now += 1.0
    recorder.tick()
    recorder.close()
    assert file_topics(tmp_path / 'w' / 'w_episode0001.mcap') == ['/hrc/state', '/hrc/state',
                                                             '/hrc/episode']
    assert file_topics(tmp_path / 'w' / 'w_episode0002.mcap') == ['/hrc/state',
                                                                  '/hrc/human/action']
    assert sorted(path.name for path in (tmp_path / 'w').glob('*.mcap')) == [
        'w_episode0001.mcap', 'w_episode0002.mcap']


def test_the_wait_follows_the_executors_lag_so_a_file_closes_with_all_its_messages(tmp_path):
    """A loaded recorder gets states 0.6 s late but the summary at once: the wait grows."""
    wall = [0]
    recorder = EpisodeRecorder(
        RecorderParams(output_dir=str(tmp_path), session_id='lag', reorder_window=0.2),
        lambda topic, type_name: TopicDescription(type_name, (PROFILE,), ''),
        clock=FakeClock(), wall_clock=lambda: wall[0])
    millisecond = 1_000_000
    start = 10_000 * millisecond

    def receive(topic, message, received_at, now):
        wall[0] = now
        type_name = type_name_of(message)
        recorder.record(RawMessage(topic, type_name, serialize_message(message),
                                   received_at, received_at), boundary_event(type_name, message))

    for step in range(3):                 # received at 10.0 s + 10 ms steps, served 0.6 s late
        receive('/hrc/state', TaskState(episode=0, step=step), start + step * 10 * millisecond,
                start + 600 * millisecond)
    # the summary's queue is short: served 50 ms after it was received, before states 3, 4
    receive('/hrc/episode', EpisodeSummary(episode=0), start + 300 * millisecond,
            start + 350 * millisecond + 300 * millisecond)
    wall[0] = start + 800 * millisecond
    recorder.tick()                       # a fixed 0.2 s window would close episode 0 here
    receive('/hrc/state', TaskState(episode=0, step=3), start + 30 * millisecond,
            start + 850 * millisecond)
    receive('/hrc/state', TaskState(episode=0, step=4, truncated=True),
            start + 40 * millisecond, start + 860 * millisecond)
    wall[0] = start + 3000 * millisecond
    recorder.tick()
    assert [info.name for info in recorder.closed_files] == ['lag_episode0001.mcap']
    assert file_topics(tmp_path / 'lag' / 'lag_episode0001.mcap') == ['/hrc/state'] * 5 + [
        '/hrc/episode']
    recorder.close()


def test_messages_go_to_the_file_of_their_episode_whatever_their_order(tmp_path):
    """Episode fields and command stamps route messages even when served out of order."""
    clock = FakeClock()
    recorder = make_recorder(tmp_path, clock, reorder_window=0.0)
    feed = Feeder(recorder)

    def state(episode, step, seconds, final=False):
        message = TaskState(episode=episode, step=step, truncated=final)
        message.header.stamp.sec = seconds
        return message

    def command(seconds):
        message = WrenchStamped()
        message.header.stamp.sec = seconds
        return message

    feed.send('/hrc/state', state(0, 0, 10))
    feed.send('/hrc/state', state(0, 1, 11, final=True))
    feed.send('/hrc/agent/step', AgentStep(episode=1, step=0))        # before its state
    feed.send('/hrc/state', state(1, 0, 12))
    feed.send('/hrc/robot/cmd_wrench', command(10))                    # answers episode 0
    feed.send('/hrc/robot/cmd_wrench', command(12))                    # answers episode 1
    feed.send('/hrc/human/action', HumanAction(episode=0, step=0))
    recorder.close()
    folder = tmp_path / 's'
    assert file_topics(folder / 's_episode0001.mcap') == [
        '/hrc/state', '/hrc/state', '/hrc/robot/cmd_wrench', '/hrc/human/action']
    assert file_topics(folder / 's_episode0002.mcap') == [
        '/hrc/agent/step', '/hrc/state', '/hrc/robot/cmd_wrench']


@pytest.fixture(scope='module')
def recorded(tmp_path_factory):
    """Record a synthetic session of 4 episodes in-process (no DDS)."""
    folder = tmp_path_factory.mktemp('bags')
    plan = strategy_plan('responsibility_guided', 1, 2, 1)
    session = record_in_process(folder, 'core', 2, 'responsibility_guided', 3, plan, steps=6)
    return folder / 'core', session


def test_rosbags_reads_the_session_folder_with_exact_counts_and_values(recorded,
                                                                       rosbags_typestore):
    folder, session = recorded
    assert bag_reader.read_bag_metadata_yaml(folder)['relative_file_paths'] == [
        'core_episode0001.mcap', 'core_episode0002.mcap', 'core_episode0003.mcap',
        'core_episode0004.mcap',
        'core_end.mcap']
    with Reader(folder) as reader:
        assert reader.ros_distro == 'jazzy' and reader.duration > 0
        counts = {connection.topic: connection.msgcount for connection in reader.connections}
        assert counts == {topic: len(messages)
                          for topic, messages in session.published.by_topic.items()}
        assert reader.message_count == session.published.count()
        received = {}
        for connection, _, raw in reader.messages():
            received.setdefault(connection.topic, []).append(raw)
            if connection.topic == '/hrc/state':
                decoded = rosbags_typestore.deserialize_cdr(raw, connection.msgtype)
                assert decoded.header.frame_id == 'world'
        for topic, messages in session.published.by_topic.items():
            # (serializing again is not byte-stable: rclpy leaves CDR padding uninitialized)
            assert [deserialize_message(raw, type(messages[0])) for raw in received[topic]] \
                == messages
        qos = {connection.topic: connection.ext.offered_qos_profiles[0]
               for connection in reader.connections}
        assert qos['/hrc/session'].durability.name == 'TRANSIENT_LOCAL'
        assert qos['/hrc/robot/cmd_wrench'].deadline.sec == 1


def test_each_episode_file_plays_alone_and_carries_the_session_config(recorded):
    folder, session = recorded
    files = sorted(folder.glob('*_episode*.mcap'))
    assert len(files) == 4
    for index, path in enumerate(files):
        with Reader(path) as reader:
            assert reader.message_count > 0
        metadata = bag_reader.read_metadata(path)
        record = metadata[SESSION_RECORD]
        assert record['episode'] == str(index)
        assert record['case_id'] == '2' and record['strategy'] == 'responsibility_guided'
        assert yaml.safe_load(record['session_config'])['seeds'] == {'session': 3}
        rosbag2 = yaml.safe_load(metadata['rosbag2']['serialized_metadata'])
        assert rosbag2['version'] == 9 and rosbag2['relative_file_paths'] == [path.name]


def test_mcap_layout_is_the_rosbag2_profile(recorded):
    folder, session = recorded
    with open(folder / 'core_episode0002.mcap', 'rb') as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert summary.statistics.message_count == sum(
            summary.statistics.channel_message_counts.values()) > 0
        assert summary.chunk_indexes and all(index.message_index_offsets
                                             for index in summary.chunk_indexes)
        assert {schema.encoding for schema in summary.schemas.values()} == {'ros2msg'}
        assert {channel.message_encoding for channel in summary.channels.values()} == {'cdr'}
        for channel in summary.channels.values():
            assert set(channel.metadata) == {'offered_qos_profiles', 'topic_type_hash'}
            assert yaml.safe_load(channel.metadata['offered_qos_profiles'])[0]['reliability'] \
                == 'reliable'
        assert {chunk.compression for chunk in summary.chunk_indexes} == {'zstd'}


def test_a_file_cut_anywhere_reads_up_to_its_last_complete_chunk(recorded, tmp_path):
    folder, session = recorded
    source = folder / 'core_episode0003.mcap'
    complete = bag_reader.scan_file(source)
    data = source.read_bytes()
    previous = 0
    for cut in range(0, len(data), max(1, len(data) // 40)):
        path = tmp_path / 'cut.mcap'
        path.write_bytes(data[:cut])
        scan = bag_reader.scan_file(path)
        assert not scan.complete
        assert scan.messages == complete.messages[:len(scan.messages)]
        assert len(scan.messages) >= previous
        previous = len(scan.messages)


def test_a_later_recorder_finishes_a_left_open_file_and_continues(recorded, tmp_path):
    folder, session = recorded
    copy = tmp_path / 'core'
    shutil.copytree(folder, copy)
    # as if the recorder had been killed during episode 3: drop it from metadata.yaml, cut it
    document = yaml.safe_load((copy / 'metadata.yaml').read_text())
    information = document['rosbag2_bagfile_information']
    information['relative_file_paths'] = information['relative_file_paths'][:3]
    information['files'] = information['files'][:3]
    (copy / 'metadata.yaml').write_text(yaml.safe_dump(document))
    (copy / 'core_end.mcap').unlink()
    path = copy / 'core_episode0004.mcap'
    expected = bag_reader.scan_file(path).messages
    data = path.read_bytes()
    path.write_bytes(data[:len(data) - 700])         # cuts into the summary section
    assert not bag_reader.is_complete(path)
    kept = bag_reader.scan_file(path).messages
    assert 0 < len(kept) <= len(expected)

    recorder = make_recorder(tmp_path, FakeClock(), session_id='core')
    assert recorder.index.listed('core_episode0004.mcap')
    assert bag_reader.is_complete(path)
    assert bag_reader.scan_file(path).messages == kept
    feed = Feeder(recorder)
    feed.send('/hrc/state', TaskState(episode=4, step=0))
    recorder.close()
    assert bag_reader.read_bag_metadata_yaml(copy)['relative_file_paths'] == [
        'core_episode0001.mcap', 'core_episode0002.mcap', 'core_episode0003.mcap',
        'core_episode0004.mcap',
        'core_episode0005.mcap']
    with Reader(copy) as reader:
        assert sum(1 for _ in reader.messages()) == reader.message_count == (
            sum(len(bag_reader.scan_file(file).messages) for file in copy.glob('*.mcap')))


def test_an_unwritable_output_dir_is_a_recording_error(tmp_path):
    blocker = tmp_path / 'file'
    blocker.write_text('not a folder')
    with pytest.raises(RecordingError, match='cannot create the session folder'):
        make_recorder(blocker, FakeClock())


def test_a_recovered_file_names_itself_not_its_temporary_file(recorded, tmp_path):
    from hrc_bag.recovery import recover_file
    folder, _ = recorded
    path = tmp_path / 'core_episode0002.mcap'
    data = (folder / 'core_episode0002.mcap').read_bytes()
    path.write_bytes(data[:len(data) - 700])            # as a killed recorder leaves it
    info = recover_file(path)
    assert info.name == 'core_episode0002.mcap'
    rosbag2 = yaml.safe_load(bag_reader.read_metadata(path)['rosbag2']['serialized_metadata'])
    assert rosbag2['relative_file_paths'] == ['core_episode0002.mcap']
    assert [entry['path'] for entry in rosbag2['files']] == ['core_episode0002.mcap']
    assert not list(tmp_path.glob('.*recovering'))


@pytest.mark.parametrize('personal', [{'subject_id': 'P07'}, {'notes': 'tired'}, {}])
def test_bags_naming_a_subject_or_notes_are_owner_only(tmp_path, personal):
    import os
    from hrc_bag.recovery import recover_file
    plan = strategy_plan('learn_together', 1, 0, 0)
    config = {'session_id': 'p', 'case': 5, 'strategy': 'learn_together', **personal}
    old_umask = os.umask(0o022)
    try:
        record_in_process(tmp_path, 'p', 5, 'learn_together', 1, plan, steps=3,
                          session_config=config)
    finally:
        os.umask(old_umask)
    expected = 0o600 if personal else 0o644
    paths = sorted((tmp_path / 'p').iterdir())
    assert {path.name for path in paths} == {'metadata.yaml', 'p_episode0001.mcap', 'p_end.mcap'}
    assert {path.name: path.stat().st_mode & 0o777 for path in paths} == {
        path.name: expected for path in paths}
    episode = tmp_path / 'p' / 'p_episode0001.mcap'
    data = episode.read_bytes()
    episode.write_bytes(data[:len(data) - 300])
    recover_file(episode)                                # recovery keeps the mode
    assert episode.stat().st_mode & 0o777 == expected


def test_a_recorder_on_a_folder_with_an_unusable_metadata_yaml_lists_the_files_again(
        recorded, tmp_path):
    folder, _ = recorded
    copy = tmp_path / 'core'
    shutil.copytree(folder, copy)
    (copy / 'metadata.yaml').write_text('- a list\n- not rosbag2 metadata\n')
    warnings = []

    class Log:
        def info(self, text):
            pass

        warning = error = warnings.append

    recorder = EpisodeRecorder(
        RecorderParams(output_dir=str(tmp_path), session_id='core'),
        lambda topic, type_name: TopicDescription(type_name, (PROFILE,), ''),
        logger=Log(), clock=FakeClock())
    recorder.close()
    assert any('metadata.yaml cannot be used' in text for text in warnings), warnings
    listed = bag_reader.read_bag_metadata_yaml(copy)['relative_file_paths']
    assert listed == ['core_episode0001.mcap', 'core_episode0002.mcap', 'core_episode0003.mcap',
                      'core_episode0004.mcap', 'core_end.mcap']
    with Reader(copy) as reader:
        assert reader.message_count == sum(
            len(bag_reader.scan_file(path).messages) for path in copy.glob('*.mcap'))


def test_the_graph_is_asked_once_per_topic_and_file_not_per_message(tmp_path):
    """The topic's description (a ROS graph query in the node) only when a channel is made.

    Earlier the recorder asked for it at every message: at the human's rate (ten
    commands a step) that query was most of the recorder's CPU. The files are unchanged: the
    description is used only to register the channel.
    """
    clock = FakeClock()
    asked = []

    def describe(topic, type_name):
        asked.append(topic)
        return TopicDescription(type_name, (PROFILE,), 'RIHS01_' + '0' * 64)

    recorder = EpisodeRecorder(
        RecorderParams(output_dir=str(tmp_path), session_id='q', close_grace=0.2), describe,
        clock=clock)
    feed = Feeder(recorder)
    for episode in range(2):
        for step in range(20):
            feed.send('/hrc/state', TaskState(episode=episode, step=step, truncated=step == 19))
            for _ in range(10):
                feed.send('/hrc/human/cmd_wrench', WrenchStamped())
        feed.send('/hrc/episode', EpisodeSummary(episode=episode))
        clock.now += 1.0
        recorder.tick()
    recorder.close()
    assert asked == ['/hrc/state', '/hrc/human/cmd_wrench', '/hrc/episode'] * 2
    with Reader(tmp_path / 'q') as reader:
        counts = {connection.topic: connection.msgcount for connection in reader.connections}
        assert counts == {'/hrc/state': 40, '/hrc/human/cmd_wrench': 400, '/hrc/episode': 2}
        assert all(connection.ext.offered_qos_profiles for connection in reader.connections)


def test_batches_give_the_files_of_one_message_at_a_time(tmp_path):
    """The node drains its subscriptions in batches: the files, message for message.

    The same stream (a synthetic session: statuses between episodes, states, commands, steps,
    summaries) with the same log times goes in one message at a time (``record``, as the
    synthetic sessions do: each TaskState deserialized) and in batches of 50 (each taken 1 ms
    after its last message arrived; TaskState read from its bytes). A file due to close (at
    once after its EpisodeSummary) closes before the next message of a batch is handled.
    """
    stream = []
    session = SyntheticSession(sink=lambda topic, message: stream.append((topic, message)),
                               session_id='b', seed=3)
    for episode in range(3):
        session.publish_status(episode, human_involved=True)
        session.publish_episode(episode, steps=12, human_involved=True)
    session.publish_status(3, SessionStatus.PHASE_DONE)
    start = 1_700_000_000_000_000_000
    messages = [(RawMessage(topic, type_name_of(message), serialize_message(message),
                            start + index * 1_000_000, start + index * 1_000_000 - 500, index),
                 type(message)) for index, (topic, message) in enumerate(stream)]

    def record(folder, batch: int) -> dict:
        wall = [0]
        clock = FakeClock()
        recorder = EpisodeRecorder(
            RecorderParams(output_dir=str(folder), session_id='b'),
            lambda topic, type_name: TopicDescription(type_name, (PROFILE,)), clock=clock,
            wall_clock=lambda: wall[0])
        for first in range(0, len(messages), batch):
            chunk = messages[first:first + batch]
            wall[0] = chunk[-1][0].log_time + 1_000_000
            clock.now = wall[0] / 1e9
            if batch == 1:
                message, kind = chunk[0]
                recorder.record(message, boundary_event(
                    message.type_name, deserialize_message(message.data, kind)))
            else:
                recorder.record_batch([
                    (message, boundary_event_of_cdr(
                        message.type_name, message.data,
                        lambda data, kind=kind: deserialize_message(data, kind)))
                    for message, kind in chunk])
        recorder.close()
        return {path.name: [(message.topic, message.data, message.log_time,
                             message.publish_time, message.sequence)
                            for message in bag_reader.scan_file(path).messages]
                for path in sorted((folder / 'b').glob('*.mcap'))}

    one_at_a_time = record(tmp_path / 'one', 1)
    assert list(one_at_a_time) == ['b_end.mcap', 'b_episode0001.mcap', 'b_episode0002.mcap',
                                   'b_episode0003.mcap']
    # each status announcing an episode opens its file; the last (done) is the end file's
    assert [topic for topic, *_ in one_at_a_time['b_episode0002.mcap']][:2] == ['/hrc/session',
                                                                          '/hrc/state']
    assert [topic for topic, *_ in one_at_a_time['b_end.mcap']] == ['/hrc/session']
    assert sum(len(file) for file in one_at_a_time.values()) == len(messages)
    assert record(tmp_path / 'batched', 50) == one_at_a_time
