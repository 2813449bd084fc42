"""Session records from recorded bags (through hrc_bag's reader; no rclpy)."""

import math

from hrc_bag.report import load_sessions as load_bag_sessions
from hrc_common.contract import EpisodeKind

from hrc_study.sessions import case_roles, EpisodeRecord, SessionRecord


def _nested(config: dict, *keys, default=None):
    value = config
    for key in keys:
        if not isinstance(value, dict) or key not in value:
            return default
        value = value[key]
    return value


def profile_of(config: dict) -> str:
    """Return the simulated-human profile of a session config ('paper' when not given)."""
    for path in (('human_profile',), ('settings', 'human_profile'),
                 ('parameters', 'human', 'profile'), ('human', 'profile')):
        value = _nested(config, *path)
        if value:
            return str(value)
    return 'paper'


def person_of(config: dict) -> int:
    """Return the simulated person drawn for the session (-1: the profile itself)."""
    for path in (('parameters', 'human', 'person'), ('human', 'person'), ('person',)):
        value = _nested(config, *path)
        if isinstance(value, int):
            return value
    return -1


def limits_of(config: dict) -> dict:
    """Return the command limits the session's sim was given {dof: N or N*m} (may be empty).

    Sims started without them use the sim's defaults (hrc_study.sessions.default_limits).
    """
    limits = {}
    for dof, name in (('translation', 'max_force'), ('rotation', 'max_torque')):
        for path in (('parameters', 'sim', name), ('sim', name)):
            value = _nested(config, *path)
            if isinstance(value, (int, float)) and value > 0:
                limits[dof] = float(value)
                break
    return limits


def episode_seconds_of(config: dict) -> float:
    """Return the session's episode duration (s of simulated time; NaN when not said)."""
    for path in (('parameters', 'sim', 'episode_duration'), ('sim', 'episode_duration')):
        value = _nested(config, *path)
        if isinstance(value, (int, float)) and value > 0:
            return float(value)
    return math.nan


def episode_limit_of(config: dict) -> int:
    """Return the session's max training episodes (0 when the config does not say)."""
    for path in (('parameters', 'agent', 'max_training_episodes'),
                 ('agent', 'max_training_episodes'), ('max_training_episodes',),
                 ('settings', 'training_episodes')):
        value = _nested(config, *path)
        if isinstance(value, (int, float)) and value > 0:
            return int(value)
    return 0


def record_from_bag_session(session) -> SessionRecord:
    """Convert an hrc_bag report Session into a SessionRecord."""
    episodes = [EpisodeRecord(
        episode=int(summary.episode), training_step=int(summary.training_step),
        human_involved=bool(summary.human_involved), evaluation=bool(summary.evaluation),
        converged=bool(summary.converged), episode_return=float(summary.episode_return),
        slider_error=float(summary.slider_error), pendulum_error=float(summary.pendulum_error),
        ball_error=float(summary.ball_error), total_error=float(summary.total_error),
        human_effort=float(summary.human_effort), robot_effort=float(summary.robot_effort),
        final_evaluation=_final_flag(summary), kind=_kind_label(summary))
        for summary in session.summaries]
    strategy, robot_dof = case_roles().get(session.case_id, (session.strategy, session.robot_dof))
    try:
        seed = int(session.seed)
    except ValueError:
        seed = -1
    step_count = max((int(status.training_step_count) for status in session.statuses),
                     default=0)
    return SessionRecord(session_id=session.session_id, case_id=session.case_id,
                         strategy=session.strategy or strategy,
                         robot_dof=session.robot_dof or robot_dof, seed=seed,
                         profile=profile_of(session.config), episodes=episodes,
                         step_count=step_count,
                         episode_limit=episode_limit_of(session.config),
                         path=str(session.path),
                         extra={'bag_session': session, 'person': person_of(session.config),
                                'limits': limits_of(session.config),
                                'episode_seconds': episode_seconds_of(session.config)})


def _kind_label(summary) -> str:
    """Return the summary's kind label, '' when it does not say (bags before the field)."""
    try:
        kind = EpisodeKind(int(getattr(summary, 'kind', 0)))
    except ValueError:
        return ''
    return '' if kind is EpisodeKind.UNKNOWN else kind.label


def _final_flag(summary):
    """Return the summary's own final-evaluation flag if the message has one, else None."""
    for name in ('final_evaluation', 'final'):
        if hasattr(summary, name):
            return bool(getattr(summary, name))
    return None


def session_order(record) -> tuple:
    """Return the key sessions are listed by: profile, case, seed, session id."""
    return (record.profile, record.case_id, record.seed, record.session_id)


def load_sessions(paths, log=print) -> list:
    """Return SessionRecords of every session folder under ``paths`` (sorted by case, seed).

    The sessions are read by ``hrc_bag.report.load_sessions`` (its notices and skipped
    sessions go to ``log``; a path without sessions raises FileNotFoundError, files that are
    not MCAP raise ``hrc_bag.bag_reader.BagError`` with every reason).
    """
    records = [record_from_bag_session(session) for session in load_bag_sessions(paths, log)]
    records.sort(key=session_order)
    return records
