"""The recorder node: one rosbag2-compatible MCAP file per episode of an hrc session.

Subscribes (raw CDR, no deserialization except the three topics that mark episode boundaries)
to the configured topics and hands every message to :class:`hrc_bag.recording.EpisodeRecorder`,
which owns the files. The recording subscriptions are hidden from the executor
(:class:`hrc_common.nodes.DrainedNode`): a message does not wake the recorder; a timer takes
every waiting message of every subscription each ``batch_period`` and hands them over in one
batch (TaskState's episode boundaries read from its bytes, not deserialized).
The /hrc topics are subscribed at start with their contract QoS (so the first state of a
session is not missed); other topics once a publisher reveals their type, with a QoS adapted to
the publishers' offers (as rosbag2 does). Each channel carries the publishers'
``offered_qos_profiles`` and ``topic_type_hash``.

Exit codes: 0 after Ctrl-C/SIGTERM (files closed), 2 for bad parameters, 3 when a bag cannot be
written (disk full, permissions): the session must stop, nothing is dropped silently.
"""

import faulthandler
import functools
import importlib
import pathlib
import shutil
import signal
import sys
import time

from hrc_common import bounded_yaml
from hrc_common.cdr_header import header_stamp
from hrc_common import qos as hrc_qos
from hrc_common import topics as hrc_topics
from hrc_common.nodes import closing_log, DrainedNode, run_node, take_waiting
from hrc_common.diagnostics import DiagnosticsReporter, disk_level, status
from hrc_common.session_end import SessionEndWatch
from hrc_common.params import as_dict, declare_parameters, ParameterError
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from std_msgs.msg import Header
import yaml

from hrc_bag.qos_yaml import profile_to_dict
from hrc_bag.format import RawMessage, RecordingError, TopicDescription
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.boundaries import boundary_event_of_cdr
from hrc_bag.recording import EpisodeRecorder

EXECUTABLE = 'recorder_node'
SUMMARY = ('Record the hrc topics into one rosbag2-compatible MCAP file per episode under '
           '<output_dir>/<session_id>/, with a metadata.yaml that ros2 bag play and rosbags '
           'read. Exit code 3 when the bags cannot be written.')
EXIT_RECORDING_FAILED = 3
# s: how often the recorder checks which publishers its subscriptions have matched.
MATCH_REPORT_PERIOD_S = 0.5

# Types of the hrc graph's topics (by default name), so they are subscribed before anyone
# publishes; and the QoS contract their publishers offer.
KNOWN_TOPICS = {topic: (type_name, hrc_qos.OF_TOPIC[topic])
                for topic, type_name in hrc_topics.TYPES.items()}


def message_class(type_name: str):
    """Import the Python class of ``pkg/msg/Type``."""
    package, kind, name = type_name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), name)


