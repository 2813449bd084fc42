"""Record an hrc session into one rosbag2-compatible MCAP file per episode (pure, no rclpy).

Layout of a session (``<output_dir>/<session_id>/``)::

    metadata.yaml                 rosbag2 bag metadata (version 9, storage mcap), rewritten
                                  atomically each time an episode file is closed
    <session_id>_ep0000.mcap      everything recorded during episode 0, ...
    <session_id>_ep0001.mcap
    <session_id>_end.mcap         messages after the last episode (only if there are any)

Episode boundaries (the rule; the node turns messages into the events used here):

* A file opens at the first ``/hrc/state`` (TaskState) of an episode not recorded yet.
* Each message goes to the file of its episode: the ``episode`` field of TaskState,
  HumanAction, AgentStep, EpisodeSummary; for a command (WrenchStamped) the episode of the
  state whose stamp it carries (the step protocol). Messages that name no episode
  (SessionStatus, other topics) go to the newest open file.
* A file closes ``close_grace`` seconds after the EpisodeSummary of its episode, or after the
  first state of the next episode (late messages of its episode on other topics still find
  it), or after a ``/hrc/session`` with phase done/aborted; ``summary_timeout`` seconds after
  its final state (``terminated`` or ``truncated``) if nothing else closed it (a sim without
  an agent); or at shutdown. A message of an episode whose file closed already goes to the
  newest file (with a warning).
* Messages that arrive while no file is open (between episodes: phase ``updating``, the next
  training step, the human joining; or before the first episode), and messages of an episode
  whose first state has not been handled yet, are kept in memory and written at the start of
  the next file with their original timestamps. What is left at shutdown goes to
  ``<session_id>_end.mcap``.

Messages are handled in the order DDS received them (their log time), after ``reorder_window``
seconds: rclpy's executor takes one message per subscription in turn, so a recorder that lags
behind gets a topic's messages later than another topic's received after them.

Crash safety: the open chunk is closed at least every ``flush_period`` seconds (and whenever it
exceeds ``chunk_size``), and written to the file, so a SIGKILL loses at most that much (plus
the ``reorder_window``) of the open episode; every closed file is complete (summary, indexes,
footer) and fsynced, and metadata.yaml lists only closed files. A later recorder of the same
session finishes the files a killed one left open (``recover``). Write errors (disk full,
permissions) raise :class:`RecordingError`, which stops the recorder with a clear message.
"""

import collections
from dataclasses import dataclass, field
import datetime
import errno
import heapq
import itertools
import os
import pathlib
import re
import time
import typing

from hrc_common.params import param
from hrc_common.topics import (AGENT_STEP, EPISODE, HUMAN_ACTION, HUMAN_CMD_WRENCH,
                               ROBOT_CMD_WRENCH, SESSION, STATE)
from mcap.writer import CompressionType, IndexType, Writer
import yaml

from hrc_bag import cdr_peek, msgdefs
from hrc_bag.qos_yaml import dump_profiles, dump_yaml, load_yaml

BAG_VERSION = 9                 # rosbag2 metadata version written (ROS 2 Jazzy)
STORAGE_IDENTIFIER = 'mcap'
PROFILE = 'ros2'
SCHEMA_ENCODING = 'ros2msg'
MESSAGE_ENCODING = 'cdr'
SESSION_RECORD = 'hrc_session'  # name of the MCAP metadata record with the session config
ROSBAG2_RECORD = 'rosbag2'      # name of rosbag2's own metadata record
END_FILE_SUFFIX = '_end'

# SessionStatus.PHASE_DONE / PHASE_ABORTED
SESSION_FINISHED_PHASES = (4, 5)

DEFAULT_TOPICS = [STATE, ROBOT_CMD_WRENCH, HUMAN_CMD_WRENCH, HUMAN_ACTION, SESSION, EPISODE,
                  AGENT_STEP]
_SESSION_ID = re.compile(r'^[A-Za-z0-9][A-Za-z0-9_.-]{0,99}$')
_COMPRESSION = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4,
                'none': CompressionType.NONE}


