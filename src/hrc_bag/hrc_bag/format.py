"""The hrc bag format: episode MCAP files, their records, metadata.yaml (pure, no rclpy).

This is the layer every bag tool imports (the recorder's routing policy in ``recording.py``,
``recovery.py``, the in-process writer ``session_writer.py``, replay and the report); it
imports none of them. What one session folder holds (``<output_dir>/<session_id>/``)::

    metadata.yaml                 rosbag2 bag metadata (version 9, storage mcap), rewritten
                                  atomically each time an episode file is closed; it lists
                                  closed files only
    <session_id>_ep0000.mcap      one MCAP file per episode (episode_file_stem) ...
    <session_id>_end.mcap         messages after the last episode (only if there are any)

Each MCAP file (:class:`EpisodeFile`) has profile ``ros2``, zstd chunks, every index,
statistics and summary offsets, and holds:

* one ``ros2msg`` schema per message type: the type's .msg text with its dependencies
  (:mod:`hrc_bag.msgdefs`, the layout rosbag2 writes);
* one ``cdr`` channel per topic whose metadata holds ``offered_qos_profiles`` (YAML of the
  publishers' offered profiles in rosbag2 v9 form, :mod:`hrc_bag.qos_yaml`) and
  ``topic_type_hash`` (RIHS01 of the type);
* the ``hrc_session`` metadata record (:func:`session_record`: session id, episode, case,
  strategy, roles, seeds, versions, the session configuration as YAML, the writer's
  parameters, the last SessionStatus, when it was written), written first;
* at close, the ``hrc_episode`` record (:class:`HumanInputTally`: which input drove the
  human in this episode, steps per source) and rosbag2's own ``rosbag2`` record (this file's
  bag metadata), then summary, indexes, footer; the file is fsynced before metadata.yaml
  lists it.

A file holding personal data (a session configuration with a non-empty ``subject_id`` or
``notes``) is created owner-only (0600), and so is a metadata.yaml that names them.

Writing messages without rclpy (the in-process engine): :class:`MessageEncoder` turns a plain
mapping or an object with the message's attributes (a dataclass) into the CDR bytes rclpy
would publish (mcap-ros2-support's encoder, with the .msg definitions of the installed
packages), and :func:`offered_profile` / :func:`contract_description` give the QoS metadata a
live publisher would have offered. :class:`hrc_bag.session_writer.SessionWriter` puts these
together into the writer API the engine uses; its bags are the recorder node's bags.
"""

import collections
import dataclasses
from dataclasses import dataclass, field
import datetime
import errno
import functools
import importlib.metadata
import json
import os
import pathlib
import typing

from hrc_common.contract import (atomic_write, DOF_NAME, NS_PER_S, PERSONAL_FILE_MODE,
                                 PUBLIC_FILE_MODE)
from mcap.writer import CompressionType, IndexType, Writer
from mcap_ros2._dynamic import serialize_dynamic
import yaml

from hrc_bag import cdr_peek, msgdefs
from hrc_bag.qos_yaml import dump_profiles, dump_yaml, load_yaml

BAG_VERSION = 9                 # rosbag2 metadata version written (ROS 2 Jazzy)
STORAGE_IDENTIFIER = 'mcap'
PROFILE = 'ros2'
SCHEMA_ENCODING = 'ros2msg'
MESSAGE_ENCODING = 'cdr'
SESSION_RECORD = 'hrc_session'  # name of the MCAP metadata record with the session config
EPISODE_RECORD = 'hrc_episode'  # name of the record of what the file's episode held (at close)
ROSBAG2_RECORD = 'rosbag2'      # name of rosbag2's own metadata record
METADATA_FILE = 'metadata.yaml'
END_FILE_SUFFIX = '_end'
# keys of a session configuration whose values identify or describe a person
PERSONAL_KEYS = ('subject_id', 'notes')

COMPRESSIONS = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4,
                'none': CompressionType.NONE}
DEFAULT_CHUNK_SIZE = 262144     # B

# What rmw reports for an unset duration of an offered profile (RMW_DURATION_INFINITE).
_INFINITE = {'sec': 9223372036, 'nsec': 854775807}


class RecordingError(RuntimeError):
    """A bag could not be written (disk full, permissions, ...): the recording must stop."""


