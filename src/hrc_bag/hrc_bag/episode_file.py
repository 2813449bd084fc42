"""One episode's MCAP file being written: schemas, channels, messages, records (pure).

:class:`EpisodeFile` writes the file :mod:`hrc_bag.format` describes: profile ``ros2``,
chunked and compressed, every index, statistics and summary offsets, the ``hrc_session``
record first and, at close, the ``hrc_episode`` and ``rosbag2`` records; it is fsynced before
the session's metadata.yaml (:mod:`hrc_bag.session_index`) may list it.
"""

import collections
from dataclasses import dataclass
import os
import pathlib
import typing

from hrc_common.contract import PUBLIC_FILE_MODE
from hrc_common.topics import STATE as STATE_TOPIC
from mcap.writer import CompressionType, IndexType, Writer

from hrc_bag import cdr_peek, msgdefs
from hrc_bag.format import (describe_error, EPISODE_RECORD, FileInfo, HumanInputTally,
                            MESSAGE_ENCODING, package_version, PROFILE, RawMessage,
                            RecordingError, ROSBAG2_RECORD, SCHEMA_ENCODING, TopicDescription)
from hrc_bag.qos_yaml import dump_profiles, dump_yaml
from hrc_bag.session_index import bag_metadata, topic_entries

COMPRESSIONS = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4,
                'none': CompressionType.NONE}
DEFAULT_CHUNK_SIZE = 262144     # B


