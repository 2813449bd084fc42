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

**What the sim applied.** Acting at its own rate (``sim.human_period``, 0.02 s by default) the
person answers the step's state with a ``HumanAction`` (its first command of the period) and
every slice state of the period with a command the sim applies; the next ``TaskState`` carries
every command applied in the period (``human_applied``, N or N*m, in time order). Each step's
``EpisodeTrace.applied`` holds them normalized by the session's full scale (``max_force`` /
``max_torque`` of its sim parameters; the defaults 2 N and 0.5 N*m when a session does not
record them): what the person really did in the period after the state. A step without them
(the episode's last, a session recorded before the human's own rate (0aecc4c), a period
whose human command was missing and so applied as zero) keeps the ``HumanAction`` command alone.
"""

from dataclasses import dataclass, field
import typing

from hrc_bag import bag_reader
from hrc_bag.report.loading import load_sessions, topics_of_type
from hrc_common.contract import (dof_name, HUMAN_ACTION_TYPE, InputSource, SESSION_STATUS_TYPE,
                                 TASK_STATE_TYPE, TRANSLATION)
import numpy

from hrc_joystick_node.human_model import STATE_FIELDS

DRIVING_SOURCES = (int(InputSource.DEVICE), int(InputSource.JOY), int(InputSource.SIMULATED))
# Full scale of a normalized command when a session does not record its sim parameters (the
# sim's defaults, hrc_sim_node.physics.PhysicsParams): N on translation, N*m on rotation.
DEFAULT_FULL_SCALE = {'max_force': 2.0, 'max_torque': 0.5}


@dataclass
class EpisodeTrace:
    """One episode of one person: what they saw and the command they gave at each step."""

    episode: int
    states: numpy.ndarray        # (steps, 6) STATE_FIELDS per state (m, m/s, rad, rad/s, m, m/s)
    commands: numpy.ndarray      # (steps,) the person's normalized command, [-1, 1]
    driving: numpy.ndarray       # (steps,) bool: the person drove at this step (kept for fits)
    subtasks: typing.List[str]   # subtask ids asked of the person (slider, pendulum, ball)
    # per step: the person's normalized commands the sim applied in the period after the state,
    # in time order (one per slice at the human's rate; the command alone when not recorded)
    applied: typing.List[numpy.ndarray] = field(default_factory=list)


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


def full_scales(config: dict) -> typing.Dict[str, float]:
    """Return ``{'max_force': N, 'max_torque': N*m}`` of a session's configuration."""
    parameters = config.get('parameters') if isinstance(config, dict) else None
    sim = parameters.get('sim') if isinstance(parameters, dict) else None
    scales = dict(DEFAULT_FULL_SCALE)
    for name in scales:
        try:
            value = float((sim or {}).get(name))
        except (TypeError, ValueError):
            continue
        if value > 0:
            scales[name] = value
    return scales


def _applied(next_state, action, scales: dict) -> numpy.ndarray:
    """Return the person's normalized commands applied after the state ``action`` answered."""
    values = list(getattr(next_state, 'human_applied', []) or []) if next_state is not None else []
    if not values or bool(getattr(next_state, 'human_command_missing', False)):
        return numpy.array([float(action.command)])
    dof = dof_name(int(action.dof), '')
    scale = scales['max_force'] if dof == TRANSLATION else scales['max_torque']
    return numpy.array([float(value) / scale for value in values])


def read_episode(file, topics: dict, decoder, episode: int,
                 scales: typing.Optional[dict] = None) -> typing.Optional[tuple]:
    """Return (EpisodeTrace, human dof, source details) of one episode file, or None if empty.

    ``scales``: the session's full scales (:func:`full_scales`; default the sim's defaults).
    """
    wanted = topics[TASK_STATE_TYPE] + topics[HUMAN_ACTION_TYPE] + topics[SESSION_STATUS_TYPE]
    scan = bag_reader.scan_file(file, topics=wanted)
    states, actions, statuses = {}, {}, []
    for message in scan.messages:
        decoded = decoder.decode(message)
        if message.topic in topics[TASK_STATE_TYPE]:
            if int(getattr(decoded, 'slice', 0) or 0) == 0:  # slice states: not the step's
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
    scales = scales or DEFAULT_FULL_SCALE
    applied = [_applied(states.get((key[0], key[1] + 1)), actions[key], scales) for key in keys]
    trace = EpisodeTrace(episode, rows, commands, driving, _subtasks_of(statuses, episode),
                         applied)
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
        scales = full_scales(session.config)
        by_dof = {}
        for episode, files in sorted(session.files_by_episode.items()):
            record = session.human_inputs.get(episode, {})
            period = _seconds(record.get('control_period')) or period or 0.2
            for file in files:
                read = read_episode(file, by_type, decoder, episode, scales)
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