def describe_error(error: OSError) -> str:
    """Return 'No space left on device (ENOSPC)' and the like."""
    name = errno.errorcode.get(error.errno, '') if error.errno else ''
    text = error.strerror or str(error)
    return f'{text} ({name})' if name else text


def package_version() -> str:
    """Return the installed hrc_bag version."""
    try:
        return importlib.metadata.version('hrc_bag')
    except importlib.metadata.PackageNotFoundError:
        return 'unknown'


def holds_personal_data(config: typing.Optional[dict]) -> bool:
    """Return True when a session configuration names a subject or carries notes."""
    return isinstance(config, dict) and any(config.get(key) for key in PERSONAL_KEYS)


def file_mode(config: typing.Optional[dict]) -> int:
    """Return the mode of the bag files of a session with configuration ``config``."""
    return PERSONAL_FILE_MODE if holds_personal_data(config) else PUBLIC_FILE_MODE


# -- records ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class RawMessage:
    """One message as CDR bytes, with reception and source times (ns, epoch)."""

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


@dataclass
class FileInfo:
    """What metadata.yaml says about one closed file."""

    name: str
    start: int                              # ns, first log time (0 when empty)
    end: int                                # ns, last log time
    message_count: int
    topic_counts: dict                      # topic -> message count
    topics: dict                            # topic -> TopicDescription


