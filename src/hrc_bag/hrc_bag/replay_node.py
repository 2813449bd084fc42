"""The replay node: republish a recorded episode or session with its original timing.

Publishes the recorded CDR bytes unchanged (no deserialization) with the QoS the original
publishers offered, at the recorded relative times scaled by ``rate``; optionally loops,
selects topics, skips ``start_offset`` seconds, and publishes ``/clock`` with the recording
time. None of the original publishers need to run. Exits 0 at the end (unless ``loop``).

An input that cannot be replayed is refused before anything is published, with every reason
and exit code 2 (:func:`replay_problems`): a path that is no bag, a file that is not MCAP or
is corrupt (the MCAP magic followed by nothing readable), a folder without an MCAP file (its
metadata.yaml unusable or listing nothing), a bag that holds no message.
"""

import pathlib
import sys
import threading
import time

from hrc_common.contract import NS_PER_S
from hrc_common.nodes import run_node
from hrc_common.params import declare_parameters, ParameterError
from hrc_common import qos as hrc_qos
from hrc_common.topics import CLOCK, REPLAY
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from hrc_bag import bag_reader
from hrc_bag.recorder_node import message_class
from hrc_bag.replay import bag_start, playlist, publisher_qos, ReplayParams, Timeline

EXECUTABLE = 'replay_node'
SUMMARY = ('Replay an episode file (.mcap) or a session folder recorded by recorder_node: the '
           'recorded messages are republished unchanged with their original relative timing '
           '(rate, loop, topic selection, start offset, /clock).')

# Longest wait (s) for live readers to acknowledge a newest-only topic's previous sample.
ACK_TIMEOUT = 5.0

# As rclcpp::ClockQoS: the newest time only, best effort.
CLOCK_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                       reliability=ReliabilityPolicy.BEST_EFFORT)


def qos_profile(recorded) -> QoSProfile:
    """Return the rclpy QoSProfile of a :class:`hrc_bag.replay.PublisherQos`."""
    profile = QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=recorded.depth,
        reliability=(ReliabilityPolicy.RELIABLE if recorded.reliable
                     else ReliabilityPolicy.BEST_EFFORT),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if recorded.transient_local
                    else DurabilityPolicy.VOLATILE))
    if recorded.deadline_ns:
        profile.deadline = Duration(nanoseconds=recorded.deadline_ns)
    if recorded.lifespan_ns:
        profile.lifespan = Duration(nanoseconds=recorded.lifespan_ns)
    if recorded.liveliness_lease_ns:
        profile.liveliness_lease_duration = Duration(nanoseconds=recorded.liveliness_lease_ns)
    return profile


def replay_problems(path) -> list:
    """Return every reason why ``path`` cannot be replayed ([] = it can).

    Beyond :func:`hrc_bag.bag_reader.bag_problems` (exists, regular files, MCAP magic): each
    file is read record by record; one of which nothing at all can be read is corrupt (a file
    cut by a killed recorder is not: it is read up to its last chunk). A folder must hold an
    MCAP file, and the bag at least one message.
    """
    path = pathlib.Path(path)
    problems = bag_reader.bag_problems(path)
    if problems:
        return problems
    files = bag_reader.session_files(path)
    if not files:
        _, unusable = bag_reader.bag_metadata_yaml(path)
        why = unusable.replace(f'{path / bag_reader.METADATA_FILE}', '').replace(
            ': using the MCAP files of the folder', '').strip(' :')
        return [f'{path}: holds no MCAP file to replay'
                + (f' (and its metadata.yaml {why})' if unusable else '')]
    messages = 0
    for file in files:
        schemas, channels, records, metadata, error = bag_reader.scan_records(file)
        if error and not (schemas or channels or records or metadata):
            problems.append(f'{file}: is corrupt: nothing after the MCAP magic can be read '
                            f'({error})')
        messages += len(records)
    if not problems and messages == 0:
        problems.append(f'{path}: holds no messages: nothing to replay')
    return problems


