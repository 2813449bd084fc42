"""The format layer: an in-process SessionWriter (no rclpy) writes the recorder's bags."""

import json
import os
import subprocess
import sys

from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from mcap.reader import make_reader
import pytest
from rclpy.serialization import serialize_message
from rosbags.rosbag2 import Reader
import yaml

from hrc_bag import bag_reader, cdr_peek, report
from hrc_bag.boundaries import boundary_event
from hrc_bag.format import (contract_description, EPISODE_RECORD, episode_file_key,
                            episode_file_stem, FileInfo, plain_values, RawMessage,
                            SESSION_RECORD)
from hrc_bag.qos_yaml import dump_yaml
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.recording import EpisodeRecorder
from hrc_bag.session_index import bag_metadata, dump_bag_metadata
from hrc_bag.session_writer import contract_descriptions, SessionWriter, TOPIC_TYPES
from hrc_testing.bag_traffic import SyntheticSession, type_name_of

START_NS = 1_700_000_000_000_000_000
CONFIG = {'session_id': 'fmt', 'case': 1, 'strategy': 'responsibility_guided',
          'roles': {'robot': 'translation', 'human': 'rotation'}, 'seeds': {'session': 7},
          'package_version': '0.1.0'}

# Runs in a fresh interpreter: reads the messages as JSON, writes them with SessionWriter, and
# proves that neither the writer nor the encoder imported rclpy.
WRITER_SCRIPT = r"""
import json, sys
from hrc_bag.format import contract_description
from hrc_bag.session_writer import SessionWriter, TOPIC_TYPES
job = json.load(sys.stdin)
descriptions = {topic: contract_description(TOPIC_TYPES[topic], *offer)
                for topic, offer in job['offers'].items()}
writer = SessionWriter(job['output_dir'], job['session_id'], session_config=job['config'],
                       descriptions=descriptions)
for kind, topic, message, log_time in job['events']:
    if kind == 'begin':
        writer.begin_episode(message)
    elif kind == 'end':
        writer.end_episode()
    else:
        writer.write(topic, message, log_time)
writer.close()
loaded = sorted(name for name in sys.modules if name.split('.')[0] == 'rclpy')
print(json.dumps(loaded))
"""

OFFERS = {  # topic: (reliable, transient_local, deadline ns), as hrc_common.qos offers them
    '/hrc/state': (True, False, 0), '/hrc/robot/cmd_wrench': (True, False, 1_000_000_000),
    '/hrc/human/cmd_wrench': (True, False, 1_000_000_000), '/hrc/human/action': (True, False, 0),
    '/hrc/session': (True, True, 0), '/hrc/episode': (True, True, 0),
    '/hrc/agent/step': (True, False, 0), '/robot_description': (True, True, 0),
    '/joint_states': (True, False, 0)}


def synthetic_traffic():
    """Return [(topic, rclpy message, log time ns)] of a 3-episode session (+ a final status)."""
    traffic = []
    session = None

    def sink(topic, message):
        traffic.append((topic, message, START_NS + session.sim_time_ns + len(traffic) * 1000))

    session = SyntheticSession(None, 'fmt', case_id=1, seed=7, sink=sink)
    for episode in range(3):
        session.publish_status(episode, human_involved=episode > 0)
        session.publish_episode(episode, steps=5, human_involved=episode > 0,
                                evaluation=episode == 2)
    session.publish_status(3, SessionStatus.PHASE_DONE)
    return traffic


def record_with_the_recorder(traffic, output_dir):
    """Record ``traffic`` with the recorder core, QoS described as the live graph offers it."""
    clock = [0.0]
    params = RecorderParams(output_dir=str(output_dir), session_id='fmt')
    descriptions = contract_descriptions()
    recorder = EpisodeRecorder(params, lambda topic, type_name: descriptions[topic],
                               session_config=CONFIG, clock=lambda: clock[0],
                               wall_clock=lambda: traffic[-1][2] + 10**10)
    for sequence, (topic, message, log_time) in enumerate(traffic):
        type_name = type_name_of(message)
        recorder.record(RawMessage(topic, type_name, serialize_message(message), log_time,
                                   log_time, sequence), boundary_event(type_name, message))
        if type_name.endswith('EpisodeSummary'):
            clock[0] += params.close_grace + 0.1
            recorder.tick()
    recorder.close()


