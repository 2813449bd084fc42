"""The recorder's routing policy: which episode file receives a message, and when it closes.

Pure (no rclpy). The files themselves (MCAP layout, records, metadata.yaml) are the format
layer, :mod:`hrc_bag.format`. Layout of a session (``<output_dir>/<session_id>/``)::

    metadata.yaml                 rosbag2 bag metadata (version 9, storage mcap), rewritten
                                  atomically each time an episode file is closed
    <session_id>_episode0001.mcap everything recorded during episode 1 (index 0), ...
    <session_id>_episode0002.mcap
    <session_id>_episode0002_attempt2.mcap   a second attempt of episode 2 (see below)
    <session_id>_end.mcap         messages after the last episode (only if there are any)

Episode boundaries (the rule; the node turns messages into the events of
:mod:`hrc_bag.boundaries`):

* A file opens at the first ``/hrc/state`` (TaskState) of an episode not recorded yet.
* Each message goes to the file of its episode: the ``episode`` field of TaskState,
  HumanAction, AgentStep, EpisodeSummary; for a command (WrenchStamped) the episode of the
  state whose stamp it carries (the step protocol). Messages that name no episode
  (SessionStatus, other topics) go to the newest open file.
* The EpisodeSummary is the last message of an episode (the final state is not answered; the
  agent publishes the last AgentStep before the summary), so a file closes ``close_grace``
  seconds (default 0: at once) after its EpisodeSummary is handled and it holds the final
  state or the state of the summary's last step, at most ``summary_timeout`` later (a
  recorder that was stalled gets the states retransmitted by their writer after the agent's
  summary: each topic keeps its order, the topics do not), or after the first state of the
  next episode, or after a ``/hrc/session`` with phase
  done/aborted;
  ``summary_timeout`` seconds after its final state (``terminated`` or ``truncated``) if
  nothing else closed it (a sim without an agent); or at shutdown. A message of an episode
  whose file closed already goes to the newest file (with a warning).
* Every attempt of an episode is filed as itself: an episode that starts again (a state at
  step 0 of an episode whose file is closed, or whose file has seen later steps: the agent
  re-runs an episode after a lost joystick and a resume, or a resumed session re-runs the
  episode it was aborted in) closes the earlier attempt's file at once and opens
  ``<session_id>_episode<n>_attempt<k>.mcap``. The ``hrc_episode`` record of such a file (and of
  any file whose EpisodeSummary never came) says which attempt it holds (``attempt``), the
  files of the episode so far (``attempt_files``), its last step and whether its
  EpisodeSummary came (``finished``); metadata.yaml's custom data
  ``hrc.episode_attempts`` lists the files of every episode recorded more than once. The
  attempts are counted from the files in the folder, so a later recorder of a resumed session
  continues the count.
* Messages that arrive while no file is open (between episodes: phase ``updating``, the next
  training step, the human joining; or before the first episode), and messages of an episode
  whose first state has not been handled yet, are kept in memory and written at the start of
  the next file with their original timestamps. What is left at shutdown goes to
  ``<session_id>_end.mcap``.

Messages are handled in the order DDS received them (their log time), after ``reorder_window``
seconds or longer while the recorder lags (:mod:`hrc_bag.reception_order`); the node hands
them over in batches (:meth:`EpisodeRecorder.record_batch`). A file due to close closes before
the next message is handled, so the files do not depend on how many messages are handled
together.

Crash safety: the open chunk is closed at least every ``flush_period`` seconds (and whenever it
exceeds ``chunk_size``), and written to the file, so a SIGKILL loses at most that much plus the
``reorder_window`` and what waits in DDS for the node's next batch (defaults 0.1 + 0.2 + 0.05
s) of the open episode; a finished episode's file is closed (summary, indexes, footer, fsync)
about ``reorder_window`` after its EpisodeSummary arrived, and metadata.yaml lists only closed
files. A later recorder of the same session finishes the files a killed one left open
(``recover``). Write errors (disk full, permissions) raise :class:`RecordingError`, which stops
the recorder with a clear message.
"""

import collections
import datetime
import pathlib
import time
import typing

from hrc_common.contract import FINISHED_PHASES, id_problem
import yaml

from hrc_bag import cdr_peek, msgdefs
from hrc_bag.bag_reader import recording_order
from hrc_bag.boundaries import SessionSeen, StateSeen, SummarySeen
from hrc_bag.episode_file import EpisodeFile, OpenEpisode
from hrc_bag.format import (describe_error, episode_file_stem, file_mode,
                            index_named_file_stem, LatchedMessages, RawMessage,
                            RecordingError, session_custom_data, SESSION_RECORD, session_record,
                            TopicDescription, unused_path)
from hrc_bag.qos_yaml import load_yaml
from hrc_bag.reception_order import ReceptionOrder
from hrc_bag.recorder_params import RecorderParams
from hrc_bag.recovery import recover_file
from hrc_bag.session_index import SessionIndex


# metadata.yaml custom data: {episode: [file, ...]} of the episodes recorded more than once
ATTEMPTS_KEY = 'hrc.episode_attempts'


