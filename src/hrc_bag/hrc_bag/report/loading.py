"""Load recorded sessions into per-episode records: the report's first layer (pure, no rclpy).

:func:`load_sessions` (or :func:`load_session` for one) turns session folders written by the
recorder (or by :class:`hrc_bag.session_writer.SessionWriter`) into :class:`Session` objects:
per episode the decoded EpisodeSummary (``summaries``, by episode), the file it was
recorded in (``files_by_episode``) and the input that drove the human (``human_inputs``: the
``hrc_episode`` record of its file), plus the session's SessionStatus messages, its
configuration (the ``hrc_session`` record), case, strategy, robot DOF and seed. Topics are
recognized by their type, whatever their (remapped) names. Metrics, tables and figures
(:mod:`.metrics`, :mod:`.tables`, :mod:`.figures`) and the statistics of ``hrc_study`` build
on these records.
"""

from dataclasses import dataclass, field
import math
import pathlib
import typing

from hrc_common.episode_numbers import episode_number
from hrc_common.contract import (dof_name, episode_kind, EPISODE_SUMMARY_TYPE, EpisodeKind,
                                 HUMAN_ACTION_TYPE, SESSION_STATUS_TYPE)
import yaml

from hrc_bag import bag_reader
from hrc_bag.format import EPISODE_RECORD, HumanInputTally, SESSION_RECORD
from hrc_bag.qos_yaml import load_yaml
from hrc_bag.report.session_config import nested


@dataclass
class Session:
    """What the report uses of one recorded session."""

    path: pathlib.Path
    session_id: str
    case_id: int                    # 0 = unknown / custom
    strategy: str
    robot_dof: str                  # translation | rotation | '' (unknown)
    seed: str
    config: dict
    summaries: list                 # decoded EpisodeSummary, one per episode, by episode
    statuses: list                  # decoded SessionStatus, in order
    complete: bool                  # every file was closed properly
    files_by_episode: dict = field(default_factory=dict)   # episode -> [file paths]
    # episode -> the hrc_episode record of its file (which input drove the human, steps)
    human_inputs: dict = field(default_factory=dict)
    notices: list = field(default_factory=list)             # what the reader had to work around
    # episode -> every file of it, in attempt order, when it was recorded more than once (a
    # dropped attempt and its re-run); files_by_episode, human_inputs and the summary are
    # then all the attempt that finished (its EpisodeSummary), else the last one
    attempts: dict = field(default_factory=dict)

    @property
    def training(self) -> list:
        """Return the summaries of the training episodes (judging episodes included)."""
        return [summary for summary in self.summaries
                if kind_of(summary) in (EpisodeKind.TRAINING, EpisodeKind.JUDGING)]

    @property
    def evaluation(self) -> list:
        """Return the summaries of the evaluation episodes."""
        return [summary for summary in self.summaries
                if kind_of(summary) is EpisodeKind.EVALUATION]

    @property
    def practice(self) -> list:
        """Return the summaries of the practice episodes (in neither list above)."""
        return [summary for summary in self.summaries
                if kind_of(summary) is EpisodeKind.PRACTICE]


def kind_of(summary) -> EpisodeKind:
    """Return the kind of a decoded EpisodeSummary (``EpisodeSummary.kind``).

    Bags recorded before the field existed (no ``kind`` attribute) or with KIND_UNKNOWN: the
    ``evaluation`` flag decides (evaluation, else training), as the report always read them.
    """
    return episode_kind(getattr(summary, 'kind', EpisodeKind.UNKNOWN),
                        evaluation=bool(getattr(summary, 'evaluation', False)))


def find_sessions(paths) -> list:
    """Return the session folders under ``paths`` (session folders or folders of them)."""
    found = []
    for path in map(pathlib.Path, paths):
        if bag_reader.is_session_folder(path):
            found.append(path)
        elif path.is_dir():
            found += sorted(child for child in path.iterdir()
                            if bag_reader.is_session_folder(child))
        elif path.suffix == '.mcap' and path.exists():       # (a FIFO is refused later)
            found.append(path)
        else:
            raise FileNotFoundError(f'{path}: neither a session folder nor a folder of them')
    return found