def write_without_rclpy(traffic, output_dir):
    """Write ``traffic`` with SessionWriter in a fresh interpreter; return its rclpy modules."""
    events = []
    for topic, message, log_time in traffic:
        values = plain_values(message)
        if topic == '/hrc/state' and values['step'] == 0:
            events.append(['begin', topic, values['episode'], log_time])
        events.append(['write', topic, values, log_time])
        if topic == '/hrc/episode':
            events.append(['end', topic, None, log_time])
    job = {'output_dir': str(output_dir), 'session_id': 'fmt', 'config': CONFIG,
           'offers': OFFERS, 'events': events}
    result = subprocess.run([sys.executable, '-c', WRITER_SCRIPT], input=json.dumps(job),
                            capture_output=True, text=True, timeout=120, env=dict(os.environ))
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.splitlines()[-1])


@pytest.fixture(scope='module')
def both(tmp_path_factory):
    """Write the same session with the recorder core and with SessionWriter (no rclpy)."""
    traffic = synthetic_traffic()
    recorder_dir = tmp_path_factory.mktemp('recorder')
    writer_dir = tmp_path_factory.mktemp('writer')
    record_with_the_recorder(traffic, recorder_dir)
    rclpy_modules = write_without_rclpy(traffic, writer_dir)
    return traffic, recorder_dir / 'fmt', writer_dir / 'fmt', rclpy_modules


def test_the_writer_needs_no_rclpy(both):
    assert both[3] == []


def test_rosbags_reads_the_written_session_with_exact_values(both, rosbags_typestore):
    traffic, _, folder, _ = both
    with Reader(folder) as reader:
        decoded = [(connection.topic,
                    rosbags_typestore.deserialize_cdr(raw, connection.msgtype), time)
                   for connection, time, raw in reader.messages()]
        digests = {connection.topic: connection.digest for connection in reader.connections}
    assert len(decoded) == len(traffic)
    by_time = {time: (topic, message) for topic, message, time in traffic}
    for topic, message, time in decoded:
        assert by_time[time][0] == topic
        assert plain_values(message) == plain_values(by_time[time][1]), topic
    assert set(digests) == {topic for topic, _, _ in traffic} <= set(TOPIC_TYPES)
    assert digests == {topic: contract_descriptions()[topic].type_description_hash
                       for topic in digests}
    assert all(digest.startswith('RIHS01_') for digest in digests.values())


def test_the_report_loader_reads_it(both):
    session = report.load_session(both[2])
    assert session.complete and session.session_id == 'fmt'
    assert (session.case_id, session.strategy, session.robot_dof, session.seed) == (
        1, 'responsibility_guided', 'translation', '7')
    assert [(summary.episode, summary.evaluation) for summary in session.summaries] == [
        (0, False), (1, False), (2, True)]
    assert sorted(session.files_by_episode) == [0, 1, 2]


def _file_layout(path) -> dict:
    with open(path, 'rb') as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        metadata = {record.name: dict(record.metadata) for record in reader.iter_metadata()}
        channels = {channel.topic: (summary.schemas[channel.schema_id].name,
                                    bytes(summary.schemas[channel.schema_id].data),
                                    channel.message_encoding, dict(channel.metadata))
                    for channel in summary.channels.values()}
        return {'profile': reader.get_header().profile, 'channels': channels,
                'counts': sorted(summary.statistics.channel_message_counts.values()),
                'compression': {chunk.compression for chunk in summary.chunk_indexes},
                'records': metadata}