def attempt_stem(session_id: str, episode: int, attempt: int) -> str:
    """Return the file name (without .mcap) of ``attempt`` (1, 2, ...) of ``episode``."""
    stem = episode_file_stem(session_id, episode)
    return stem if attempt <= 1 else f'{stem}_attempt{attempt}'


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
        self._mode = file_mode(self.session_config)     # 0600 with a subject id or notes
        self._session_config_text = session_config_text
        self._recorder_parameters = dict(recorder_parameters or {})
        self._log = logger
        self._clock = clock
        # wall_clock: ns since the epoch, the clock of the log times
        self._reception = ReceptionOrder(params.reorder_window, wall_clock)
        self.session_id = params.session_id or str(self.session_config.get('session_id', ''))
        self.folder = None
        self.index = None
        self.open_files = {}                # episode -> OpenEpisode
        self.current = None                 # the newest OpenEpisode (gets episode-less messages)
        self._closed_episodes = set()
        self._attempt_files = {}            # episode -> names of its files, attempt order
        self._late = collections.Counter()  # episode -> messages that came after its file closed
        self._stamp_episodes = collections.OrderedDict()   # state stamp (ns) -> episode
        self._last_flush = clock()
        self._pending = collections.deque()
        self.latched = LatchedMessages()    # the newest URDF, repeated in each new file
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
            if id_problem(candidate) is None:
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
        self.index = SessionIndex(self.folder, self._custom_data(), self._mode)
        if self.index.problem:
            self._warn(self.index.problem)
        if self.params.recover:
            self._recover_unfinished()
        try:
            # proves at once that the folder is writable; lists closed files only
            self.index.write()
        except RecordingError as error:
            raise self._fail(str(error), error)
        self._info(f'recording session {self.session_id!r} into {self.folder}')

    def _recover_unfinished(self) -> None:
        for path in sorted(self.folder.glob('*.mcap'), key=recording_order):
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
        return session_custom_data(self.session_id, self.session_config, self.last_status)

    def _session_record(self, episode) -> dict:
        """Return the hrc_session metadata record written at the start of every file."""
        return session_record(self.session_id, episode, self.session_config,
                              self._session_config_text, self.last_status,
                              self._recorder_parameters)

    def _fail(self, text: str, cause=None) -> RecordingError:
        error = RecordingError(text)
        if cause is not None:
            error.__cause__ = cause
        self.failed = error
        self._error(f'recording stopped: {text}')
        return error

    # -- files ------------------------------------------------------------------------------

    def _earlier_attempts(self, episode: int) -> list:
        """Return the names of the files of ``episode`` so far (this recorder's or before)."""
        if episode not in self._attempt_files:
            found = []
            # a folder of a session begun before hrc 1.0 holds its first attempts by index
            for stem in (episode_file_stem(self.session_id, episode),
                         index_named_file_stem(self.session_id, episode)):
                found += [self.folder / f'{stem}.mcap'] + list(self.folder.glob(f'{stem}_*.mcap'))
            self._attempt_files[episode] = [path.name for path in sorted(
                (path for path in found if path.exists()), key=recording_order)]
        return self._attempt_files[episode]

    def _open(self, episode: typing.Optional[int]) -> OpenEpisode:
        if self.folder is None:
            self.session_id = self._resolve_session_id()
            self._open_session()
        attempt = 1
        stem = episode_file_stem(self.session_id, episode)
        if episode is not None:
            attempt = len(self._earlier_attempts(episode)) + 1
            stem = attempt_stem(self.session_id, episode, attempt)
        path = unused_path(self.folder, stem)
        try:
            file = EpisodeFile(path, self.params.compression, self.params.chunk_size,
                               {SESSION_RECORD: self._session_record(episode)},
                               mode=self._mode)
        except RecordingError as error:
            raise self._fail(str(error), error)
        self.current = OpenEpisode(file, episode, attempt=attempt)
        self.open_files[episode] = self.current
        if episode is not None:
            self._attempt_files[episode].append(path.name)
            if attempt > 1:
                listed = load_yaml(self.index.custom_data.get(ATTEMPTS_KEY) or '') or {}
                listed = listed if isinstance(listed, dict) else {}
                listed.update({number: files for number, files in self._attempt_files.items()
                               if len(files) > 1})
                # in metadata.yaml: {6: [<id>_episode0007.mcap, <id>_episode0007_attempt2.mcap]}
                self.index.custom_data[ATTEMPTS_KEY] = yaml.safe_dump(
                    dict(sorted(listed.items())), default_flow_style=True, width=10**6).strip()
        self._last_flush = self._clock()
        self._info(f'episode {episode if episode is not None else "(none)"}: recording into '
                   f'{path.name}' + (f' (attempt {attempt}; earlier: '
                                     f'{", ".join(self._attempt_files[episode][:-1])})'
                                     if attempt > 1 else '')
                   + (f' ({len(self._pending)} messages from before it)'
                      if self._pending else ''))
        flushed = []
        while self._pending:
            flushed.append(self._pending.popleft())
            self._write(self.current, flushed[-1])
        for message in self.latched.missing_from(flushed):  # the URDF in every file
            self._write(self.current, message)
        return self.current

    def _close(self, episode: OpenEpisode, reason: str) -> None:
        self.open_files.pop(episode.episode, None)
        if episode is self.current:
            self.current = None
        if episode.episode is not None:
            self._closed_episodes.add(episode.episode)
        record = None
        if episode.episode is not None and (episode.attempt > 1 or not episode.finished):
            # an attempt of an episode recorded more than once, or one cut short: say which
            # (a plain finished episode's record stays as hrc_bag.session_writer writes it)
            record = {'attempt': episode.attempt, 'last_step': episode.last_step,
                      'finished': 'true' if episode.finished else 'false',
                      'attempt_files': ','.join(self._attempt_files.get(episode.episode, []))}
        try:
            info = episode.file.close(self.index.custom_data, record)
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
            # The graph is asked for the topic's description (offered QoS, type hash) when
            # the file registers its channel, not for every message (a graph query per message
            # was most of the recorder's CPU at the human's rate).
            episode.file.write(message, lambda: self._description(message))
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
    def waiting(self) -> int:
        """Return the messages buffered, not yet written (their episode file is not open)."""
        return len(self._pending)

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
        self.record_batch([(message, event)])

    def record_batch(self, messages: list) -> None:
        """Record ``(message, event)`` pairs taken together, with one release at the end.

        The node drains its subscriptions in batches. The files are those of :meth:`record` of each
        in turn (messages are handled in log-time order either way); only a message older than
        the reorder window when it arrives could be placed differently, and in the batch it
        takes its place in log-time order among the batch's others.

        The executor's lag is counted once per batch (:class:`ReceptionOrder`).
        """
        if self.failed is not None:
            raise self.failed
        self._reception.add(messages)
        self.tick()

    def _release(self, everything: bool = False) -> None:
        """Handle the waiting messages that are due (ReceptionOrder.due), in log-time order."""
        for message, event in self._reception.due(everything):
            self._handle(message, event)
            # a file due to close (at once after its EpisodeSummary, by default) closes before
            # the next message is handled, however many are released together: the files do
            # not depend on how the messages were batched
            self._close_due()

    def _close_due(self) -> None:
        """Close the open files whose close time has come."""
        if not any(episode.close_at is not None for episode in self.open_files.values()):
            return
        now = self._clock()
        for episode in list(self.open_files.values()):
            if episode.close_at is not None and now >= episode.close_at:
                self._close(episode, episode.reason)

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
        self.latched.seen(message)
        if isinstance(event, SessionSeen):
            self.last_status = dict(event.status)
            if event.status.get('phase') in FINISHED_PHASES:
                for episode in self.open_files.values():
                    episode.schedule_close(now + grace, 'the session finished')
        number = self._episode_of(message, event)
        if isinstance(event, StateSeen):
            self._remember_stamp(message, event.episode)
        target = self.open_files.get(number) if number is not None else self.current
        if isinstance(event, StateSeen) and event.step == 0 and (
                number in self._closed_episodes
                or (target is not None and target.last_step > 0)):
            # the episode starts again (a re-run after a resume): a new attempt, a new file
            if target is not None:
                self._close(target, f'episode {number} started again')
            self._closed_episodes.discard(number)
            target = None
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
            if isinstance(event, StateSeen) and target.episode == number:
                target.last_step = max(target.last_step, event.step)
        else:
            self._buffer(message)
        episode = self.open_files.get(number) if number is not None else None
        if episode is not None and isinstance(event, (StateSeen, SummarySeen)):
            self._schedule_end(episode, event, now)

    def _schedule_end(self, episode: OpenEpisode, event, now: float) -> None:
        """Schedule the close an episode's final state or its EpisodeSummary calls for.

        The summary closes the file once the file holds the episode's final state or the
        summary's last step (an aborted episode has no final state); before that (the states
        retransmitted after a stall come after the summary) the file waits, at most
        ``summary_timeout`` s.
        """
        if isinstance(event, SummarySeen):
            episode.finished = True
            episode.summary_steps = event.steps
        elif event.final:
            episode.final_seen = True
            if not episode.finished:
                episode.schedule_close(now + self.params.summary_timeout,
                                       'no EpisodeSummary after the final state')
        if not episode.finished:
            return
        if episode.final_seen or episode.last_step >= episode.summary_steps:
            episode.schedule_close(now + self.params.close_grace, 'EpisodeSummary received')
        elif isinstance(event, SummarySeen):
            episode.schedule_close(now + self.params.summary_timeout,
                                   f'EpisodeSummary received, no state of its last step '
                                   f'{episode.summary_steps}')

    def tick(self) -> None:
        """Handle due messages; close files whose time has come; write the chunk if due."""
        if self.failed is not None:
            raise self.failed
        self._release()
        self._close_due()
        now = self._clock()
        if now - self._last_flush >= self.params.flush_period:
            self._last_flush = now
            for episode in self.open_files.values():
                try:
                    episode.file.flush()        # a no-op when nothing came since the last
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
