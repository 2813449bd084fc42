"""The replay node over DDS: same bytes, original timing, selection, offset, /clock, loop."""

import pathlib

from hrc_common.params import load_yaml, ParameterError
from hrc_testing.nodes import wait_for
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
import yaml

from hrc_bag import bag_reader
from hrc_bag.recorder_node import message_class
from hrc_bag.replay import bag_start, playlist, publisher_qos, ReplayParams, Timeline
from hrc_testing.bag_traffic import record_in_process, strategy_plan

PARAMS_DIR = pathlib.Path(__file__).resolve().parents[3] / 'params'


def test_the_default_file_names_no_bag_and_is_refused_with_the_reason():
    with pytest.raises(ParameterError, match='path: give an episode file'):
        load_yaml(ReplayParams, PARAMS_DIR / 'replay.yaml', 'replay')


def test_timeline_scales_recording_time_by_the_rate():
    timeline = Timeline(bag_start=10_000_000_000, rate=2.0, start_offset=1.0)
    assert timeline.due(11_000_000_000) == 0.0
    assert timeline.due(13_000_000_000) == 1.0
    assert timeline.recording_time(1.0) == 13_000_000_000


def test_recorded_qos_is_offered_again():
    deadline = {'sec': 1, 'nsec': 0}
    infinite = {'sec': 9223372036, 'nsec': 854775807}
    profile = yaml.safe_dump([{'history': 'unknown', 'depth': 0, 'reliability': 'reliable',
                               'durability': 'transient_local', 'deadline': deadline,
                               'lifespan': infinite, 'liveliness': 'automatic',
                               'liveliness_lease_duration': infinite,
                               'avoid_ros_namespace_conventions': False}])
    qos = publisher_qos({'offered_qos_profiles': profile})
    assert (qos.reliable, qos.transient_local, qos.depth) == (True, True, 10)
    assert (qos.deadline_ns, qos.lifespan_ns) == (1_000_000_000, 0)
    assert publisher_qos({}).reliable


@pytest.fixture(scope='module')
def session_folder(tmp_path_factory):
    """Record two episodes of 6 steps (2.4 s of recording time) in-process."""
    folder = tmp_path_factory.mktemp('replay')
    record_in_process(folder, 'rp', 5, 'learn_together', 1,
                      strategy_plan('learn_together', 1, 1, 0), steps=6)
    return folder / 'rp'


def same_cdr(received: bytes, recorded: bytes) -> bool:
    """Return True when ``received`` is ``recorded`` plus at most the 4-byte alignment padding.

    The bag was written in-process from rclpy.serialization (unpadded); on the wire the
    middleware pads a sample with zeros to a multiple of 4 bytes.
    """
    padding = received[len(recorded):]
    return (received[:len(recorded)] == recorded and padding == bytes(len(padding))
            and len(padding) < 4)


def same_sequence(received: list, recorded: list) -> bool:
    """Return True when two lists of CDR samples are equal (up to the alignment padding)."""
    return len(received) == len(recorded) and all(
        same_cdr(got, want) for got, want in zip(received, recorded))


class Listener:
    """Raw subscriptions to the recorded topics; remembers bytes and send times.

    The send time is the replay's writer's (DDS source timestamp), not when this test's
    executor got to the message: a busy machine may keep this process waiting for the CPU.
    """

    def __init__(self, node, topics, prefix, clock=False):
        self.received = []                              # (topic, bytes, send time s)
        self.clock = []
        for topic, info in topics.items():
            durability = (DurabilityPolicy.TRANSIENT_LOCAL
                          if publisher_qos(info.channel_metadata).transient_local
                          else DurabilityPolicy.VOLATILE)
            qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                             durability=durability)
            node.create_subscription(message_class(info.type_name), prefix + topic,
                                     self._callback(topic), qos, raw=True)
        if clock:
            node.create_subscription(Clock, prefix + '/clock', self.clock.append,
                                     QoSProfile(depth=100,
                                                reliability=ReliabilityPolicy.BEST_EFFORT))
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def _callback(self, topic):
        def on_message(data, info):
            self.received.append((topic, data, info['source_timestamp'] / 1e9))
        return on_message

    def spin_until(self, condition, timeout):
        return wait_for(condition, timeout,
                        spin=lambda: self.executor.spin_once(timeout_sec=0.01))

    def of(self, topic):
        return [data for name, data, _ in self.received if name == topic]