def test_the_files_are_the_recorders_files(both):
    _, recorder_folder, writer_folder, _ = both
    recorded = bag_reader.read_bag_metadata_yaml(recorder_folder)
    written = bag_reader.read_bag_metadata_yaml(writer_folder)
    assert written['relative_file_paths'] == recorded['relative_file_paths'] == [
        'fmt_episode0001.mcap', 'fmt_episode0002.mcap', 'fmt_episode0003.mcap', 'fmt_end.mcap']
    for key in ('version', 'storage_identifier', 'message_count', 'topics_with_message_count',
                'files', 'starting_time', 'duration', 'custom_data'):
        assert written[key] == recorded[key], key
    for name in recorded['relative_file_paths']:
        ours, theirs = _file_layout(writer_folder / name), _file_layout(recorder_folder / name)
        for key in ('profile', 'channels', 'counts', 'compression'):
            assert ours[key] == theirs[key], (name, key)
        assert set(ours['records']) == set(theirs['records']) == {SESSION_RECORD, 'rosbag2',
                                                                  EPISODE_RECORD}
        assert ours['records'][EPISODE_RECORD] == theirs['records'][EPISODE_RECORD], name
        ours_record, theirs_record = ours['records'][SESSION_RECORD], \
            theirs['records'][SESSION_RECORD]
        assert set(ours_record) == set(theirs_record)
        for key in ('session_id', 'episode', 'case_id', 'strategy', 'roles', 'seeds',
                    'package_version', 'session_config'):
            assert ours_record[key] == theirs_record[key], (name, key)
        assert yaml.safe_load(ours_record['session_status']) == (
            yaml.safe_load(theirs_record['session_status']))
        assert ours['records']['rosbag2'] == theirs['records']['rosbag2'], name


@pytest.mark.parametrize('stem, key', [
    ('s_episode0001', (0, 1)), ('s_episode0061_attempt2', (60, 2)), ('s_episode0002_2', (1, 2)),
    ('s_ep0000', (0, 1)), ('s_ep0060_attempt3', (60, 3)),     # before hrc 1.0: the index
    ('case2-seed0_episode0120', (119, 1)), ('s_end', None), ('notes', None)])
def test_an_episode_file_name_gives_its_index_and_attempt(stem, key):
    assert episode_file_key(stem) == key


def test_files_are_named_by_the_episode_number_people_read_and_ordered_with_old_names():
    assert episode_file_stem('s', 0) == 's_episode0001'
    assert episode_file_stem('s', None) == 's_end'
    names = ['s_end.mcap', 's_episode0010.mcap', 's_ep0000.mcap', 's_episode0002_attempt2.mcap',
             's_episode0002.mcap', 's_ep0008.mcap']
    assert sorted(names, key=bag_reader.recording_order) == [
        's_ep0000.mcap', 's_episode0002.mcap', 's_episode0002_attempt2.mcap', 's_ep0008.mcap',
        's_episode0010.mcap', 's_end.mcap']


def test_default_descriptions_are_the_contract_offers():
    assert contract_descriptions() == {
        topic: contract_description(TOPIC_TYPES[topic], *offer)
        for topic, offer in OFFERS.items()}


@pytest.mark.parametrize('frame_id, detail', [('', ''), ('world', 'x'), ('abc', '/dev/input/js0')])
def test_the_human_action_is_read_from_cdr_whatever_the_string_lengths(frame_id, detail):
    message = HumanAction(episode=7, step=3, command=-0.5, dof=1,
                          source=HumanAction.SOURCE_JOY, source_detail=detail, engaged=True)
    message.header.stamp.sec, message.header.stamp.nanosec = 5, 9
    message.header.frame_id = frame_id
    assert cdr_peek.human_action(serialize_message(message)) == (5_000_000_009, 7, 3,
                                                                 HumanAction.SOURCE_JOY, True)


@pytest.mark.parametrize('frame_id', ['', 'w', 'world', 'abcdefgh'])
@pytest.mark.parametrize('applied', [[], [0.5], [0.1] * 10])
def test_the_task_state_boundary_fields_are_read_from_cdr(frame_id, applied):
    """The batched recorder reads episode, step and the end flags without deserializing."""
    for terminated, truncated in ((False, False), (True, False), (False, True), (True, True)):
        state = TaskState(episode=70000, step=199, slice=3, robot_command_missing=True,
                          human_applied=applied, terminated=terminated, truncated=truncated)
        state.header.frame_id = frame_id
        data = serialize_message(state)
        assert cdr_peek.task_state(data) == (70000, 199, terminated or truncated)
        assert cdr_peek.task_state(data + bytes(2)) == (70000, 199, terminated or truncated)
        assert cdr_peek.task_state(data[:-2]) is None          # cut: the caller deserializes
        assert cdr_peek.task_state(data + bytes(4)) is None    # not a TaskState's length