def topics_of_type(topics: dict, type_name: str) -> list:
    """Return the names of the topics (bag_reader.TopicInfo by name) of ``type_name``."""
    return sorted(name for name, info in topics.items() if info.type_name == type_name)


def _config_of(metadata: dict) -> dict:
    record = metadata.get(SESSION_RECORD, {})
    try:
        config = load_yaml(record.get('session_config', '') or '') or {}
    except yaml.YAMLError:
        config = {}
    if not isinstance(config, dict):
        config = {}
    return config


def _seed_of(config: dict, fallback: str) -> str:
    seeds = config.get('seeds', config.get('seed'))
    if isinstance(seeds, dict):
        seeds = seeds.get('session', next(iter(seeds.values()), None))
    return str(seeds) if seeds is not None else fallback


def _human_inputs_of_file(file, metadata: dict, human_topics: list) -> dict:
    """Return the file's hrc_episode record, or one counted from its HumanAction messages."""
    record = metadata.get(EPISODE_RECORD)
    if record is not None:
        return dict(record)
    tally = HumanInputTally()                 # a file left open, or older than the record
    for message in bag_reader.scan_file(file, topics=human_topics).messages:
        tally.add_cdr(message.data)
    return tally.record()


def _human_inputs_by_episode(path, human_topics: list) -> dict:
    """Return {episode: an hrc_episode record counted from the HumanAction messages}.

    For files another tool wrote (rosbags' Writer, a merge): they carry no hrc records, and
    one file may hold several episodes; each HumanAction names its own episode.
    """
    from hrc_bag import cdr_peek  # lazy: only for bags without hrc records
    tallies = {}
    for message in bag_reader.iter_messages(path, topics=human_topics):
        fields = cdr_peek.human_action(message.data)
        if fields is not None:
            tallies.setdefault(fields[1], HumanInputTally()).add(*fields)
    return {episode: tally.record() for episode, tally in sorted(tallies.items())}


# fields of an EpisodeSummary that are finite and >= 0 (m, rad, their sum, variances)
CHECKED_FIELDS = ('slider_error', 'pendulum_error', 'ball_error', 'total_error',
                  'human_effort', 'robot_effort')
SUM_TOLERANCE = 1e-6        # relative: the agent writes the sum of the three in float64


def summary_problems(summary, three_subtasks: bool = True) -> list:
    """Return why an episode summary contradicts itself, and repair what can be ([]: fine).

    The total error is the sum of the subtasks' errors (hrc_agent_node's EpisodeResult): with
    the installed task tree (``three_subtasks``: slider, pendulum, ball) a total that is not
    their sum is replaced by the sum; with another tree only a total below the three is (its
    other subtasks add to it). An error or effort that is not a finite number >= 0 (a bag
    edited or written by another tool) is set to NaN, so no table shows a number for it.
    """
    problems = []
    for name in CHECKED_FIELDS:
        value = float(getattr(summary, name))
        if not math.isfinite(value) or value < 0:
            problems.append(f'{name} {value!r} is not a finite number >= 0: left out')
            setattr(summary, name, math.nan)
    parts = [float(summary.slider_error), float(summary.pendulum_error),
             float(summary.ball_error)]
    total = float(summary.total_error)
    slack = SUM_TOLERANCE * max(1.0, abs(total))
    if all(map(math.isfinite, parts)) and math.isfinite(total) and (
            total < sum(parts) - slack or (three_subtasks and total > sum(parts) + slack)):
        problems.append(f'total_error {total:g} is not the sum of its errors '
                        f'({sum(parts):g}): the sum is used')
        summary.total_error = sum(parts)
    return [f'episode {episode_number(summary.episode)}: its summary {problem}'
            for problem in problems]


def missing_commands_notice(episode: int, record: dict) -> list:
    """Return the notice of an episode file whose states went without commands ([] if none).

    The sim applies a missing command as zero (a frozen or lost actor, a stalled graph), so
    the episode is not what the learner or the person did; files recorded before the count
    say nothing.
    """
    def count(value) -> int:
        return int(value) if str(value).isdigit() else 0     # another tool's record: none

    counts = {actor: count(record.get(f'{actor}_commands_missing'))
              for actor in ('robot', 'human')}
    if not any(counts.values()):
        return []
    states = record.get('states') or '?'
    return [f'episode {episode_number(episode)}: of its {states} states, '
            f"{counts['robot']} went without the robot's command and {counts['human']} "
            "without the person's (each applied as zero): not a normal episode"]