def recording_qos(reliable: bool, transient_local: bool, depth: int) -> QoSProfile:
    """Return the QoS of a recording subscription (no deadline: it would only add events)."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if transient_local
                    else DurabilityPolicy.VOLATILE))


class RecorderNode(DrainedNode):

    def __init__(self):
        super().__init__('recorder')
        self.params = declare_parameters(self, RecorderParams)
        self.session_end = SessionEndWatch(self, self.params.exit_after_session)
        self.diagnostics = DiagnosticsReporter(self, self._diagnostics)
        config, config_text = self._load_session_config(self.params.session_config)
        self._subscriptions_by_topic = {}
        self._waiting = []                  # topics whose type is not known yet
        # the recording subscriptions are not the executor's (a message does not wake this
        # process); _drain takes their messages
        self._drained = []                  # (subscription, topic, type name, deserialize)
        self.core = EpisodeRecorder(
            self.params, self._describe_topic, session_config=config,
            session_config_text=config_text, logger=self.get_logger(),
            recorder_parameters=as_dict(self.params))
        for topic in self.params.topics:
            known = KNOWN_TOPICS.get(topic)
            if known is None:
                self._waiting.append(topic)
                continue
            type_name, contract = known
            self._subscribe(topic, type_name, recording_qos(
                contract.reliability == ReliabilityPolicy.RELIABLE,
                contract.durability == DurabilityPolicy.TRANSIENT_LOCAL,
                self.params.subscription_depth))
        if self._waiting:
            self.get_logger().info(f'waiting for publishers to learn the types of '
                                   f'{self._waiting}')
            self._discovery_timer = self.create_timer(self.params.discovery_period,
                                                      self._discover)
        # How far this recorder has taken the states, after each batch: a lockstep sim that
        # awaits it (await_recorder) runs no further ahead (hrc_sim_node.recorder_gate).
        self._progress_pub = self.create_publisher(Header, hrc_topics.RECORDER_PROGRESS,
                                                   hrc_qos.RECORDER_PROGRESS_QOS)
        self._state_topic = self.resolve_topic_name(hrc_topics.STATE)
        self._tick_timer = self.create_timer(
            min(self.params.batch_period, self.params.flush_period / 2), self._drain)
        # How many publishers each recording subscription has matched, said when it changes: a
        # writer this node has not matched yet (discovery across a lossy link can lag the rest
        # of the graph) is a topic missing from the bag, and the log is where a lab sees it.
        self._matched_publishers = {}
        self._match_timer = self.create_timer(MATCH_REPORT_PERIOD_S, self._report_matches)

    @staticmethod
    def _load_session_config(path: str) -> tuple:
        if not path:
            return {}, ''
        try:
            with open(path) as stream:
                text = stream.read()
            config = bounded_yaml.load(text, path) or {}
        except (OSError, yaml.YAMLError) as error:
            reason = bounded_yaml.describe(error) if isinstance(error, yaml.YAMLError) else error
            raise ParameterError(f'session_config: cannot read {path}: {reason}')
        if not isinstance(config, dict):
            raise ParameterError(f'session_config: {path} is not a YAML mapping')
        return config, text

    def _subscribe(self, topic: str, type_name: str, qos: QoSProfile) -> None:
        message_type = message_class(type_name)
        resolved = self.resolve_topic_name(topic)
        subscription = self.create_drained_subscription(message_type, topic, qos, raw=True)
        self._subscriptions_by_topic[topic] = subscription
        # only the messages that mark episode boundaries are deserialized (boundary_event_of_cdr)
        self._drained.append((subscription, resolved, type_name, functools.partial(
            deserialize_message, message_type=message_type)))
        self.get_logger().info(
            f'recording {resolved} ({type_name}, {qos.reliability.name.lower()}, '
            f'{qos.durability.name.lower()}, drained every {self.params.batch_period:g} s)')

    def _take_waiting(self) -> list:
        """Return (RawMessage, event) of every message waiting in the recording subscriptions.

        At most ``subscription_depth`` per subscription and call (what its history holds),
        so that a publisher faster than this loop cannot keep it here.
        """
        batch = []
        depth = self.params.subscription_depth
        for subscription, topic, type_name, deserialize in self._drained:
            for data, info in take_waiting(subscription, depth):
                log_time = info.get('received_timestamp') or time.time_ns()
                batch.append((RawMessage(topic, type_name, data, log_time,
                                         info.get('source_timestamp') or log_time,
                                         info.get('publication_sequence_number') or 0),
                              boundary_event_of_cdr(type_name, data, deserialize)))
        return batch

    def _drain(self) -> None:
        """Hand every waiting message to the core in one batch; say the newest state taken."""
        batch = self._take_waiting()
        self.core.record_batch(batch)
        stamps = [header_stamp(message.data) for message, _ in batch
                  if message.topic == self._state_topic]
        if stamps:
            sec, nanosec = max(stamps)
            progress = Header(frame_id=self.core.session_id or '')
            progress.stamp.sec, progress.stamp.nanosec = int(sec), int(nanosec)
            self._progress_pub.publish(progress)

    def _report_matches(self) -> None:
        """Log each subscription whose count of matched publishers changed."""
        for topic, subscription in self._subscriptions_by_topic.items():
            count = subscription.get_publisher_count()
            if count != self._matched_publishers.get(topic, 0):
                self.get_logger().info(f'{self.resolve_topic_name(topic)}: {count} '
                                       f'publisher(s) matched')
            self._matched_publishers[topic] = count

    def _discover(self) -> None:
        """Subscribe to the waiting topics whose publishers have shown up."""
        types = dict(self.get_topic_names_and_types())
        for topic in list(self._waiting):
            resolved = self.resolve_topic_name(topic)
            names = types.get(resolved)
            if not names:
                continue
            if len(names) > 1:
                self.get_logger().warning(f'{resolved} has several types {names}: recording '
                                          f'{names[0]}')
            publishers = self.get_publishers_info_by_topic(resolved)
            if not publishers:
                continue
            # as rosbag2: reliable / transient_local only if every publisher offers it
            reliable = all(info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                           for info in publishers)
            transient_local = all(
                info.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                for info in publishers)
            try:
                self._subscribe(topic, names[0], recording_qos(
                    reliable, transient_local, self.params.subscription_depth))
            except (ImportError, AttributeError, ValueError) as error:
                self.get_logger().error(f'cannot record {resolved}: type {names[0]} is not '
                                        f'installed ({error})')
            self._waiting.remove(topic)
        if not self._waiting:
            self._discovery_timer.cancel()

    def _describe_topic(self, topic: str, type_name: str) -> TopicDescription:
        """Return the offered QoS profiles and type hash of the topic's publishers now.

        None when the graph cannot be asked (at shutdown the context is gone): the recorder
        then uses what it learnt earlier about the topic.
        """
        try:
            publishers = self.get_publishers_info_by_topic(topic)
        except Exception as error:  # RCLError/InvalidHandle once the context is shut down
            self.get_logger().debug(f'no graph information on {topic}: {error}')
            return None
        profiles = tuple(profile_to_dict(info.qos_profile) for info in publishers)
        hashes = [str(info.topic_type_hash) for info in publishers
                  if info.topic_type == type_name]
        return TopicDescription(type_name, profiles, hashes[0] if hashes else '')

    def _diagnostics(self) -> list:
        """Return ``recorder: writing`` (levels and thresholds: hrc_common.diagnostics)."""
        folder = pathlib.Path(self.params.output_dir)
        while not folder.exists() and folder != folder.parent:
            folder = folder.parent              # the bags folder is made at the first file
        try:
            free = shutil.disk_usage(folder).free
        except OSError:
            free = 0
        failed = str(self.core.failed) if self.core.failed is not None else ''
        level, words = disk_level(free, failed)
        closed = self.core.closed_files
        return [status('recorder: writing', str(folder), level, words, {
            'session': self.core.session_id or '(not known yet)',
            'files_closed': len(closed),
            'messages_written': sum(info.message_count for info in closed),
            'files_open': len(self.core.open_files),
            'messages_waiting': self.core.waiting,
            'disk_free_mib': free >> 20})]

    def close(self) -> None:
        """Take what is still waiting, close the open episode file (called on shutdown)."""
        try:
            if self.core.failed is None:
                try:
                    batch = self._take_waiting()
                except Exception as error:  # RCLError/InvalidHandle once the context is gone
                    closing_log(self, 'warning', f'messages still waiting in DDS are not '
                                                 f'recorded: {error}')
                else:
                    self.core.record_batch(batch)
            self.core.close()
        except RecordingError as error:
            closing_log(self, 'error', f'recording stopped: {error}')
        # what the recording cost this process (bench/middleware.py reads this line)
        closing_log(
            self, 'info',
            f'{sum(info.message_count for info in self.core.closed_files)} messages recorded '
            f'in {len(self.core.closed_files)} files; process CPU {time.process_time():.2f} s')


def main(args=None):
    """Run the recorder node; exit 3 when bags cannot be written."""
    # `kill -USR1 <pid>` prints where every thread of a recorder that seems stuck is
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    try:
        return run_node(RecorderNode, EXECUTABLE, SUMMARY, RecorderParams, args)
    except RecordingError as error:
        print(f'[ERROR] [recorder] recording stopped, the session must stop: {error}',
              file=sys.stderr, flush=True)
        return EXIT_RECORDING_FAILED


if __name__ == '__main__':
    sys.exit(main())