@pytest.mark.parametrize('frame_id', ['', 'w', 'world', 'abcdefgh'])
@pytest.mark.parametrize('applied', [[], [0.5], [0.1] * 10])
def test_the_missing_command_flags_are_read_from_cdr(frame_id, applied):
    for robot, human in ((False, False), (True, False), (False, True), (True, True)):
        state = TaskState(episode=3, step=9, slice=1, robot_command_missing=robot,
                          human_command_missing=human, human_applied=applied, truncated=True)
        state.header.frame_id = frame_id
        data = serialize_message(state)
        assert cdr_peek.task_state_missing(data) == (robot, human)
        assert cdr_peek.task_state_missing(data[:-2]) is None


def test_each_episode_records_which_input_drove_the_human(tmp_path):
    writer = SessionWriter(tmp_path, 'src', descriptions={})
    writer.begin_episode(0)
    sources = [HumanAction.SOURCE_DEVICE] * 3 + [HumanAction.SOURCE_SIMULATED] * 5
    for step, source in enumerate(sources):
        action = {'header': {'stamp': {'sec': step // 5, 'nanosec': step % 5 * 200_000_000}},
                  'episode': 0, 'step': step, 'source': source, 'engaged': step != 7}
        writer.write('/hrc/human/action', action, START_NS + step)
        writer.write('/hrc/human/action', action, START_NS + step)        # a repeat: once
    writer.end_episode()
    writer.begin_episode(1)
    writer.end_episode()
    record = bag_reader.read_metadata(tmp_path / 'src' / 'src_episode0001.mcap')[EPISODE_RECORD]
    assert record['human_source'] == 'simulated'           # 4 engaged steps against 3
    assert record['human_sources'] == 'simulated,device'
    assert yaml.safe_load(record['human_steps']) == {'device': 3, 'simulated': 5}
    assert yaml.safe_load(record['human_engaged_steps']) == {'device': 3, 'simulated': 4}
    assert float(record['control_period']) == pytest.approx(0.2)
    assert record['message_count'] == '16'
    empty = bag_reader.read_metadata(tmp_path / 'src' / 'src_episode0002.mcap')[EPISODE_RECORD]
    assert empty['human_source'] == '' and empty['control_period'] == ''


@pytest.mark.parametrize('names', [
    [],
    [f'case2-seed0-20261203-054508_episode{episode + 1:04d}.mcap' for episode in range(120)],
    # names a plain YAML scalar cannot hold, and a long one with spaces (the dumper may fold it)
    ['odd: name.mcap', "it's #1.mcap", '- dash.mcap', 'x ' * 60 + '.mcap', 'ü.mcap'],
])
def test_metadata_yaml_is_the_whole_dump_with_each_files_lines_dumped_once(names):
    state = contract_description('/hrc/state')
    files = [FileInfo(name, 10**9 * index, 10**9 * index + 5, 3 * index,
                      {'/hrc/state': 3 * index}, {'/hrc/state': state})
             for index, name in enumerate(names)]
    entries = [('/hrc/state', state, sum(range(len(names))) * 3)]
    custom = {'session_id': 'case2', 'hrc_session': 'a: 1'}
    whole = dump_yaml({'rosbag2_bagfile_information': bag_metadata(files, entries, custom)})
    cache = {}
    for count in (len(files) // 2, len(files)):       # a session growing: the cache reused
        text = dump_bag_metadata(files[:count], entries, custom, cache)
    assert len(cache) == 2 * len(files)
    assert yaml.safe_load(text) == yaml.safe_load(whole)
    if all(' ' not in name for name in names):        # nothing to fold: the same text
        assert text == whole
