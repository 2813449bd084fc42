"""The hrc bag format's vocabulary: names, records, QoS metadata (pure, no rclpy).

This is the layer every bag tool imports (the recorder's routing policy in ``recording.py``,
``recovery.py``, the in-process writer ``session_writer.py``, replay and the report); it
imports none of them. What one session folder holds (``<output_dir>/<session_id>/``)::

    metadata.yaml                 rosbag2 bag metadata (version 9, storage mcap), rewritten
                                  atomically each time an episode file is closed; it lists
                                  closed files only (:mod:`hrc_bag.session_index`)
    <session_id>_episode0001.mcap one MCAP file per episode, named by the episode's number
                                  (counted from 1, as people read it; episode_file_stem) ...
    <session_id>_end.mcap         messages after the last episode (only if there are any)

Each MCAP file (:class:`hrc_bag.episode_file.EpisodeFile`) has profile ``ros2``, zstd chunks,
every index, statistics and summary offsets, and holds:

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

Writing messages without rclpy (the in-process engine): :func:`hrc_bag.serializer.encode`
turns a plain mapping or an object with the message's attributes (a dataclass) into the CDR
bytes rclpy would publish, and :func:`offered_profile` / :func:`contract_description` give
the QoS metadata a live publisher would have offered.
:class:`hrc_bag.session_writer.SessionWriter` puts these together into the writer API the
engine uses; its bags are the recorder node's bags.
"""

import collections
import dataclasses
from dataclasses import dataclass, field
import datetime
import errno
import functools
import importlib.metadata
import json
import pathlib
import re
import typing

from hrc_common.contract import DOF_NAME, NS_PER_S, PERSONAL_FILE_MODE, PUBLIC_FILE_MODE
from hrc_common.episode_numbers import episode_number
from hrc_common.topics import ROBOT_DESCRIPTION

from hrc_bag import cdr_peek, msgdefs
from hrc_bag.qos_yaml import dump_yaml

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


# Latched topics whose newest message every episode file repeats at its start, so that one
# file alone shows the system in a viewer (Foxglove, RViz): the sim's URDF.
REPEATED_IN_EVERY_FILE = (ROBOT_DESCRIPTION,)


class LatchedMessages:
    """The newest message of each :data:`REPEATED_IN_EVERY_FILE` topic, for the next file."""

    def __init__(self):
        self.newest = {}

    def seen(self, message: RawMessage) -> None:
        """Take a message as it is recorded."""
        if message.topic in REPEATED_IN_EVERY_FILE:
            self.newest[message.topic] = message

    def missing_from(self, written: list) -> list:
        """Return the newest latched messages a new file lacks after ``written`` (its first)."""
        return [message for message in self.newest.values()
                if not any(message is other for other in written)]


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
    """Return the file name (without .mcap) of the episode with this 0-based index.

    ``<id>_episode0001`` for index 0: the number the page and the runner show. None: the end
    file.
    """
    return (f'{session_id}_episode{episode_number(episode):04d}' if episode is not None
            else f'{session_id}{END_FILE_SUFFIX}')


def index_named_file_stem(session_id: str, episode: int) -> str:
    """Return the name folders written before hrc 1.0 gave an episode: ``_ep<index>``."""
    return f'{session_id}_ep{episode:04d}'


# <id>_episode0061 (number 61 = index 60) or, before hrc 1.0, <id>_ep0060 (index 60); then
# _attempt2 (a re-run, hrc_bag.recording) or _2 (the name was taken)
_EPISODE_FILE_NAME = re.compile(r'_(episode|ep)(\d+)(?:_attempt(\d+)|_(\d+))?$')


def episode_file_key(stem: str) -> typing.Optional[tuple]:
    """Return (episode index, attempt) of an episode file's stem, None if it names none."""
    match = _EPISODE_FILE_NAME.search(stem)
    if match is None:
        return None
    counted, digits = match.group(1), int(match.group(2))
    index = digits - 1 if counted == 'episode' else digits
    return index, int(match.group(3) or match.group(4) or 1)


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


# -- messages as plain values ---------------------------------------------------------------

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