# the words of every notice of a loss the recorder left (the session runner looks for them)
RECORDER_MISSED = 'the recorder missed'


def recording_gaps(episode_files: dict, summaries: dict, human_inputs: dict) -> list:
    """Return a notice per kind of loss the recorder left: episodes without a file, states.

    A stalled or stopped recorder misses whole episodes (their summary may still come,
    transient local) or the states of part of one; the numbers of such an episode are not in
    the bags. Episodes before the first recorded one are not asked for (a recorder started
    late is not seen). States are compared with the summary's steps (a lower bound: the sim also
    publishes the initial state) when the recording holds states.
    """
    if not episode_files:
        return []
    # from the first episode recorded on: the episodes before it may never have been the
    # graph's (a partners-first pre-training runs in process, unrecorded)
    known = set(episode_files) | set(summaries)
    absent = sorted(set(range(min(episode_files), max(known) + 1)) - set(episode_files))
    notices = []
    if absent:
        named = ', '.join(str(episode_number(episode)) for episode in absent)
        notices.append(f'episodes {named} have no file in the bags ({RECORDER_MISSED} '
                       'them: stalled or stopped)')
    counted = {episode: str((record or {}).get('states', ''))
               for episode, record in human_inputs.items()}
    if not any(states.isdigit() and int(states) for states in counted.values()):
        return notices              # no state recorded at all (not a topic of this recording)
    for episode in sorted(set(episode_files) & set(summaries)):
        states = counted.get(episode, '')
        steps = int(getattr(summaries[episode], 'steps', 0) or 0)
        if states.isdigit() and int(states) < steps:
            notices.append(f'episode {episode_number(episode)}: the bags hold {states} of its '
                           f'{steps}+ states ({RECORDER_MISSED} the others)')
    return notices


def _steps_of(record: dict) -> str:
    """Return "N steps" of a file's hrc_episode record (its last step + 1, if recorded)."""
    last = record.get('last_step', '')
    if str(last).lstrip('-').isdigit():
        return f'{int(last) + 1} steps' + (', finished' if record.get('finished') == 'true'
                                           else ', dropped')
    return f'{record.get("message_count", "?")} messages'