def test_a_session_is_replayed_with_the_same_bytes_and_timing(start_node, test_node,
                                                              session_folder, isolation):
    recorded = list(bag_reader.iter_messages(session_folder))
    topics = bag_reader.bag_topics(session_folder)
    listener = Listener(test_node, topics, isolation.prefix)
    rate = 2.0
    replay = start_node('hrc_bag', 'replay_node',
                        parameters={'path': str(session_folder), 'rate': rate,
                                    'start_delay': 0.5, 'wait_for_subscribers': 1},
                        ros_args=isolation.ros_args)
    assert listener.spin_until(lambda: replay.process.poll() is not None, 120.0), replay.output
    assert replay.wait(timeout=10) == 0, replay.output
    listener.spin_until(lambda: len(listener.received) >= len(recorded), 60.0)

    for topic in topics:
        assert same_sequence(listener.of(topic), [message.data for message in recorded
                                                  if message.topic == topic]), topic
    assert len(listener.received) == len(recorded)
    # timing: send offsets against the recorded offsets scaled by the rate
    first_arrival = min(arrival for _, _, arrival in listener.received)
    arrivals = {}
    for topic, _, arrival in listener.received:
        arrivals.setdefault(topic, []).append(arrival - first_arrival)
    errors = []
    for topic, times in arrivals.items():
        expected = [(message.log_time - recorded[0].log_time) / 1e9 / rate
                    for message in recorded if message.topic == topic]
        errors += [got - want for got, want in zip(times, expected)]
    span = (recorded[-1].log_time - recorded[0].log_time) / 1e9 / rate
    assert span > 1.0
    assert max(abs(error) for error in errors) < 0.3, errors
    assert 'replay finished' in replay.output


def test_one_file_with_topic_selection_offset_clock_and_loop(start_node, test_node,
                                                            session_folder, isolation):
    episode_file = session_folder / 'rp_episode0002.mcap'
    offset = 0.5
    threshold = bag_start(episode_file) + int(offset * 1e9)
    expected = [message.data for message in bag_reader.scan_file(episode_file).messages
                if message.topic == '/hrc/state' and message.log_time >= threshold]
    assert 0 < len(expected) < 6
    topics = bag_reader.bag_topics(episode_file)
    listener = Listener(test_node, topics, isolation.prefix, clock=True)
    replay = start_node('hrc_bag', 'replay_node',
                        parameters={'path': str(episode_file), 'rate': 4.0, 'loop': True,
                                    'topics': ['/hrc/state'], 'start_offset': offset,
                                    'clock': True, 'clock_rate': 50.0, 'start_delay': 0.5,
                                    'wait_for_subscribers': 1},
                        ros_args=isolation.ros_args)
    assert listener.spin_until(lambda: len(listener.received) >= 2 * len(expected) + 1,
                               120.0), replay.output
    assert replay.stop() == 0, replay.output
    states = listener.of('/hrc/state')
    assert {topic for topic, _, _ in listener.received} == {'/hrc/state'}
    assert same_sequence(states[:len(expected)], expected)
    assert same_sequence(states[len(expected):2 * len(expected)], expected)      # looped
    times = [message.clock.sec * 10**9 + message.clock.nanosec for message in listener.clock]
    assert times, 'no /clock received'
    end = max(message.log_time for message in bag_reader.scan_file(episode_file).messages)
    assert all(threshold <= value <= end + 10**9 for value in times)


def test_a_missing_bag_is_a_parameter_error(start_node, tmp_path):
    replay = start_node('hrc_bag', 'replay_node',
                        parameters={'path': str(tmp_path / 'nothing')})
    assert replay.wait(timeout=60) == 2
    assert 'does not exist' in replay.output


