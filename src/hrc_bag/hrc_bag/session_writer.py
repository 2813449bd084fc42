"""Write an hrc session folder in-process, from plain values (no rclpy, no DDS).

The in-process engine (``hrc_engine``) runs sim, agent and human in one process; it writes
the same bags the recorder node writes for a graph (:mod:`hrc_bag.format`: one MCAP file per
episode, metadata.yaml, the ``hrc_session`` record, QoS metadata and type hashes of the
publishers the graph would have), so recovery, replay, the report and rosbags read both alike.

Usage::

    from hrc_bag.session_writer import SessionWriter

    writer = SessionWriter('bags', 'case2-seed0-20261130-201500',
                           session_config={'case': 2, 'strategy': 'responsibility_guided',
                                           'seeds': {'session': 0}, ...})
    writer.write('/hrc/session', {'session_id': ..., 'episode': 0, 'phase': 0, ...}, t_ns)
    writer.begin_episode(0)                 # opens <session_id>_episode0001.mcap
    writer.write('/hrc/state', {'header': {'stamp': {'sec': 0, 'nanosec': 0},
                                           'frame_id': 'world'}, 'episode': 0, ...}, t_ns)
    ...                                     # commands, human action, agent step per step
    writer.write('/hrc/episode', summary, t_ns)
    writer.end_episode()                    # footer, index, fsync; metadata.yaml lists it
    ...
    writer.close()                          # what came after the last episode: _end.mcap

* ``write(topic, message, log_time_ns, type_name=None, publish_time_ns=None)``: ``message`` is
  a mapping, an object with the fields as attributes (a dataclass), or CDR bytes, encoded by
  :func:`hrc_bag.serializer.encode`; the type of the /hrc topics is known (``TOPIC_TYPES``),
  other topics need ``type_name``. Messages written
  while no episode is open wait in memory and open the next episode's file (as the recorder
  does with the SessionStatus announcing an episode); the last SessionStatus written goes
  into the ``hrc_session`` record of the files opened after it.
* ``begin_episode(n)`` closes the open episode first; ``end_episode()`` closes the file at
  once (footer, indexes, fsync, metadata.yaml rewritten atomically): durable as soon as the
  episode's last message is in.
* Log times are ns since the epoch (what the recorder stores: reception time); the engine
  passes its wall clock, or a synthetic clock for deterministic files.
* ``descriptions`` ({topic: TopicDescription}) overrides the QoS metadata; by default the
  contract QoS (``hrc_common.qos_table``) as a live publisher offers it.
"""

import pathlib
import typing

from hrc_common import contract, qos_table
from hrc_common import topics as hrc_topics

from hrc_bag import serializer
from hrc_bag.episode_file import DEFAULT_CHUNK_SIZE, EpisodeFile
from hrc_bag.format import (episode_file_stem, file_mode, FileInfo, LatchedMessages,
                            offered_profile,
                            plain_values, RawMessage, RecordingError, session_custom_data,
                            SESSION_RECORD, session_record, TopicDescription, type_hash,
                            unused_path)
from hrc_bag.session_index import SessionIndex

# The type of each topic of the graph (by default name).
TOPIC_TYPES = hrc_topics.TYPES


def contract_descriptions() -> dict:
    """Return {topic: TopicDescription} of the /hrc topics as their publishers offer them."""
    descriptions = {}
    for topic, qos in qos_table.OF_TOPIC.items():
        type_name = TOPIC_TYPES[topic]
        profile = offered_profile(reliable=qos.reliable, transient_local=qos.transient_local,
                                  deadline_ns=qos.deadline_ns)
        descriptions[topic] = TopicDescription(type_name, (profile,), type_hash(type_name))
    return descriptions


