"""Groupings and derived data of session records: cases, Fig. 6-7 data, human time (no rclpy).

* :func:`by_case` / :func:`primary_profile`: the sessions of a Table II row (a case of one
  simulated-human profile) and the profile the tables and figures are for;
* :func:`three_factors`: Fig. 7 per strategy: human-involved episodes, total episodes, total
  error, each the mean over the strategy's sessions with its BCa interval;
* :func:`action_trace` / :func:`final_trace`: Fig. 6's robot and human actions of an evaluation
  episode, read from the session's bags;
* :func:`human_time`: the simulated seconds in which the human was engaged, per input source
  that drove him (device, joy, simulated, replay, none), and the episodes each source drove.
"""

import dataclasses
import math
import typing

from hrc_common import bounded_yaml
from hrc_common.contract import AGENT_STEP_TYPE, HUMAN_ACTION_TYPE
import yaml

from hrc_bag import bag_reader
from hrc_bag.report.intervals import bca_interval
from hrc_bag.report.loading import Session, topics_of_type
from hrc_bag.report.records import final_block_start, measures, STRATEGY_ORDER

# (measure, Fig. 7's axis: outer is better)
FACTOR_AXES = [('human_involved_episodes', 'less human-involved training'),
               ('total_episodes', 'less total training'),
               ('total_error', 'higher team performance')]
FIGURE_RESAMPLES = 2000             # bootstrap resamples of a Fig. 7 whisker


def primary_profile(sessions) -> str:
    """Return the profile the report's tables and figures are for: 'paper' if present."""
    profiles = sorted({session.profile for session in sessions},
                      key=lambda name: (name != 'paper', name))
    return profiles[0] if profiles else 'paper'


def by_case(sessions, profile: str) -> dict:
    """Return {case_id: [SessionRecord]} of one profile, by case."""
    groups = {}
    for session in sessions:
        if session.profile == profile:
            groups.setdefault(session.case_id, []).append(session)
    return dict(sorted(groups.items()))


def case_measures(sessions, profile: str) -> dict:
    """Return {case_id: [measures of each session]} of one profile."""
    return {case_id: [measures(member) for member in members]
            for case_id, members in by_case(sessions, profile).items()}


def strategy_rank(strategy: str) -> int:
    """Return the paper's order of a strategy (unknown ones last)."""
    return STRATEGY_ORDER.index(strategy) if strategy in STRATEGY_ORDER else len(STRATEGY_ORDER)


def three_factors(sessions, seed: int = 0, resamples: int = FIGURE_RESAMPLES) -> list:
    """Return Fig. 7's data per strategy: {'strategy', 'sessions', factor: Interval}.

    Each factor (:data:`FACTOR_AXES`) is the mean over every session of the strategy's cases
    (both role assignments) with its 95% BCa interval (:mod:`hrc_bag.report.intervals`).
    """
    groups = {}
    for session in sessions:
        groups.setdefault(session.strategy, []).append(measures(session))
    factors = []
    for strategy in sorted(groups, key=strategy_rank):
        values = groups[strategy]
        entry = {'strategy': strategy, 'sessions': len(values)}
        for key, _ in FACTOR_AXES:
            entry[key] = bca_interval([value[key] for value in values], floor=0.0, seed=seed,
                                      resamples=resamples)
        factors.append(entry)
    return factors


def factor_score(value: float, largest: float) -> float:
    """Return the radius of a factor on Fig. 7: 1 for 0, 0.2 for the largest (outer = better)."""
    if math.isnan(value):
        return math.nan
    if largest <= 0:
        return 1.0
    return 1.0 - 0.8 * value / largest


def median_session(members):
    """Return the session whose total error is the (lower) median of its case."""
    ranked = sorted((value, session.seed, session.session_id, session) for session, value in
                    ((session, measures(session)['total_error']) for session in members)
                    if not math.isnan(value))
    return ranked[(len(ranked) - 1) // 2][3] if ranked else None


def final_trace(session, seconds: float = 4.0, start: float = 0.0) -> dict:
    """Return the robot and human actions of the first final-evaluation episode (Fig. 6)."""
    bag_session = session.extra.get('bag_session')
    if bag_session is None:
        return {}
    first = final_block_start(session)
    final_episodes = {episode.episode for episode in session.episodes[first:]}
    summaries = [summary for summary in bag_session.summaries
                 if summary.episode in final_episodes]
    return action_trace(dataclasses.replace(bag_session, summaries=summaries), seconds, start)


def action_trace(session: Session, seconds: float = 4.0, start: float = 0.0,
                 decoder: typing.Optional[bag_reader.MessageDecoder] = None) -> dict:
    """Return the Fig. 6 data: robot and human actions of the first evaluation episode.

    Times are seconds of simulation time from the episode's first state (the header stamps);
    the window is [start, start + seconds).
    """
    evaluation = session.evaluation
    if not evaluation:
        return {}
    episode = evaluation[0].episode
    decoder = decoder or bag_reader.MessageDecoder()
    files = session.files_by_episode.get(episode) or bag_reader.session_files(session.path)
    robot, human = {}, {}
    topics = bag_reader.bag_topics(session.path)
    agent_topics = topics_of_type(topics, AGENT_STEP_TYPE)
    human_topics = topics_of_type(topics, HUMAN_ACTION_TYPE)
    for file in files:
        scan = bag_reader.scan_file(file, topics=agent_topics + human_topics)
        for message in scan.messages:
            decoded = decoder.decode(message)
            if decoded.episode != episode:
                continue
            stamp = decoded.header.stamp.sec + decoded.header.stamp.nanosec * 1e-9
            if message.topic in agent_topics:
                robot[decoded.step] = (stamp, decoded.action)
            else:
                human[decoded.step] = (stamp, decoded.command)
    if not robot and not human:
        return {}
    origin = min(stamp for stamp, _ in list(robot.values()) + list(human.values()))

    def window(samples):
        points = sorted((stamp - origin, value) for stamp, value in samples.values())
        # (1 us of slack: stamps are sums of control periods in floating point)
        return [(time, value) for time, value in points
                if start - 1e-6 <= time < start + seconds - 1e-6]

    return {'episode': episode, 'robot': window(robot), 'human': window(human)}


def _counts(text) -> dict:
    try:
        counts = bounded_yaml.load(text or '', 'the episode counts') or {}
    except yaml.YAMLError:
        return {}
    return {str(name): int(count) for name, count in counts.items()} if isinstance(
        counts, dict) else {}


def human_time(session: Session) -> dict:
    """Return {source: {'seconds', 'engaged_steps', 'steps', 'episodes'}} of one session.

    ``seconds``: simulated time in which that source drove the engaged human (engaged steps
    times the episode's control period); ``episodes``: episodes whose human_source it was
    (the source of most engaged steps). Training and evaluation episodes alike.
    """
    result = {}
    for record in session.human_inputs.values():
        period = record.get('control_period') or ''
        period = float(period) if period else math.nan
        engaged = _counts(record.get('human_engaged_steps'))
        for source, steps in _counts(record.get('human_steps')).items():
            entry = result.setdefault(source, {'seconds': 0.0, 'engaged_steps': 0,
                                               'steps': 0, 'episodes': 0})
            entry['steps'] += steps
            entry['engaged_steps'] += engaged.get(source, 0)
            if engaged.get(source, 0) and not math.isnan(period):
                entry['seconds'] += engaged[source] * period
        majority = record.get('human_source') or ''
        if majority:
            result.setdefault(majority, {'seconds': 0.0, 'engaged_steps': 0, 'steps': 0,
                                         'episodes': 0})['episodes'] += 1
    return result
