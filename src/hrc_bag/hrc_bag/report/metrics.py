"""Metrics of loaded sessions: Table II values, Fig. 5-7 data, human time (pure, no rclpy).

Per session, then mean and sample standard deviation over the sessions of a case (seeds):

* training: human-involved episodes, total episodes (training episodes, i.e. not evaluation)
  and their ratio (Table II "Training (Episode)");
* performance: the mean over the evaluation episodes of each subtask's error (mean |S_x| m,
  |P_z| rad, |B_y| m, as the agent computes them) and of their sum (Table II "Performance");
* effort: the mean over the evaluation episodes of the variance of each actor's normalized
  action (Table II "Effort");
* human time by input source (:func:`human_time`): the simulated seconds in which the human
  was engaged, per source that drove him (device, joy, simulated, replay, none), and the
  episodes each source drove most.

A session without evaluation episodes has no performance or effort values (NaN).
"""

from dataclasses import dataclass
import math
import typing

from hrc_common.contract import AGENT_STEP_TYPE, dof_name, EpisodeKind, HUMAN_ACTION_TYPE
import yaml

from hrc_bag import bag_reader
from hrc_bag.report.loading import kind_of, Session, topics_of_type

STRATEGY_ORDER = ['responsibility_guided', 'level_guided', 'learn_together']

# (key, Table II column title, decimals)
METRICS = [
    ('human_involved_episodes', 'Human-involved episodes', 1),
    ('total_episodes', 'Total episodes', 1),
    ('percentage', 'Percentage', 0),
    ('slider_error', 'Slider error (m)', 3),
    ('pendulum_error', 'Pendulum error (rad)', 3),
    ('ball_error', 'Ball error (m)', 3),
    ('total_error', 'Total error', 3),
    ('human_effort', 'Human effort', 4),
    ('robot_effort', 'Robot effort', 4),
]


def _mean(values) -> float:
    values = list(values)
    return sum(values) / len(values) if values else math.nan


def session_metrics(session: Session) -> dict:
    """Return the Table II values of one session (NaN where there is no data)."""
    training, evaluation = session.training, session.evaluation
    involved = sum(1 for summary in training if summary.human_involved)
    metrics = {
        'human_involved_episodes': float(involved),
        'total_episodes': float(len(training)),
        'percentage': 100.0 * involved / len(training) if training else math.nan,
        'evaluation_episodes': float(len(evaluation)),
    }
    for key in ('slider_error', 'pendulum_error', 'ball_error', 'total_error', 'human_effort',
                'robot_effort'):
        metrics[key] = _mean(getattr(summary, key) for summary in evaluation)
    return metrics


def mean_and_spread(values) -> tuple:
    """Return (mean, sample standard deviation, count) of the finite values."""
    finite = [value for value in values if not math.isnan(value)]
    if not finite:
        return math.nan, math.nan, 0
    mean = sum(finite) / len(finite)
    if len(finite) < 2:
        return mean, 0.0, len(finite)
    variance = sum((value - mean) ** 2 for value in finite) / (len(finite) - 1)
    return mean, math.sqrt(variance), len(finite)


@dataclass
class CaseRow:
    """One row of Table II: a case over its sessions (seeds)."""

    case_id: int
    strategy: str
    robot_dof: str
    sessions: list                  # Session
    values: dict                    # metric -> (mean, std, n)


def _case_robot_dof(case_id: int, sessions) -> str:
    known = [session.robot_dof for session in sessions if session.robot_dof]
    if known:
        return known[0]
    # the paper's cases: odd = robot translation, even = robot rotation
    return dof_name(0 if case_id % 2 else 1) if case_id else ''


def table2(sessions) -> list:
    """Return the Table II rows (CaseRow), one per case, ordered as the paper."""
    by_case = {}
    for session in sessions:
        by_case.setdefault(session.case_id, []).append(session)
    rows = []
    for case_id, members in by_case.items():
        metrics = [session_metrics(session) for session in members]
        values = {key: mean_and_spread(metric[key] for metric in metrics)
                  for key, _, _ in METRICS}
        strategy = next((session.strategy for session in members if session.strategy), '')
        rows.append(CaseRow(case_id, strategy, _case_robot_dof(case_id, members), members,
                            values))
    rows.sort(key=lambda row: (_strategy_rank(row.strategy), row.case_id))
    return rows


def _strategy_rank(strategy: str) -> int:
    return STRATEGY_ORDER.index(strategy) if strategy in STRATEGY_ORDER else len(STRATEGY_ORDER)


def training_curve(session: Session) -> dict:
    """Return the Fig. 5 data of a session: returns per training episode and the marks.

    Judging episodes (deterministic, ``EpisodeSummary.kind``) are left out: their returns are
    not on the training policy's scale. Bags before the field cannot tell them apart.
    """
    training = [summary for summary in session.training
                if kind_of(summary) is EpisodeKind.TRAINING]
    returns = [summary.episode_return for summary in training]
    human_joins, reward_changes = [], []
    for index, summary in enumerate(training):
        before = training[index - 1] if index else None
        if summary.human_involved and (before is None or not before.human_involved):
            human_joins.append(index + 1)
        if before is not None and summary.training_step != before.training_step:
            reward_changes.append(index + 1)
    return {'returns': returns, 'human_joins': human_joins, 'reward_changes': reward_changes}


def mean_curve(curves) -> tuple:
    """Return (mean, std) per episode index over curves of different lengths."""
    length = max(len(curve) for curve in curves)
    means, spreads = [], []
    for index in range(length):
        mean, spread, _ = mean_and_spread(curve[index] for curve in curves
                                          if index < len(curve))
        means.append(mean)
        spreads.append(spread)
    return means, spreads


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


def three_factors(rows) -> list:
    """Return the Fig. 7 data per strategy: mean and spread of the three factors.

    Factors: human-involved training episodes, total training episodes (training time), total
    error (team performance), over every session of the strategy's cases.
    """
    by_strategy = {}
    for row in rows:
        by_strategy.setdefault(row.strategy, []).extend(row.sessions)
    factors = []
    for strategy in sorted(by_strategy, key=_strategy_rank):
        metrics = [session_metrics(session) for session in by_strategy[strategy]]
        factors.append({
            'strategy': strategy,
            'sessions': len(metrics),
            'human_involved_episodes': mean_and_spread(m['human_involved_episodes']
                                                       for m in metrics),
            'total_episodes': mean_and_spread(m['total_episodes'] for m in metrics),
            'total_error': mean_and_spread(m['total_error'] for m in metrics),
        })
    return factors


FACTOR_AXES = [('human_involved_episodes', 'less human-involved training'),
               ('total_episodes', 'less total training'),
               ('total_error', 'higher team performance')]


def factor_score(value: float, largest: float) -> float:
    """Return the radius of a factor on Fig. 7: 1 for 0, 0.2 for the largest (outer = better)."""
    if math.isnan(value):
        return math.nan
    if largest <= 0:
        return 1.0
    return 1.0 - 0.8 * value / largest




def _counts(text) -> dict:
    try:
        counts = yaml.safe_load(text or '') or {}
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