class ReplayNode(Node):

    def __init__(self):
        super().__init__('replay')
        self.params = declare_parameters(self, ReplayParams)
        self._publishers_by_topic = {}
        self._newest_only_topics = set()     # reliable keep-last-1 topics (see _wait_for_acks)
        self._skip = set()
        problems = replay_problems(self.params.path)
        if problems:
            raise ParameterError('ReplayParams rejected: path: ' + '; '.join(problems),
                                 [f'path: {problem}' for problem in problems])
        if pathlib.Path(self.params.path).is_dir():
            _, problem = bag_reader.bag_metadata_yaml(self.params.path)
            if problem:
                self.get_logger().warning(problem)
        topics = bag_reader.bag_topics(self.params.path)
        for topic, info in sorted(topics.items()):
            if not self.params.selected(topic):
                continue
            if self.params.clock and topic == CLOCK:
                self._skip.add(topic)
                self.get_logger().info('the recorded /clock is not replayed: /clock is '
                                       'published from the recording time')
                continue
            try:
                message_type = message_class(info.type_name)
            except (ImportError, AttributeError, ValueError) as error:
                self.get_logger().error(f'{topic} not replayed: type {info.type_name!r} is '
                                        f'not installed ({error})')
                self._skip.add(topic)
                continue
            qos = qos_profile(publisher_qos(info.channel_metadata))
            self._publishers_by_topic[topic] = self.create_publisher(message_type, topic, qos)
            if qos.depth == 1 and qos.reliability == ReliabilityPolicy.RELIABLE:
                self._newest_only_topics.add(topic)
        missing = [topic for topic in self.params.topics
                   if topic != '*' and topic not in topics]
        if missing:
            self.get_logger().warning(f'not in the recording: {missing}')
        self._start = bag_start(self.params.path)
        self._timeline = None
        self._playback_started = None
        self._stop = threading.Event()
        self._done = threading.Event()
        self.published = 0
        if self.params.clock:
            self._clock_publisher = self.create_publisher(Clock, CLOCK, CLOCK_QOS)
            self.create_timer(1.0 / self.params.clock_rate, self._publish_clock)
        self.create_timer(0.05, self._check_done)
        # The pages mark what they show as a replay while this says so ('' at the end).
        self._replay_marker = self.create_publisher(String, REPLAY, hrc_qos.SESSION_QOS)
        self._replay_marker.publish(String(data=f'{self.params.path} at rate {self.params.rate}'))
        self.get_logger().info(
            f'replaying {sorted(self._publishers_by_topic)} from {self.params.path} at rate '
            f'{self.params.rate}' + (', looping' if self.params.loop else ''))
        self._thread = threading.Thread(target=self._play, name='playback', daemon=True)
        self._thread.start()

    def _play(self) -> None:
        if self._stop.wait(self.params.start_delay):
            return
        if self.params.wait_for_subscribers and not self._wait_for_subscribers():
            return
        if self._start is None:
            self.get_logger().warning(f'{self.params.path} holds no messages')
            self._done.set()
            return
        while not self._stop.is_set():
            self._timeline = Timeline(self._start, self.params.rate, self.params.start_offset)
            self._playback_started = time.monotonic()
            for message in playlist(self.params.path, self.params, self._skip):
                publisher = self._publishers_by_topic.get(message.topic)
                if publisher is None:
                    continue
                wait = self._timeline.due(message.log_time) - (time.monotonic()
                                                               - self._playback_started)
                if wait > 0 and self._stop.wait(wait):
                    return
                try:
                    self._wait_for_acks_of_newest_only(message.topic, publisher)
                    publisher.publish(message.data)
                except Exception:       # the node is shutting down (Ctrl-C) under our feet
                    if self._stop.is_set() or not self.context.ok():
                        return
                    raise
                self.published += 1
            if not self.params.loop:
                break
        self._done.set()

    def _wait_for_acks_of_newest_only(self, topic, publisher) -> None:
        """Let live readers take the previous sample of a reliable depth-1 topic first.

        A reliable writer with keep-last 1 (as recorded for /hrc/session) holds only its newest
        sample: publishing the next one before a slow reader acknowledged the previous drops
        it for that reader. Waiting for the acknowledgements (bounded by ACK_TIMEOUT) keeps the
        recorded QoS -- a late joiner still gets the newest status only -- and loses nothing
        for readers that are already there; it delays the playback only when a reader lags.
        """
        if topic not in self._newest_only_topics:
            return
        if not publisher.wait_for_all_acked(Duration(seconds=ACK_TIMEOUT)):
            self.get_logger().warning(f'{topic}: a reader did not acknowledge the previous '
                                      f'sample within {ACK_TIMEOUT:.0f} s; publishing the next')

    def _wait_for_subscribers(self) -> bool:
        """Wait until each publisher has enough subscriptions; False when stopped first."""
        wanted = self.params.wait_for_subscribers
        logged = False
        while not self._stop.is_set():
            missing = sorted(topic for topic, publisher in self._publishers_by_topic.items()
                             if publisher.get_subscription_count() < wanted)
            if not missing:
                return True
            if not logged:
                self.get_logger().info(f'waiting for {wanted} subscription(s) on {missing}')
                logged = True
            self._stop.wait(0.05)
        return False

    def _publish_clock(self) -> None:
        if self._timeline is None or self._done.is_set():
            return
        elapsed = time.monotonic() - self._playback_started
        nanoseconds = self._timeline.recording_time(elapsed)
        message = Clock()
        message.clock.sec, message.clock.nanosec = divmod(nanoseconds, NS_PER_S)
        self._clock_publisher.publish(message)

    def _check_done(self) -> None:
        if self._done.is_set():
            self.get_logger().info(f'replay finished: {self.published} messages published')
            self._replay_marker.publish(String(data=''))
            self.context.try_shutdown()

    def close(self) -> None:
        """Stop the playback thread; the pages are told the replay ended."""
        self._stop.set()
        try:
            self._replay_marker.publish(String(data=''))
        except Exception:   # noqa: BLE001 - the context is already shut down: nothing to tell
            pass
        self._thread.join(timeout=5.0)


def main(args=None):
    """Run the replay node."""
    return run_node(ReplayNode, EXECUTABLE, SUMMARY, ReplayParams, args)


if __name__ == '__main__':
    sys.exit(main())