class EpisodeFile:
    """One MCAP file being written: profile ros2, chunked, compressed, indexed, statistics.

    ``name`` is the name metadata.yaml and the embedded rosbag2 record give the file (default:
    the name of ``path``; recovery writes a temporary file under its final name). ``mode``:
    the file's permissions (0600 for personal data), whatever the umask.
    """

    def __init__(self, path, compression: str = 'zstd', chunk_size: int = DEFAULT_CHUNK_SIZE,
                 metadata: typing.Optional[dict] = None, name: str = '',
                 mode: int = PUBLIC_FILE_MODE):
        self.path = pathlib.Path(path)
        self.name = name or self.path.name
        self._schemas = {}                  # type name -> schema id
        self._channels = {}                 # topic -> channel id
        self.topics = {}                    # topic -> TopicDescription
        self.topic_counts = collections.Counter()
        self.message_count = 0
        self.start = 0
        self.end = 0
        self.closed = False
        self.human = HumanInputTally()
        # the period states of the file and how many of them went without an actor's command
        self.states = 0
        self.missing_commands = collections.Counter(robot=0, human=0)
        try:
            # O_EXCL: never overwrite a file of an earlier recording
            descriptor = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
            os.fchmod(descriptor, mode)
            self._stream = os.fdopen(descriptor, 'wb')
            self._writer = Writer(self._stream, chunk_size=chunk_size,
                                  compression=COMPRESSIONS[compression],
                                  index_types=IndexType.ALL, use_chunking=True,
                                  use_statistics=True, use_summary_offsets=True)
            self._writer.start(profile=PROFILE, library=f'hrc_bag/{package_version()}')
            for record_name, record in (metadata or {}).items():
                self._writer.add_metadata(record_name,
                                          {str(k): str(v) for k, v in record.items()})
            self._stream.flush()
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error

    def write(self, message: RawMessage, description) -> None:
        """Append one message (registering its schema and channel on first use).

        ``description``: the topic's TopicDescription, or a callable returning it, called only
        when the topic's channel is registered (the recorder asks the ROS graph for it, which
        costs far more than writing a message).
        """
        try:
            channel_id = self._channels.get(message.topic)
            if channel_id is None:
                channel_id = self._add_channel(
                    message.topic, description() if callable(description) else description)
            self._writer.add_message(channel_id, log_time=message.log_time,
                                     data=message.data, publish_time=message.publish_time,
                                     sequence=message.sequence & 0xFFFFFFFF)
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error
        self.topic_counts[message.topic] += 1
        if message.type_name == cdr_peek.HUMAN_ACTION_TYPE:
            self.human.add_cdr(message.data)
        elif message.topic == STATE_TOPIC:
            missing = cdr_peek.task_state_missing(message.data)
            if missing is not None:
                self.states += 1
                self.missing_commands['robot'] += missing[0]
                self.missing_commands['human'] += missing[1]
        if self.message_count == 0:
            self.start = self.end = message.log_time
        self.start = min(self.start, message.log_time)
        self.end = max(self.end, message.log_time)
        self.message_count += 1

    def _add_channel(self, topic: str, description: TopicDescription) -> int:
        schema_id = self._schemas.get(description.type_name)
        if schema_id is None:
            definition = (description.message_definition
                          or msgdefs.full_definition(description.type_name))
            schema_id = self._writer.register_schema(description.type_name, SCHEMA_ENCODING,
                                                     definition.encode())
            self._schemas[description.type_name] = schema_id
        metadata = {'offered_qos_profiles': dump_profiles(description.offered_qos_profiles),
                    'topic_type_hash': description.type_description_hash}
        channel_id = self._writer.register_channel(topic, MESSAGE_ENCODING, schema_id, metadata)
        self._channels[topic] = channel_id
        self.topics[topic] = description
        return channel_id

    def flush(self) -> None:
        """Close the open chunk and push it to the file (survives a SIGKILL from now on)."""
        try:
            self._writer.flush()
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error

    def info(self) -> FileInfo:
        """Return what metadata.yaml lists about this file."""
        return FileInfo(self.name, self.start, self.end, self.message_count,
                        dict(self.topic_counts), dict(self.topics))

    def close(self, custom_data: typing.Optional[dict] = None,
              episode_record: typing.Optional[dict] = None) -> FileInfo:
        """Finish the file (rosbag2 record, summary, indexes, footer), fsync, return its info.

        ``episode_record``: more fields of the ``hrc_episode`` record (the recorder's attempt
        of the episode: ``attempt``, ``attempt_files``, ``last_step``, ``finished``).
        """
        info = self.info()
        try:
            self._writer.flush()
            self._writer.add_metadata(EPISODE_RECORD, {
                'message_count': str(self.message_count), **self.human.record(),
                'states': str(self.states),
                'robot_commands_missing': str(self.missing_commands['robot']),
                'human_commands_missing': str(self.missing_commands['human']),
                **{str(key): str(value) for key, value in (episode_record or {}).items()}})
            own_metadata = bag_metadata([info], topic_entries(info), custom_data or {})
            self._writer.add_metadata(ROSBAG2_RECORD,
                                      {'serialized_metadata': dump_yaml(own_metadata)})
            self._writer.finish()
            self._stream.flush()
            os.fsync(self._stream.fileno())
            self._stream.close()
        except OSError as error:
            self.abandon()
            raise RecordingError(f'cannot finish {self.path}: {describe_error(error)}') from error
        self.closed = True
        return info

    def abandon(self) -> None:
        """Close the file handle without finishing (after a write error)."""
        self.closed = True
        try:
            self._stream.close()
        except OSError:
            pass


@dataclass
class OpenEpisode:
    """An episode file being written, and when and why it is to be closed."""

    file: EpisodeFile
    episode: typing.Optional[int]       # None for the end file
    close_at: typing.Optional[float] = None     # monotonic s
    reason: str = ''
    attempt: int = 1                    # 1 = the first recording of the episode
    last_step: int = -1                 # the highest TaskState step written
    finished: bool = False              # its EpisodeSummary was handled
    summary_steps: int = -1             # the steps its EpisodeSummary says (-1: not said)
    final_seen: bool = False            # its final state (terminated or truncated) was handled

    def schedule_close(self, close_at: float, reason: str) -> None:
        """Close at ``close_at`` unless an earlier close is scheduled already."""
        if self.close_at is None or close_at < self.close_at:
            self.close_at = close_at
            self.reason = reason