@dataclass
class RecorderParams:
    """Parameters of the recorder node (node ``recorder``, params/recorder.yaml)."""

    output_dir: str = param(
        'bags', 'folder that receives one subfolder per session (created if missing)')
    session_id: str = param(
        '', 'session folder and file name prefix (letters, digits, _ . -); empty: the '
        'session_config session_id, else the first /hrc/session, else the start time')
    session_config: str = param(
        '', 'YAML file with the session configuration (case, strategy, roles, seeds, every '
        "node's parameters, package version) stored in every file; empty: what the recorder "
        'knows')
    topics: list = param(
        list(DEFAULT_TOPICS), 'topics to record; /hrc topics are subscribed at once, others '
        'when a publisher shows their type')
    compression: str = param('zstd', 'chunk compression', choices=('zstd', 'lz4', 'none'))
    chunk_size: int = param(
        262144, 'a chunk is closed when it holds this many bytes (B)', low=1024,
        high=64 * 1024 * 1024)
    flush_period: float = param(
        1.0, 'the open chunk is written at least this often (s); a SIGKILL loses at most this '
        'much of the open episode', low=0.05, high=60.0)
    close_grace: float = param(
        0.5, 'an episode file closes this long (s) after its EpisodeSummary, so late messages '
        'of the episode on other topics still land in it', low=0.0, high=10.0)
    summary_timeout: float = param(
        5.0, 'an episode file closes this long (s) after its final state if no EpisodeSummary '
        'comes', low=0.1, high=600.0)
    reorder_window: float = param(
        0.5, 'messages are handled in the order DDS received them, after waiting this long (s) '
        'for those the executor serves late (it serves topics in its own order)', low=0.0,
        high=10.0)
    max_buffered: int = param(
        100000, 'messages kept in memory between episodes; beyond, the oldest are dropped '
        'with an error log', low=100, high=10_000_000)
    recover: bool = param(
        True, 'at start, finish the files of this session that a killed recorder left open')
    subscription_depth: int = param(
        1000, 'history depth of the recording subscriptions', low=1, high=100000)
    discovery_period: float = param(
        0.5, 'period (s) of the graph check for topics of not yet known type', low=0.05,
        high=10.0)

    def check(self):
        """Return the reasons why fields that depend on each other are bad."""
        reasons = []
        if self.session_id and not _SESSION_ID.match(self.session_id):
            reasons.append(f'session_id: {self.session_id!r} must be 1-100 letters, digits, '
                           f'_ . - (no path separators)')
        if not self.topics:
            reasons.append('topics: at least one topic is needed')
        if len(set(self.topics)) != len(self.topics):
            reasons.append(f'topics: listed twice in {self.topics}')
        if not self.output_dir:
            reasons.append('output_dir: must not be empty')
        return reasons


class RecordingError(RuntimeError):
    """A bag could not be written (disk full, permissions, ...): the recording must stop."""


@dataclass(frozen=True)
class RawMessage:
    """One received message as CDR bytes, with reception and source times (ns, epoch)."""

    topic: str
    type_name: str          # pkg/msg/Type
    data: bytes
    log_time: int
    publish_time: int
    sequence: int = 0


@dataclass(frozen=True)
class TopicDescription:
    """What a bag records about a topic besides its messages (taken from the publishers)."""

    type_name: str
    offered_qos_profiles: tuple = ()        # rosbag2 v9 mappings (hrc_bag.qos_yaml)
    type_description_hash: str = ''         # RIHS01_...
    # the ros2msg schema text; empty: built from the installed .msg files
    message_definition: str = field(default='', compare=False, repr=False)


@dataclass(frozen=True)
class StateSeen:
    """A TaskState was received."""

    episode: int
    step: int
    final: bool                             # terminated or truncated


@dataclass(frozen=True)
class SummarySeen:
    """An EpisodeSummary was received."""

    episode: int
    session_id: str


