"""What a person saw and did, read from recorded sessions (pure: no rclpy).

:func:`load_demonstrations` reads session folders (the recorder's or the in-process engine's)
through the report's loading layer (``hrc_bag.report.loading.load_sessions``) and, per episode
file, pairs each ``TaskState`` with the ``HumanAction`` that answered it (same episode and
step). Kept: the steps where the person drove (``engaged``, source device, ``/joy`` or the
simulated human: ``SOURCE_DEVICE``, ``SOURCE_JOY``, ``SOURCE_SIMULATED``); dropped: zero
commands held for a missing input (``SOURCE_NONE``) and replays. The subtasks asked of the
person come from the ``SessionStatus`` in force for the episode (the last one in its file that
announces that episode). A session belongs to its subject (``subject_id`` of its configuration)
or, without one, is its own subject: splits are by subject, never by step.
"""

from dataclasses import dataclass, field
import typing

from hrc_bag import bag_reader
from hrc_bag.report.loading import load_sessions, topics_of_type
from hrc_common.contract import (dof_name, HUMAN_ACTION_TYPE, InputSource, SESSION_STATUS_TYPE,
                                 TASK_STATE_TYPE)
import numpy

from hrc_joystick_node.human_model import STATE_FIELDS

DRIVING_SOURCES = (int(InputSource.DEVICE), int(InputSource.JOY), int(InputSource.SIMULATED))


@dataclass
class EpisodeTrace:
    """One episode of one person: what they saw and the command they gave at each step."""

    episode: int
    states: numpy.ndarray        # (steps, 6) STATE_FIELDS per state (m, m/s, rad, rad/s, m, m/s)
    commands: numpy.ndarray      # (steps,) the person's normalized command, [-1, 1]
    driving: numpy.ndarray       # (steps,) bool: the person drove at this step (kept for fits)
    subtasks: typing.List[str]   # subtask ids asked of the person (slider, pendulum, ball)


@dataclass
class Demonstration:
    """The episodes of one recorded session in which a person drove one degree of freedom."""

    session_id: str
    subject: str                 # subject id, or the session id when none was recorded
    dof: str                     # translation | rotation
    control_period: float        # s
    sources: typing.List[str] = field(default_factory=list)   # source details seen
    episodes: typing.List[EpisodeTrace] = field(default_factory=list)

    @property
    def steps(self) -> int:
        """Return the number of driven steps."""
        return int(sum(int(trace.driving.sum()) for trace in self.episodes))


def _seconds(value) -> float:
    """Return ``value`` as seconds (a number or its repr in a metadata record), 0.0 if none."""
    try:
        return round(float(value), 6)      # stamps in ns: a period of 0.19999999999999998 s
    except (TypeError, ValueError):
        return 0.0


def _subtasks_of(statuses, episode: int) -> typing.List[str]:
    chosen = None
    for status in statuses:
        if int(status.episode) == episode:
            chosen = status
    if chosen is None and statuses:
        chosen = statuses[-1]
    return list(chosen.human_subtasks) if chosen is not None else []


def read_episode(file, topics: dict, decoder, episode: int) -> typing.Optional[tuple]:
    """Return (EpisodeTrace, human dof, source details) of one episode file, or None if empty."""
    wanted = topics[TASK_STATE_TYPE] + topics[HUMAN_ACTION_TYPE] + topics[SESSION_STATUS_TYPE]
    scan = bag_reader.scan_file(file, topics=wanted)
    states, actions, statuses = {}, {}, []
    for message in scan.messages:
        decoded = decoder.decode(message)
        if message.topic in topics[TASK_STATE_TYPE]:
            states[(int(decoded.episode), int(decoded.step))] = decoded
        elif message.topic in topics[HUMAN_ACTION_TYPE]:
            actions[(int(decoded.episode), int(decoded.step))] = decoded
        else:
            statuses.append(decoded)
    keys = sorted(key for key in actions if key in states and key[0] == episode)
    if not keys:
        return None
    rows = numpy.array([[float(getattr(states[key], name)) for name in STATE_FIELDS]
                        for key in keys])
    commands = numpy.array([float(actions[key].command) for key in keys])
    driving = numpy.array([bool(actions[key].engaged) and int(actions[key].source)
                           in DRIVING_SOURCES for key in keys])
    dofs = {dof_name(int(actions[key].dof), '') for key, use in zip(keys, driving) if use}
    details = sorted({str(actions[key].source_detail) for key, use in zip(keys, driving) if use})
    trace = EpisodeTrace(episode, rows, commands, driving, _subtasks_of(statuses, episode))
    return trace, dofs, details


def load_demonstrations(paths, log=print) -> typing.List[Demonstration]:
    """Return one Demonstration per session under ``paths`` in which a person drove.

    ``paths``: session folders or folders of them (as ``hrc_report`` takes them). Sessions in
    which nobody drove (no engaged HumanAction from a device, /joy or the simulated human) are
    skipped with a line to ``log``. A session whose person drove both degrees of freedom is
    split into one demonstration per degree of freedom.
    """
    decoder = bag_reader.MessageDecoder()
    found = []
    for session in load_sessions(paths, log, decoder):
        topics = bag_reader.bag_topics(session.path)
        by_type = {name: topics_of_type(topics, name)
                   for name in (TASK_STATE_TYPE, HUMAN_ACTION_TYPE, SESSION_STATUS_TYPE)}
        subject = str(session.config.get('subject_id') or session.session_id)
        period = _seconds(session.config.get('control_period'))
        by_dof = {}
        for episode, files in sorted(session.files_by_episode.items()):
            record = session.human_inputs.get(episode, {})
            period = _seconds(record.get('control_period')) or period or 0.2
            for file in files:
                read = read_episode(file, by_type, decoder, episode)
                if read is None:
                    continue
                trace, dofs, details = read
                if len(dofs) != 1 or not trace.driving.any():
                    continue
                dof = dofs.pop()
                demonstration = by_dof.setdefault(dof, Demonstration(
                    session.session_id, subject, dof, period))
                demonstration.episodes.append(trace)
                demonstration.sources = sorted(set(demonstration.sources) | set(details))
        if not by_dof:
            log(f'{session.path}: no step driven by a person (joystick, /joy or simulated '
                f'human), skipped')
        found += [by_dof[dof] for dof in sorted(by_dof)]
    return found