def offered_profile(reliable: bool = True, transient_local: bool = False,
                    deadline_ns: int = 0) -> dict:
    """Return an offered QoS profile as the ROS graph reports it (rosbag2 v9 mapping).

    This is what the recorder node stores for a live publisher: history 'unknown' and depth 0
    (DDS does not advertise them), unset durations as RMW_DURATION_INFINITE, liveliness
    'automatic'. ``deadline_ns`` 0 means no deadline.
    """
    deadline = ({'sec': deadline_ns // NS_PER_S, 'nsec': deadline_ns % NS_PER_S}
                if deadline_ns else dict(_INFINITE))
    return {'history': 'unknown', 'depth': 0,
            'reliability': 'reliable' if reliable else 'best_effort',
            'durability': 'transient_local' if transient_local else 'volatile',
            'deadline': deadline, 'lifespan': dict(_INFINITE), 'liveliness': 'automatic',
            'liveliness_lease_duration': dict(_INFINITE),
            'avoid_ros_namespace_conventions': False}


@functools.lru_cache(maxsize=None)
def type_hash(type_name: str) -> str:
    """Return the RIHS01 type hash of an installed type ('' when it is not known).

    Read from the ``share/<pkg>/msg/<Type>.json`` type description rosidl installs: the same
    hash a live publisher advertises (``topic_type_hash``).
    """
    try:
        package, name = msgdefs.split_type_name(type_name)
        path = msgdefs.share_directory(package) / 'msg' / f'{name}.json'
        hashes = json.loads(path.read_text()).get('type_hashes', [])
    except (ValueError, OSError, msgdefs.DefinitionNotFound, json.JSONDecodeError):
        return ''
    wanted = f'{package}/msg/{name}'
    return next((entry.get('hash_string', '') for entry in hashes
                 if entry.get('type_name') == wanted), '')


def contract_description(type_name: str, reliable: bool = True, transient_local: bool = False,
                         deadline_ns: int = 0) -> TopicDescription:
    """Return the TopicDescription of a topic whose one publisher offers the given QoS."""
    return TopicDescription(type_name, (offered_profile(reliable, transient_local,
                                                        deadline_ns),),
                            type_hash(type_name))


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


# metadata.yaml's two lists that grow with every closed file. The whole document was dumped
# again at every close: the pure-Python YAML representer over every file so far, 4.8 ms at 100
# files and 14 ms at 300 (quadratic over a session, 12% of the recorder's Python in a
# 30-episode session); each file's lines are dumped once now and joined.
GROWING_LISTS = ('relative_file_paths', 'files')


def dump_bag_metadata(files: list, entries: list, custom_data: dict, cache: dict) -> str:
    """Return metadata.yaml's text: ``dump_yaml`` of ``bag_metadata``, the same text.

    ``cache`` (a dict the caller keeps between calls) holds each file's lines of the two lists
    that grow with the session, dumped once each; the rest is dumped every time.
    """
    information = bag_metadata(files, entries, custom_data)
    placeholders = {key: f'HRCGROWINGLIST{index}' for index, key in enumerate(GROWING_LISTS)}
    lists = {key: information[key] for key in GROWING_LISTS}
    information.update(placeholders)
    text = dump_yaml({'rosbag2_bagfile_information': information})
    for key in GROWING_LISTS:
        if not lists[key]:
            lines = f'  {key}: []\n'
        else:
            items = []
            for info, item in zip(files, lists[key]):
                cache_key = (key, info.name, info.start, info.end, info.message_count)
                if cache_key not in cache:
                    # a sequence inside a mapping is written without indentation of its own
                    # ("  files:" then "  - path: ..."): the item's lines indented by two
                    cache[cache_key] = ''.join('  ' + line for line in
                                               dump_yaml([item]).splitlines(keepends=True))
                items.append(cache[cache_key])
            lines = f'  {key}:\n' + ''.join(items)
        text = text.replace(f'  {key}: {placeholders[key]}\n', lines, 1)
    return text


def custom_data_of(information: dict) -> dict:
    """Return the custom_data mapping of a rosbag2 metadata dict (or {})."""
    custom = information.get('custom_data') if isinstance(information, dict) else None
    return dict(custom) if isinstance(custom, dict) else {}


# -- the session record ----------------------------------------------------------------------

def session_summary(config: dict, status: typing.Optional[dict]) -> dict:
    """Return case, strategy, roles and seed of a session from its config, else its status."""
    status = status or {}
    roles = config.get('roles')
    if roles is None and ('robot_dof' in config or 'human_dof' in config):
        roles = {'robot': config.get('robot_dof'), 'human': config.get('human_dof')}
    if roles is None and status:
        roles = {'robot': DOF_NAME.get(status.get('robot_dof')),
                 'human': DOF_NAME.get(status.get('human_dof'))}
    seeds = config.get('seeds', config.get('seed'))
    case = config.get('case', config.get('case_id', status.get('case_id')))
    return {
        'case_id': case if case is not None else '',
        'strategy': config.get('strategy', status.get('strategy', '')),
        'roles': roles if roles is not None else '',
        'seeds': seeds if seeds is not None else '',
    }


def session_custom_data(session_id: str, config: dict, status: typing.Optional[dict]) -> dict:
    """Return the ``custom_data`` of metadata.yaml: session id, case and strategy."""
    summary = session_summary(config, status)
    return {'hrc.session_id': session_id, 'hrc.case_id': summary['case_id'],
            'hrc.strategy': summary['strategy']}


def session_record(session_id: str, episode: typing.Optional[int], config: dict,
                   config_text: str = '', status: typing.Optional[dict] = None,
                   writer_parameters: typing.Optional[dict] = None,
                   now: typing.Optional[datetime.datetime] = None) -> dict:
    """Return the ``hrc_session`` metadata record written at the start of every file.

    ``config`` is the session configuration (``config_text`` its YAML as written, kept
    verbatim when given), ``status`` the last SessionStatus as plain values, and
    ``writer_parameters`` the recorder's (or in-process writer's) parameters.
    """
    summary = session_summary(config, status)
    return {
        'session_id': session_id,
        'episode': '' if episode is None else str(episode),
        'case_id': str(summary['case_id']),
        'strategy': str(summary['strategy']),
        'roles': dump_yaml(summary['roles']),
        'seeds': dump_yaml(summary['seeds']),
        'package_version': str(config.get('package_version',
                                          config.get('version', package_version()))),
        'recorder_version': package_version(),
        'session_config': config_text or dump_yaml(config),
        'recorder_parameters': dump_yaml(dict(writer_parameters or {})),
        'session_status': dump_yaml(status) if status else '',
        'recorded_at': (now or datetime.datetime.now(datetime.timezone.utc)).isoformat(),
    }


def episode_file_stem(session_id: str, episode: typing.Optional[int]) -> str:
    """Return the file name (without .mcap) of an episode (None: the end file)."""
    return (f'{session_id}_ep{episode:04d}' if episode is not None
            else f'{session_id}{END_FILE_SUFFIX}')


def unused_path(folder, stem: str) -> pathlib.Path:
    """Return ``folder/stem.mcap``, or ``stem_2.mcap``, ... when the name is taken."""
    folder = pathlib.Path(folder)
    path = folder / f'{stem}.mcap'
    suffix = 1
    while path.exists():
        suffix += 1
        path = folder / f'{stem}_{suffix}.mcap'
    return path


# -- the human's input sources of an episode -------------------------------------------------

@functools.lru_cache(maxsize=None)
def source_names() -> dict:
    """Return {HumanAction.source code: name}: device, joy, simulated, replay, none."""
    names = {}
    for constant, value in msgdefs.constants(cdr_peek.HUMAN_ACTION_TYPE).items():
        if constant.startswith('SOURCE_') and value.isdigit():
            names[int(value)] = constant[len('SOURCE_'):].lower()
    return names


def source_name(code: int) -> str:
    """Return the name of a HumanAction.source code ('source N' if unknown)."""
    return source_names().get(code, f'source {code}')


class HumanInputTally:
    """Count one episode's human steps per input source (HumanAction.source).

    ``record()`` is the ``hrc_episode`` metadata record every episode file gets at close:
    ``human_source`` the source of most engaged steps (of most steps when the human was never
    engaged; '' without HumanAction), ``human_sources`` every source seen, most steps first,
    ``human_steps`` / ``human_engaged_steps`` YAML {source: steps}, ``control_period`` the
    simulation time between two steps (s, from the stamps; '' if unknown).
    """

    def __init__(self):
        self.steps = collections.Counter()          # source name -> steps
        self.engaged = collections.Counter()        # source name -> engaged steps
        self._seen = set()                          # (episode, step): a repeat counts once
        self._first = None                          # (step, stamp ns)
        self._last = None

    def add(self, stamp: int, episode: int, step: int, source: int, engaged: bool) -> None:
        """Count one HumanAction."""
        if (episode, step) in self._seen:
            return
        self._seen.add((episode, step))
        name = source_name(source)
        self.steps[name] += 1
        if engaged:
            self.engaged[name] += 1
        if self._first is None or step < self._first[0]:
            self._first = (step, stamp)
        if self._last is None or step > self._last[0]:
            self._last = (step, stamp)

    def add_cdr(self, data: bytes) -> None:
        """Count a HumanAction given as CDR bytes (ignored when it cannot be read)."""
        fields = cdr_peek.human_action(data)
        if fields is not None:
            self.add(*fields)

    @property
    def control_period(self) -> typing.Optional[float]:
        """Return the simulation time between two steps (s), or None."""
        if self._first is None or self._last[0] == self._first[0]:
            return None
        return (self._last[1] - self._first[1]) / NS_PER_S / (self._last[0] - self._first[0])

    def record(self) -> dict:
        """Return the ``hrc_episode`` record fields (strings)."""
        counts = self.engaged if self.engaged else self.steps
        ranked = [name for name, _ in self.steps.most_common()]
        period = self.control_period
        return {'human_source': counts.most_common(1)[0][0] if counts else '',
                'human_sources': ','.join(ranked),
                'human_steps': dump_yaml(dict(self.steps)),
                'human_engaged_steps': dump_yaml(dict(self.engaged)),
                'control_period': '' if period is None else repr(period)}


# -- one MCAP file ---------------------------------------------------------------------------

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


# -- metadata.yaml ---------------------------------------------------------------------------

class SessionIndex:
    """The session folder's metadata.yaml: the closed files of the session, in order.

    An existing metadata.yaml (an earlier recorder of the same session) is continued; one
    that cannot be used (unreadable, not YAML, not a mapping, wrong shape) is set aside:
    ``problem`` says why, and the files it listed are listed again by whoever finds them
    (the recorder's recovery lists every MCAP file it finds unlisted).
    """

    def __init__(self, folder, custom_data: dict, mode: int = PUBLIC_FILE_MODE):
        self.folder = pathlib.Path(folder)
        self.path = self.folder / METADATA_FILE
        self.custom_data = dict(custom_data)
        self.mode = mode
        self.files = []
        self.problem = ''
        self._entries = {}                  # description_key -> [topic, description, count]
        self._file_lines = {}               # dump_bag_metadata's cache of each file's lines
        if self.path.is_file():
            try:
                self._load()
            except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError,
                    AttributeError) as error:
                self.problem = f'{self.path} cannot be used ({error}): rebuilt from the files'
                self.files, self._entries = [], {}

    def _load(self) -> None:
        """Continue a session an earlier recorder started (its closed files stay listed)."""
        try:
            document = load_yaml(self.path.read_text())
        except yaml.YAMLError as error:
            raise ValueError(f'not YAML: {str(error).splitlines()[0]}') from None
        if document is None:
            return
        if not isinstance(document, dict):
            raise ValueError(f'a {type(document).__name__}, not a mapping')
        information = document.get('rosbag2_bagfile_information', {}) or {}
        if not isinstance(information, dict):
            raise ValueError('rosbag2_bagfile_information is not a mapping')
        for entry in information.get('topics_with_message_count', []) or []:
            metadata = entry['topic_metadata']
            profiles = metadata.get('offered_qos_profiles') or []
            if isinstance(profiles, str):
                profiles = load_yaml(profiles) or []
            description = TopicDescription(metadata['type'], tuple(profiles),
                                           metadata.get('type_description_hash', ''))
            self._count(metadata['name'], description, int(entry['message_count']))
        for entry in information.get('files', []) or []:
            start = int(entry['starting_time']['nanoseconds_since_epoch'])
            self.files.append(FileInfo(str(entry['path']), start,
                                       start + int(entry['duration']['nanoseconds']),
                                       int(entry['message_count']), {}, {}))
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
        text = dump_bag_metadata(self.files, entries, self.custom_data, self._file_lines)
        try:
            atomic_write(self.path, text, self.mode)
        except OSError as error:
            raise RecordingError(f'cannot write {self.path}: {describe_error(error)}') from error