@dataclass(frozen=True)
class SessionSeen:
    """A SessionStatus was received (``status``: its fields as plain Python values)."""

    status: dict


@dataclass
class FileInfo:
    """What metadata.yaml says about one closed file."""

    name: str
    start: int                              # ns, first log time (0 when empty)
    end: int                                # ns, last log time
    message_count: int
    topic_counts: dict                      # topic -> message count
    topics: dict                            # topic -> TopicDescription


def describe_error(error: OSError) -> str:
    """Return 'No space left on device (ENOSPC)' and the like."""
    name = errno.errorcode.get(error.errno, '') if error.errno else ''
    text = error.strerror or str(error)
    return f'{text} ({name})' if name else text


def package_version() -> str:
    """Return the installed hrc_bag version."""
    import importlib.metadata
    try:
        return importlib.metadata.version('hrc_bag')
    except importlib.metadata.PackageNotFoundError:
        return 'unknown'


def topic_metadata(topic: str, description: TopicDescription) -> dict:
    """Return the rosbag2 ``topic_metadata`` mapping of a topic (metadata version 9)."""
    return {
        'name': topic,
        'type': description.type_name,
        'serialization_format': MESSAGE_ENCODING,
        'offered_qos_profiles': [dict(profile) for profile in description.offered_qos_profiles],
        'type_description_hash': description.type_description_hash,
    }


def topic_entries(info: FileInfo) -> list:
    """Return the (topic, TopicDescription, message count) entries of one file."""
    return [(topic, info.topics[topic], count) for topic, count in info.topic_counts.items()]


def description_key(topic: str, description: TopicDescription) -> tuple:
    """Return what makes two topic entries of metadata.yaml the same entry."""
    return (topic, description.type_name, dump_profiles(description.offered_qos_profiles),
            description.type_description_hash)


def bag_metadata(files: list, entries: list, custom_data: dict) -> dict:
    """Return rosbag2's ``rosbag2_bagfile_information`` for ``files`` (FileInfo, in order).

    ``entries`` are (topic, TopicDescription, message count). A topic whose publishers offered
    other QoS profiles in another file gets an entry per variant, so that readers which match
    a file's channels to metadata.yaml's topics (rosbags) find every message.
    """
    non_empty = [info for info in files if info.message_count]
    start = min((info.start for info in non_empty), default=0)
    end = max((info.end for info in non_empty), default=0)
    return {
        'version': BAG_VERSION,
        'storage_identifier': STORAGE_IDENTIFIER,
        'duration': {'nanoseconds': end - start},
        'starting_time': {'nanoseconds_since_epoch': start},
        'message_count': sum(info.message_count for info in files),
        'topics_with_message_count': [
            {'topic_metadata': topic_metadata(topic, description), 'message_count': count}
            for topic, description, count in sorted(entries, key=lambda entry: entry[0])],
        'compression_format': '',           # chunks are compressed inside the MCAP files
        'compression_mode': '',
        'relative_file_paths': [info.name for info in files],
        'files': [{'path': info.name,
                   'starting_time': {'nanoseconds_since_epoch': info.start},
                   'duration': {'nanoseconds': info.end - info.start},
                   'message_count': info.message_count} for info in files],
        'custom_data': {str(key): str(value) for key, value in custom_data.items()} or None,
        'ros_distro': os.environ.get('ROS_DISTRO', 'jazzy'),
    }


def write_atomically(path: pathlib.Path, text: str) -> None:
    """Write ``text`` to a temporary file, fsync it, and rename it over ``path``."""
    temporary = path.with_name(f'.{path.name}.tmp')
    with open(temporary, 'w') as stream:
        stream.write(text)
        stream.flush()
        os.fsync(stream.fileno())
    os.replace(temporary, path)
    directory = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(directory)
    finally:
        os.close(directory)