def test_fifo_empty_and_non_mcap_paths_are_refused_with_the_reason(tmp_path):
    import os
    fifo = tmp_path / 'pipe.mcap'
    os.mkfifo(fifo)
    empty = tmp_path / 'empty.mcap'
    empty.write_bytes(b'')
    text = tmp_path / 'notes.mcap'
    text.write_text('not a bag')
    folder = tmp_path / 'session'
    folder.mkdir()
    (folder / 'a_episode0001.mcap').write_bytes(b'')
    for path, reason in ((fifo, 'is a FIFO, not an MCAP file'),
                         (empty, 'is empty, not an MCAP file'),
                         (text, 'is not an MCAP file'),
                         (folder, 'a_episode0001.mcap: is empty, not an MCAP file')):
        assert [problem for problem in ReplayParams(path=str(path)).check()
                if reason in problem], (path, ReplayParams(path=str(path)).check())


def test_a_fifo_is_refused_by_the_node_with_exit_2(start_node, tmp_path):
    import os
    fifo = tmp_path / 'pipe.mcap'
    os.mkfifo(fifo)
    replay = start_node('hrc_bag', 'replay_node', parameters={'path': str(fifo)})
    assert replay.wait(timeout=60) == 2, replay.output
    assert 'is a FIFO, not an MCAP file' in replay.output
    assert 'Traceback' not in replay.output


def test_a_session_with_an_unusable_metadata_yaml_is_played_from_its_files(tmp_path):
    plan = strategy_plan('learn_together', 1, 0, 0)
    record_in_process(tmp_path, 'bad', 5, 'learn_together', 3, plan, steps=4)
    folder = tmp_path / 'bad'
    expected = list(playlist(folder, ReplayParams(path=str(folder))))
    (folder / 'metadata.yaml').write_text('- a list\n- not rosbag2 metadata\n')
    assert ReplayParams(path=str(folder)).check() == []
    played = list(playlist(folder, ReplayParams(path=str(folder))))
    assert [message.data for message in played] == [message.data for message in expected]
    assert played


def test_corrupt_empty_and_file_less_inputs_are_refused_with_the_reason(tmp_path):
    """These passed the magic check and replayed nothing with exit 0."""
    import io
    import os

    from mcap.writer import Writer

    from hrc_bag.bag_reader import MCAP_MAGIC
    from hrc_bag.replay_node import replay_problems
    garbage = tmp_path / 'garbage.mcap'
    garbage.write_bytes(MCAP_MAGIC + bytes(range(256)) * 2)
    folder = tmp_path / 'no-files'
    folder.mkdir()
    (folder / 'metadata.yaml').write_text('rosbag2_bagfile_information: [unclosed\n')
    stream = io.BytesIO()
    writer = Writer(stream)
    writer.start()
    writer.finish()
    no_messages = tmp_path / 'no-messages.mcap'
    no_messages.write_bytes(stream.getvalue())
    for path, reason in (
            (garbage, f'{garbage}: is corrupt: nothing after the MCAP magic can be read'),
            (folder, f'{folder}: holds no MCAP file to replay (and its metadata.yaml is not '
                     f'YAML'),
            (no_messages, f'{no_messages}: holds no messages: nothing to replay')):
        problems = replay_problems(path)
        assert len(problems) == 1 and problems[0].startswith(reason), (path, problems)
    # A file cut by a killed recorder is still replayed up to its last chunk.
    plan = strategy_plan('learn_together', 1, 0, 0)
    record_in_process(tmp_path, 'cut', 5, 'learn_together', 3, plan, steps=4)
    first = sorted((tmp_path / 'cut').glob('*_episode0001.mcap'))[0]
    os.truncate(first, first.stat().st_size * 2 // 3)
    assert replay_problems(first) == []


def test_a_corrupt_file_is_refused_by_the_node_with_exit_2(start_node, tmp_path):
    from hrc_bag.bag_reader import MCAP_MAGIC
    garbage = tmp_path / 'garbage.mcap'
    garbage.write_bytes(MCAP_MAGIC + b'\xff' * 64)
    replay = start_node('hrc_bag', 'replay_node', parameters={'path': str(garbage)})
    assert replay.wait(timeout=60) == 2, replay.output
    assert 'is corrupt' in replay.output and 'Traceback' not in replay.output