# -- encoding messages without rclpy ---------------------------------------------------------

def plain_values(message):
    """Return a message (mapping, dataclass, rclpy or rosbags message) as plain values."""
    if isinstance(message, dict):
        return {key: plain_values(value) for key, value in message.items()}
    if dataclasses.is_dataclass(message) and not isinstance(message, type):
        # (rosbags messages also hold their constants, upper case, and __msgtype__; ROS field
        # names are lower case)
        return {item.name: plain_values(getattr(message, item.name))
                for item in dataclasses.fields(message)
                if not item.name.startswith('_') and not item.name.isupper()}
    if hasattr(message, 'get_fields_and_field_types'):
        return {name: plain_values(getattr(message, name))
                for name in message.get_fields_and_field_types()}
    if isinstance(message, (list, tuple)) or type(message).__name__ in ('array', 'ndarray'):
        return [plain_values(item) for item in message]
    return message



class MessageEncoder:
    """Serialize messages given as plain values to CDR, as rclpy would publish them.

    ``encode(type_name, message)`` takes a mapping (``{'header': {'stamp': {'sec': 1,
    'nanosec': 0}, 'frame_id': 'world'}, 'episode': 3, ...}``) or any object with the
    message's fields as attributes (a dataclass, a rosbags or rclpy message). Fields left out
    take their zero value; a name that is not a field of the type (a typo) raises ValueError.
    The bytes equal rclpy's except for the padding bytes, which are zero here.
    """

    def __init__(self):
        self._encoders = {}

    def _encoder(self, type_name: str):
        encoder = self._encoders.get(type_name)
        if encoder is None:
            package, name = msgdefs.split_type_name(type_name)
            full_name = f'{package}/msg/{name}'
            encoders = serialize_dynamic(full_name, msgdefs.full_definition(full_name))
            encoder = self._encoders[type_name] = encoders[full_name]
        return encoder

    def encode(self, type_name: str, message) -> bytes:
        """Return the CDR bytes of ``message`` (a mapping or an object) of ``type_name``."""
        if isinstance(message, (bytes, bytearray, memoryview)):
            return bytes(message)
        if isinstance(message, dict):
            check_fields(type_name, message)
        return bytes(self._encoder(type_name)(message))


def check_fields(type_name: str, message: dict, path: str = '') -> None:
    """Raise ValueError naming every key of ``message`` that is not a field of the type."""
    package, _ = msgdefs.split_type_name(type_name)
    fields = {name: kind for kind, name in msgdefs.fields(type_name)}
    unknown = sorted(set(message) - set(fields))
    if unknown:
        raise ValueError(f'{type_name}: no field {", ".join(path + name for name in unknown)} '
                         f'(fields: {", ".join(fields)})')
    for name, value in message.items():
        field_type = fields[name].split('[', 1)[0].split('<=', 1)[0]
        if isinstance(value, dict) and field_type not in msgdefs.PRIMITIVE_TYPES:
            if '/' not in field_type:
                field_type = f'{package}/{field_type}'
            check_fields(field_type, value, f'{path}{name}.')