class EpisodeFile:
    """One MCAP file being written: profile ros2, chunked, compressed, indexed, statistics."""

    def __init__(self, path, compression: str = 'zstd', chunk_size: int = 262144,
                 metadata: typing.Optional[dict] = None):
        self.path = pathlib.Path(path)
        self._schemas = {}                  # type name -> schema id
        self._channels = {}                 # topic -> channel id
        self.topics = {}                    # topic -> TopicDescription
        self.topic_counts = collections.Counter()
        self.message_count = 0
        self.start = 0
        self.end = 0
        self.closed = False
        try:
            # 'xb': never overwrite a file of an earlier recording
            self._stream = open(self.path, 'xb')
            self._writer = Writer(self._stream, chunk_size=chunk_size,
                                  compression=_COMPRESSION[compression],
                                  index_types=IndexType.ALL, use_chunking=True,
                                  use_statistics=True, use_summary_offsets=True)
            self._writer.start(profile=PROFILE, library=f'hrc_bag/{package_version()}')
            for name, record in (metadata or {}).items():
                self._writer.add_metadata(name, {str(k): str(v) for k, v in record.items()})
            self._stream.flush()
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error

    def write(self, message: RawMessage, description: TopicDescription) -> None:
        """Append one message (registering its schema and channel on first use)."""
        try:
            channel_id = self._channels.get(message.topic)
            if channel_id is None:
                channel_id = self._add_channel(message.topic, description)
            self._writer.add_message(channel_id, log_time=message.log_time,
                                     data=message.data, publish_time=message.publish_time,
                                     sequence=message.sequence & 0xFFFFFFFF)
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error
        self.topic_counts[message.topic] += 1
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
        return FileInfo(self.path.name, self.start, self.end, self.message_count,
                        dict(self.topic_counts), dict(self.topics))

    def close(self, custom_data: typing.Optional[dict] = None) -> FileInfo:
        """Finish the file (rosbag2 record, summary, indexes, footer), fsync, return its info."""
        info = self.info()
        try:
            self._writer.flush()
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


class SessionIndex:
    """The session folder's metadata.yaml: the closed files of the session, in order."""

    def __init__(self, folder, custom_data: dict):
        self.folder = pathlib.Path(folder)
        self.path = self.folder / 'metadata.yaml'
        self.custom_data = dict(custom_data)
        self.files = []
        self._entries = {}                  # description_key -> [topic, description, count]
        if self.path.is_file():
            self._load()

    def _load(self) -> None:
        """Continue a session an earlier recorder started (its closed files stay listed)."""
        document = load_yaml(self.path.read_text()) or {}
        information = document.get('rosbag2_bagfile_information', {}) or {}
        for entry in information.get('topics_with_message_count', []) or []:
            metadata = entry['topic_metadata']
            profiles = metadata.get('offered_qos_profiles') or []
            if isinstance(profiles, str):
                profiles = load_yaml(profiles) or []
            description = TopicDescription(metadata['type'], tuple(profiles),
                                           metadata.get('type_description_hash', ''))
            self._count(metadata['name'], description, int(entry['message_count']))
        for entry in information.get('files', []) or []:
            start = entry['starting_time']['nanoseconds_since_epoch']
            self.files.append(FileInfo(entry['path'], start,
                                       start + entry['duration']['nanoseconds'],
                                       entry['message_count'], {}, {}))
        self.custom_data = {**custom_data_of(information), **self.custom_data}

    def _count(self, topic: str, description: TopicDescription, count: int) -> None:
        key = description_key(topic, description)
        entry = self._entries.setdefault(key, [topic, description, 0])
        entry[2] += count

    def listed(self, name: str) -> bool:
        """Return True when the file ``name`` is listed already."""
        return any(info.name == name for info in self.files)

    def append(self, info: FileInfo) -> None:
        """List a closed file (without rewriting metadata.yaml)."""
        self.files.append(info)
        for topic, description, count in topic_entries(info):
            self._count(topic, description, count)

    def add(self, info: FileInfo) -> None:
        """List a closed file and rewrite metadata.yaml."""
        self.append(info)
        self.write()

    def write(self) -> None:
        """Rewrite metadata.yaml atomically."""
        entries = [tuple(entry) for entry in self._entries.values()]
        document = {'rosbag2_bagfile_information':
                    bag_metadata(self.files, entries, self.custom_data)}
        try:
            write_atomically(self.path, dump_yaml(document))
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error