def load_session(path, decoder: typing.Optional[bag_reader.MessageDecoder] = None) -> Session:
    """Read the summaries, statuses, configuration and human inputs of one session.

    ``path``: a session folder (metadata.yaml and/or MCAP files) or one MCAP file. A
    metadata.yaml that cannot be used is replaced by the folder's MCAP files (a notice says
    so); a file that is not MCAP (empty, another format, a FIFO) raises
    :class:`hrc_bag.bag_reader.BagError` with every reason.
    """
    path = pathlib.Path(path)
    bag_reader.check_bag(path)
    decoder = decoder or bag_reader.MessageDecoder()
    notices = []
    if path.is_dir():
        _, problem = bag_reader.bag_metadata_yaml(path)
        if problem:
            notices.append(problem)
    summaries, statuses = {}, []
    config, record = {}, {}
    complete = True
    files_by_episode, human_inputs = {}, {}
    episode_files = {}          # episode -> [(file, its hrc_episode record, its summary)]
    topics = bag_reader.bag_topics(path)
    episode_topics = topics_of_type(topics, EPISODE_SUMMARY_TYPE)
    human_topics = topics_of_type(topics, HUMAN_ACTION_TYPE)
    wanted = episode_topics + topics_of_type(topics, SESSION_STATUS_TYPE)
    for file in bag_reader.session_files(path):
        scan = bag_reader.scan_file(file, topics=wanted)
        complete = complete and scan.complete
        if not record and SESSION_RECORD in scan.metadata:
            record = scan.metadata[SESSION_RECORD]
            config = _config_of(scan.metadata)
        episode = scan.metadata.get(SESSION_RECORD, {}).get('episode', '')
        own_summary = None
        notices += [notice for notice in bag_reader.without_schema(scan.messages)
                    if notice not in notices]
        for message in scan.messages:
            decoded = decoder.decode(message)
            if message.topic in episode_topics:
                # a late recorder gets earlier summaries again (transient local): keep one
                summaries.setdefault(decoded.episode, decoded)
                if episode != '' and decoded.episode == int(episode):
                    own_summary = decoded
            else:
                statuses.append(decoded)
        if episode != '':
            episode_files.setdefault(int(episode), []).append(
                (file, _human_inputs_of_file(file, scan.metadata, human_topics), own_summary))
    attempts = {}
    for episode, group in episode_files.items():
        finished = [item for item in group if item[2] is not None]
        used = finished[-1] if finished else group[-1]
        files_by_episode[episode] = [used[0]]
        human_inputs[episode] = used[1]
        if used[2] is not None:
            summaries[episode] = used[2]   # the errors of the attempt whose time is counted
        if len(group) > 1:
            attempts[episode] = [item[0] for item in group]
            notices.append(
                f'episode {episode_number(episode)} was recorded {len(group)} times ('
                + ', '.join(f'{item[0].name}: {_steps_of(item[1])}' for item in group)
                + f'): its time and errors are from {used[0].name} ('
                + ('the attempt that finished)' if finished else 'none finished: the last)'))
    notices += recording_gaps(episode_files, summaries, human_inputs)
    notices += [notice for episode in sorted(human_inputs)
                for notice in missing_commands_notice(episode, human_inputs[episode])]
    own_tree = bool(nested(config, 'parameters', 'agent', 'task_tree_file'))
    for summary in summaries.values():
        notices += summary_problems(summary, three_subtasks=not own_tree)
    if not episode_files and human_topics:
        human_inputs = _human_inputs_by_episode(path, human_topics)
        notices.append('no file holds an hrc episode record (written by another tool?): the '
                       "person's time is counted from the HumanAction messages")
    if not complete:
        notices.append('a file was not closed (recorder killed?): read up to its last chunk')
    last = statuses[-1] if statuses else None
    case_id = config.get('case', config.get('case_id'))
    if case_id is None:
        case_id = last.case_id if last is not None else (
            next(iter(summaries.values())).case_id if summaries else 0)
    strategy = config.get('strategy') or (last.strategy if last is not None else '')
    roles = config.get('roles') if isinstance(config.get('roles'), dict) else {}
    robot_dof = (roles.get('robot') or config.get('robot_dof')
                 or (dof_name(last.robot_dof, '') if last else ''))
    session_id = (record.get('session_id') or (last.session_id if last else '')
                  or path.name)
    return Session(path=path, session_id=session_id, case_id=int(case_id or 0),
                   strategy=str(strategy), robot_dof=str(robot_dof),
                   seed=_seed_of(config, session_id), config=config,
                   summaries=[summaries[key] for key in sorted(summaries)], statuses=statuses,
                   complete=complete, files_by_episode=files_by_episode,
                   human_inputs=human_inputs, notices=notices, attempts=attempts)


def load_sessions(paths, log=print,
                  decoder: typing.Optional[bag_reader.MessageDecoder] = None) -> list:
    """Return a :class:`Session` per recorded session under ``paths`` (the stable entry point).

    ``paths``: session folders, folders of session folders, or MCAP files. Sessions without
    any EpisodeSummary are skipped; every notice (skipped session, file not closed, unusable
    metadata.yaml) goes to ``log`` prefixed with the session's path. Raises
    FileNotFoundError for a path that holds no session and
    :class:`hrc_bag.bag_reader.BagError` for files that are not MCAP.
    """
    decoder = decoder or bag_reader.MessageDecoder()
    found = find_sessions(paths)
    problems = [problem for path in found for problem in bag_reader.bag_problems(path)]
    if problems:                                    # every reason at once
        raise bag_reader.BagError('\n'.join(problems))
    sessions = []
    for path in found:
        session = load_session(path, decoder)
        for notice in session.notices:
            log(f'{path}: {notice}')
        if not session.summaries:
            log(f'{path}: no episode summaries, skipped')
            continue
        sessions.append(session)
    return sessions