class SessionWriter:
    """Write one session folder, episode by episode, from plain values (see the module doc)."""

    def __init__(self, output_dir, session_id: str,
                 session_config: typing.Optional[dict] = None, session_config_text: str = '',
                 compression: str = 'zstd', chunk_size: int = DEFAULT_CHUNK_SIZE,
                 descriptions: typing.Optional[dict] = None):
        problem = contract.id_problem(session_id, 'session id')
        if problem:
            raise ValueError(problem)
        self.session_id = session_id
        self.config = dict(session_config or {})
        self._config_text = session_config_text
        self.compression = compression
        self.chunk_size = chunk_size
        self._descriptions = dict(descriptions) if descriptions is not None else None
        self._mode = file_mode(self.config)
        self.folder = pathlib.Path(output_dir) / session_id
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise RecordingError(f'cannot create the session folder {self.folder}: '
                                 f'{error.strerror or error}') from error
        self.last_status = None
        self.index = SessionIndex(self.folder, self._custom_data(), self._mode)
        self.index.write()
        self._file = None
        self._episode = None
        self._pending = []
        self._latched = LatchedMessages()
        self.closed_files = []

    def _custom_data(self) -> dict:
        return session_custom_data(self.session_id, self.config, self.last_status)

    def _description(self, topic: str, type_name: str) -> TopicDescription:
        if self._descriptions is None:
            self._descriptions = contract_descriptions()
        description = self._descriptions.get(topic)
        if description is None or description.type_name != type_name:
            description = TopicDescription(type_name, (offered_profile(),),
                                           type_hash(type_name))
            self._descriptions[topic] = description
        return description

    @property
    def episode(self) -> typing.Optional[int]:
        """Return the episode whose file is open (None between episodes)."""
        return self._episode if self._file is not None else None

    def write(self, topic: str, message, log_time: int, type_name: typing.Optional[str] = None,
              publish_time: typing.Optional[int] = None, sequence: int = 0) -> None:
        """Encode and write one message (see the module doc)."""
        type_name = type_name or TOPIC_TYPES.get(topic)
        if type_name is None:
            raise ValueError(f'{topic}: give the type_name of a topic outside the contract')
        if type_name == contract.SESSION_STATUS_TYPE and not isinstance(message, bytes):
            self.last_status = plain_values(message)
        raw = RawMessage(topic, type_name, serializer.encode(type_name, message),
                         int(log_time), int(log_time if publish_time is None else publish_time),
                         sequence)
        self._latched.seen(raw)
        if self._file is None:
            self._pending.append(raw)
        else:
            self._file.write(raw, self._description(topic, type_name))

    def _open(self, episode: typing.Optional[int]) -> None:
        path = unused_path(self.folder, episode_file_stem(self.session_id, episode))
        record = session_record(self.session_id, episode, self.config, self._config_text,
                                self.last_status, {'writer': 'in-process',
                                                   'compression': self.compression,
                                                   'chunk_size': self.chunk_size})
        self._file = EpisodeFile(path, self.compression, self.chunk_size,
                                 {SESSION_RECORD: record}, mode=self._mode)
        self._episode = episode
        pending, self._pending = self._pending, []
        for raw in pending + self._latched.missing_from(pending):
            self._file.write(raw, self._description(raw.topic, raw.type_name))

    def begin_episode(self, episode: int) -> None:
        """Open the file of ``episode`` (closing the open one first)."""
        if self._file is not None:
            self.end_episode()
        self._open(int(episode))

    def end_episode(self) -> typing.Optional[FileInfo]:
        """Close the open episode file now (footer, indexes, fsync) and list it."""
        if self._file is None:
            return None
        info = self._file.close(self.index.custom_data)
        self.index.add(info)
        self.closed_files.append(info)
        self._file = None
        self._episode = None
        return info

    def close(self) -> None:
        """Close the open episode; write what came after the last one to the end file."""
        self.end_episode()
        if self._pending:
            self._open(None)
            self.end_episode()

    def __enter__(self):
        return self

    def __exit__(self, *exception):
        self.close()