def custom_data_of(information: dict) -> dict:
    """Return the custom_data mapping of a rosbag2 metadata dict (or {})."""
    return dict(information.get('custom_data') or {})


def session_summary(config: dict, status: typing.Optional[dict]) -> dict:
    """Return case, strategy, roles and seed of a session from its config, else its status."""
    status = status or {}
    roles = config.get('roles')
    if roles is None and ('robot_dof' in config or 'human_dof' in config):
        roles = {'robot': config.get('robot_dof'), 'human': config.get('human_dof')}
    if roles is None and status:
        dof = {0: 'translation', 1: 'rotation'}
        roles = {'robot': dof.get(status.get('robot_dof')),
                 'human': dof.get(status.get('human_dof'))}
    seeds = config.get('seeds', config.get('seed'))
    case = config.get('case', config.get('case_id', status.get('case_id')))
    return {
        'case_id': case if case is not None else '',
        'strategy': config.get('strategy', status.get('strategy', '')),
        'roles': roles if roles is not None else '',
        'seeds': seeds if seeds is not None else '',
    }


STATE_TYPE = 'hrc_msgs/msg/TaskState'
SUMMARY_TYPE = 'hrc_msgs/msg/EpisodeSummary'
SESSION_TYPE = 'hrc_msgs/msg/SessionStatus'
BOUNDARY_TYPES = (STATE_TYPE, SUMMARY_TYPE, SESSION_TYPE)


def message_fields(message) -> dict:
    """Return the fields of a ROS message as plain Python values (nested messages as dicts)."""
    result = {}
    for name in message.get_fields_and_field_types():
        value = getattr(message, name)
        if hasattr(value, 'get_fields_and_field_types'):
            value = message_fields(value)
        elif isinstance(value, (list, tuple)) or type(value).__name__ == 'array':
            value = [message_fields(item) if hasattr(item, 'get_fields_and_field_types')
                     else item for item in value]
        result[name] = value
    return result


def boundary_event(type_name: str, message):
    """Return the event a message of ``type_name`` means for the episode files (or None)."""
    if type_name == STATE_TYPE:
        return StateSeen(int(message.episode), int(message.step),
                         bool(message.terminated or message.truncated))
    if type_name == SUMMARY_TYPE:
        return SummarySeen(int(message.episode), str(message.session_id))
    if type_name == SESSION_TYPE:
        return SessionSeen(message_fields(message))
    return None


@dataclass
class OpenEpisode:
    """An episode file being written, and when and why it is to be closed."""

    file: EpisodeFile
    episode: typing.Optional[int]       # None for the end file
    close_at: typing.Optional[float] = None     # monotonic s
    reason: str = ''

    def schedule_close(self, close_at: float, reason: str) -> None:
        """Close at ``close_at`` unless an earlier close is scheduled already."""
        if self.close_at is None or close_at < self.close_at:
            self.close_at = close_at
            self.reason = reason


class EpisodeRecorder:
    """Route received messages into per-episode MCAP files following the boundary rule.

    A message goes to the file of its episode: the ``episode`` field of TaskState, HumanAction,
    AgentStep and EpisodeSummary; for commands (WrenchStamped) the episode of the state whose
    stamp they carry; other messages (SessionStatus, unknown topics) go to the newest open
    file, or wait for the next one between episodes.
    """

    def __init__(self, params: RecorderParams, describe_topic: typing.Callable,
                 session_config: typing.Optional[dict] = None, session_config_text: str = '',
                 logger=None, clock: typing.Callable = time.monotonic,
                 recorder_parameters: typing.Optional[dict] = None,
                 wall_clock: typing.Callable = time.time_ns):
        self.params = params
        self._describe_topic = describe_topic
        self.session_config = dict(session_config or {})
        self._session_config_text = session_config_text
        self._recorder_parameters = dict(recorder_parameters or {})
        self._log = logger
        self._clock = clock
        self._wall_clock = wall_clock       # ns since the epoch, the clock of the log times
        self._reorder = []                  # heap of (log time, arrival, message, event)
        self._arrivals = itertools.count()
        self.session_id = params.session_id or str(self.session_config.get('session_id', ''))
        self.folder = None
        self.index = None
        self.open_files = {}                # episode -> OpenEpisode
        self.current = None                 # the newest OpenEpisode (gets episode-less messages)
        self._closed_episodes = set()
        self._late = collections.Counter()  # episode -> messages that came after its file closed
        self._stamp_episodes = collections.OrderedDict()   # state stamp (ns) -> episode
        self._last_flush = clock()
        self._pending = collections.deque()
        self._dropped = 0
        self._descriptions = {}             # topic -> last good TopicDescription
        self.last_status = None
        self.closed_files = []              # FileInfo of files this recorder closed
        self.failed = None                  # RecordingError that stopped the recording
        if self.session_id:
            self._open_session()

    # -- logging ----------------------------------------------------------------------------

    def _info(self, text: str) -> None:
        if self._log is not None:
            self._log.info(text)

    def _warn(self, text: str) -> None:
        if self._log is not None:
            self._log.warning(text)

    def _error(self, text: str) -> None:
        if self._log is not None:
            self._log.error(text)

    # -- session folder ---------------------------------------------------------------------

    def _resolve_session_id(self) -> str:
        if self.last_status and self.last_status.get('session_id'):
            candidate = str(self.last_status['session_id'])
            if _SESSION_ID.match(candidate):
                return candidate
            self._warn(f'session id {candidate!r} from /hrc/session is not usable as a folder '
                       f'name; using the start time instead')
        return datetime.datetime.now(datetime.timezone.utc).strftime('session_%Y%m%d_%H%M%S')

    def _open_session(self) -> None:
        """Create (or continue) the session folder and its metadata.yaml."""
        self.folder = pathlib.Path(self.params.output_dir) / self.session_id
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise self._fail(f'cannot create the session folder {self.folder}: '
                             f'{describe_error(error)}', error)
        try:
            self.index = SessionIndex(self.folder, self._custom_data())
        except (OSError, yaml.YAMLError, KeyError, TypeError) as error:
            raise self._fail(f'cannot read {self.folder / "metadata.yaml"}: {error}', error)
        if self.params.recover:
            self._recover_unfinished()
        try:
            # proves at once that the folder is writable; lists closed files only
            self.index.write()
        except RecordingError as error:
            raise self._fail(str(error), error)
        self._info(f'recording session {self.session_id!r} into {self.folder}')

    def _recover_unfinished(self) -> None:
        from hrc_bag.recovery import recover_file
        for path in sorted(self.folder.glob('*.mcap')):
            if self.index.listed(path.name):
                continue
            try:
                info = recover_file(path, self.params.compression)
            except RecordingError as error:
                raise self._fail(str(error), error)
            self.index.append(info)
            self._warn(f'{path.name} was left open by an earlier recorder: finished it with '
                       f'{info.message_count} messages')

    def _custom_data(self) -> dict:
        summary = session_summary(self.session_config, self.last_status)
        return {'hrc.session_id': self.session_id,
                'hrc.case_id': summary['case_id'],
                'hrc.strategy': summary['strategy']}

    def _session_record(self, episode) -> dict:
        """Return the hrc_session metadata record written at the start of every file."""
        summary = session_summary(self.session_config, self.last_status)
        return {
            'session_id': self.session_id,
            'episode': '' if episode is None else str(episode),
            'case_id': str(summary['case_id']),
            'strategy': str(summary['strategy']),
            'roles': dump_yaml(summary['roles']),
            'seeds': dump_yaml(summary['seeds']),
            'package_version': str(self.session_config.get(
                'package_version', self.session_config.get('version', package_version()))),
            'recorder_version': package_version(),
            'session_config': self._session_config_text or dump_yaml(self.session_config),
            'recorder_parameters': dump_yaml(self._recorder_parameters),
            'session_status': dump_yaml(self.last_status) if self.last_status else '',
            'recorded_at': datetime.datetime.now(datetime.timezone.utc).isoformat(),
        }

    def _fail(self, text: str, cause=None) -> RecordingError:
        error = RecordingError(text)
        if cause is not None:
            error.__cause__ = cause
        self.failed = error
        self._error(f'recording stopped: {text}')
        return error

    # -- files ------------------------------------------------------------------------------

    def _file_path(self, stem: str) -> pathlib.Path:
        path = self.folder / f'{stem}.mcap'
        suffix = 1
        while path.exists():
            suffix += 1
            path = self.folder / f'{stem}_{suffix}.mcap'
        return path

    def _open(self, episode: typing.Optional[int]) -> OpenEpisode:
        if self.folder is None:
            self.session_id = self._resolve_session_id()
            self._open_session()
        stem = (f'{self.session_id}_ep{episode:04d}' if episode is not None
                else f'{self.session_id}{END_FILE_SUFFIX}')
        path = self._file_path(stem)
        try:
            file = EpisodeFile(path, self.params.compression, self.params.chunk_size,
                               {SESSION_RECORD: self._session_record(episode)})
        except RecordingError as error:
            raise self._fail(str(error), error)
        self.current = OpenEpisode(file, episode)
        self.open_files[episode] = self.current
        self._last_flush = self._clock()
        self._info(f'episode {episode if episode is not None else "(none)"}: recording into '
                   f'{path.name}' + (f' ({len(self._pending)} messages from before it)'
                                     if self._pending else ''))
        while self._pending:
            self._write(self.current, self._pending.popleft())
        return self.current

    def _close(self, episode: OpenEpisode, reason: str) -> None:
        self.open_files.pop(episode.episode, None)
        if episode is self.current:
            self.current = None
        if episode.episode is not None:
            self._closed_episodes.add(episode.episode)
        try:
            info = episode.file.close(self.index.custom_data)
            self.index.add(info)
        except RecordingError as error:
            raise self._fail(str(error), error)
        self.closed_files.append(info)
        number = episode.episode if episode.episode is not None else '(none)'
        self._info(f'episode {number}: closed {info.name} ({info.message_count} messages, '
                   f'{reason})')

    def _description(self, message: RawMessage) -> TopicDescription:
        description = self._describe_topic(message.topic, message.type_name)
        previous = self._descriptions.get(message.topic)
        if description is None or (not description.offered_qos_profiles and previous):
            description = previous or TopicDescription(message.type_name)
        self._descriptions[message.topic] = description
        return description

    def _write(self, episode: OpenEpisode, message: RawMessage) -> None:
        try:
            episode.file.write(message, self._description(message))
        except RecordingError as error:
            raise self._fail(str(error), error)
        except msgdefs.DefinitionNotFound as error:
            raise self._fail(f'cannot record {message.topic}: {error}', error)

    def _buffer(self, message: RawMessage) -> None:
        self._pending.append(message)
        if len(self._pending) > self.params.max_buffered:
            self._pending.popleft()
            self._dropped += 1
            if self._dropped == 1 or self._dropped % 1000 == 0:
                self._error(f'{self._dropped} messages dropped: more than '
                            f'{self.params.max_buffered} arrived while no episode was open')

    # -- the interface the node uses --------------------------------------------------------

    @property
    def current_episode(self) -> typing.Optional[int]:
        """Return the episode of the newest open file (None between episodes)."""
        return self.current.episode if self.current is not None else None

    def record(self, message: RawMessage, event=None) -> None:
        """Record one message; ``event`` says what it means for the episode boundaries.

        Messages wait ``reorder_window`` seconds (of their log time) and are then handled in
        log-time order: the executor takes one message per subscription in turn, so when the
        recorder lags, a topic's messages reach it later than another's received after them.
        """
        if self.failed is not None:
            raise self.failed
        heapq.heappush(self._reorder, (message.log_time, next(self._arrivals), message, event))
        self.tick()

    def _release(self, everything: bool = False) -> None:
        """Handle the waiting messages received more than reorder_window ago."""
        threshold = self._wall_clock() - int(self.params.reorder_window * 1e9)
        while self._reorder and (everything or self._reorder[0][0] <= threshold):
            _, _, message, event = heapq.heappop(self._reorder)
            self._handle(message, event)

    def _episode_of(self, message: RawMessage, event) -> typing.Optional[int]:
        """Return the episode a message belongs to, or None when it does not say."""
        if isinstance(event, (StateSeen, SummarySeen)):
            return event.episode
        stamp, episode = cdr_peek.peek(message.type_name, message.data)
        if episode is None and stamp is not None and not message.type_name.startswith('hrc_'):
            # a command (or a marker, an image) stamped with the state it belongs to; the
            # session's own messages (SessionStatus) say nothing about an episode
            episode = self._stamp_episodes.get(stamp)
        return episode

    def _remember_stamp(self, message: RawMessage, episode: int) -> None:
        stamp, _ = cdr_peek.peek(message.type_name, message.data)
        if stamp is not None:
            self._stamp_episodes[stamp] = episode
            while len(self._stamp_episodes) > 10000:
                self._stamp_episodes.popitem(last=False)

    def _handle(self, message: RawMessage, event) -> None:
        """Route one message (in log-time order) following the boundary rule."""
        now = self._clock()
        grace = self.params.close_grace
        if isinstance(event, SessionSeen):
            self.last_status = dict(event.status)
            if event.status.get('phase') in SESSION_FINISHED_PHASES:
                for episode in self.open_files.values():
                    episode.schedule_close(now + grace, 'the session finished')
        number = self._episode_of(message, event)
        if isinstance(event, StateSeen):
            self._remember_stamp(message, event.episode)
        target = self.open_files.get(number) if number is not None else self.current
        if (target is None and isinstance(event, StateSeen)
                and number not in self._closed_episodes):
            # a new episode starts: the files before it close after the grace (their late
            # messages on other topics still find them)
            for episode in self.open_files.values():
                episode.schedule_close(now + grace, f'episode {number} started')
            target = self._open(number)
        elif target is None and number is not None and number in self._closed_episodes:
            target = self.current                           # came after its file closed
            self._late[number] += 1
            if self._late[number] == 1:
                self._warn(f'a message of episode {number} ({message.topic}) arrived after its '
                           f'file closed: recorded in the newest file instead')
        if target is not None:
            self._write(target, message)
        else:
            self._buffer(message)
        if isinstance(event, StateSeen) and event.final and number in self.open_files:
            self.open_files[number].schedule_close(now + self.params.summary_timeout,
                                                   'no EpisodeSummary after the final state')
        if isinstance(event, SummarySeen) and number in self.open_files:
            self.open_files[number].schedule_close(now + grace, 'EpisodeSummary received')

    def tick(self) -> None:
        """Handle due messages; close files whose time has come; write the chunk if due."""
        if self.failed is not None:
            raise self.failed
        self._release()
        now = self._clock()
        for episode in list(self.open_files.values()):
            if episode.close_at is not None and now >= episode.close_at:
                self._close(episode, episode.reason)
        if now - self._last_flush >= self.params.flush_period:
            self._last_flush = now
            for episode in self.open_files.values():
                try:
                    episode.file.flush()
                except RecordingError as error:
                    raise self._fail(str(error), error)

    def close(self) -> None:
        """Close the open files; write what arrived after the last episode to the end file."""
        if self.failed is not None:
            for episode in self.open_files.values():
                episode.file.abandon()
            self.open_files.clear()
            self.current = None
            return
        self._release(everything=True)
        for episode in list(self.open_files.values()):
            self._close(episode, 'the recorder stopped')
        if self._pending:
            self._close(self._open(None), 'the recorder stopped')
