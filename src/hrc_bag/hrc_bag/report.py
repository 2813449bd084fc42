"""The offline report of recorded sessions: Table II and Fig. 5-7 of the paper (pure, no rclpy).

Input: session folders written by the recorder (one per case and seed). Per session the report
reads the EpisodeSummary messages (``/hrc/episode``), the SessionStatus messages
(``/hrc/session``) and the ``hrc_session`` metadata record (the session configuration), and for
Fig. 6 the AgentStep and HumanAction messages of one evaluation episode. Topics are recognized
by their type, whatever their (remapped) names.

Metrics (per session, then mean and spread over the sessions of a case, i.e. over seeds):

* training: human-involved episodes, total episodes (training episodes, i.e. not evaluation)
  and their ratio (Table II "Training (Episode)");
* performance: the mean over the evaluation episodes of each subtask's error (mean |S_x| m,
  |P_z| rad, |B_y| m, as the agent computes them) and of their sum (Table II "Performance");
* effort: the mean over the evaluation episodes of the variance of each actor's normalized
  action (Table II "Effort").

A session without evaluation episodes has no performance or effort values ("n/a"). Sessions cut
short (a killed recorder) are read up to their last complete chunk.
"""

from dataclasses import dataclass, field
import math
import pathlib
import typing

import yaml

# Topics are found by type, so remapped recordings are analysed too.
from hrc_common.contract import (AGENT_STEP_TYPE, DOF_NAME as DOF_NAMES, DOFS,
                                 EPISODE_SUMMARY_TYPE as EPISODE_TYPE, HUMAN_ACTION_TYPE,
                                 other_dof, SESSION_STATUS_TYPE as SESSION_TYPE)

from hrc_bag import bag_reader
from hrc_bag.qos_yaml import load_yaml
from hrc_bag.format import SESSION_RECORD

STRATEGY_TITLES = {
    'responsibility_guided': 'Learn task first (responsibility-guided)',
    'level_guided': 'Learn human first (level-guided)',
    'learn_together': 'Learn together (baseline)',
}
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

    @property
    def training(self) -> list:
        """Return the summaries of the training episodes."""
        return [summary for summary in self.summaries if not summary.evaluation]

    @property
    def evaluation(self) -> list:
        """Return the summaries of the evaluation episodes."""
        return [summary for summary in self.summaries if summary.evaluation]


def find_sessions(paths) -> list:
    """Return the session folders under ``paths`` (session folders or folders of them)."""
    found = []
    for path in map(pathlib.Path, paths):
        if bag_reader.is_session_folder(path):
            found.append(path)
        elif path.is_dir():
            found += sorted(child for child in path.iterdir()
                            if bag_reader.is_session_folder(child))
        elif path.is_file() and path.suffix == '.mcap':
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


def load_session(path, decoder: typing.Optional[bag_reader.MessageDecoder] = None) -> Session:
    """Read the summaries, statuses and configuration of one session folder (or file)."""
    path = pathlib.Path(path)
    decoder = decoder or bag_reader.MessageDecoder()
    summaries, statuses = {}, []
    config, record = {}, {}
    complete = True
    files_by_episode = {}
    topics = bag_reader.bag_topics(path)
    episode_topics = topics_of_type(topics, EPISODE_TYPE)
    wanted = episode_topics + topics_of_type(topics, SESSION_TYPE)
    for file in bag_reader.session_files(path):
        scan = bag_reader.scan_file(file, topics=wanted)
        complete = complete and scan.complete
        if not record and SESSION_RECORD in scan.metadata:
            record = scan.metadata[SESSION_RECORD]
            config = _config_of(scan.metadata)
        episode = scan.metadata.get(SESSION_RECORD, {}).get('episode', '')
        if episode != '':
            files_by_episode.setdefault(int(episode), []).append(file)
        for message in scan.messages:
            decoded = decoder.decode(message)
            if message.topic in episode_topics:
                # a late recorder gets earlier summaries again (transient local): keep one
                summaries[decoded.episode] = decoded
            else:
                statuses.append(decoded)
    last = statuses[-1] if statuses else None
    case_id = config.get('case', config.get('case_id'))
    if case_id is None:
        case_id = last.case_id if last is not None else (
            next(iter(summaries.values())).case_id if summaries else 0)
    strategy = config.get('strategy') or (last.strategy if last is not None else '')
    roles = config.get('roles') if isinstance(config.get('roles'), dict) else {}
    robot_dof = (roles.get('robot') or config.get('robot_dof')
                 or (DOF_NAMES.get(last.robot_dof, '') if last else ''))
    session_id = (record.get('session_id') or (last.session_id if last else '')
                  or path.name)
    return Session(path=path, session_id=session_id, case_id=int(case_id or 0),
                   strategy=str(strategy), robot_dof=str(robot_dof),
                   seed=_seed_of(config, session_id), config=config,
                   summaries=[summaries[key] for key in sorted(summaries)], statuses=statuses,
                   complete=complete, files_by_episode=files_by_episode)


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
    return {1: 'translation', 0: 'rotation'}[case_id % 2] if case_id else ''


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


def _format(value: tuple, decimals: int, percent: bool = False) -> str:
    mean, spread, count = value
    if count == 0:
        return 'n/a'
    suffix = '%' if percent else ''
    if count == 1 and decimals == 1 and float(mean).is_integer():
        return f'{int(mean)}'  # an episode count of one session
    text = f'{mean:.{decimals}f}{suffix}'
    if count > 1:
        text += f' ± {spread:.{decimals}f}{suffix}'
    return text


def table2_markdown(rows) -> str:
    """Return Table II as Markdown (mean ± sample std over the sessions of each case)."""
    header = ['Strategy', 'Case', 'Robot', 'Sessions'] + [title for _, title, _ in METRICS]
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for row in rows:
        cells = [STRATEGY_TITLES.get(row.strategy, row.strategy or 'unknown'),
                 f'Case {row.case_id}' if row.case_id else 'custom', row.robot_dof or '?',
                 str(len(row.sessions))]
        cells += [_format(row.values[key], decimals, key == 'percentage')
                  for key, _, decimals in METRICS]
        lines.append('| ' + ' | '.join(cells) + ' |')
    lines += ['', 'Training (Table II "Training"): training episodes, evaluation excluded. '
              'Errors (Table II "Performance"): mean over the evaluation episodes of the mean '
              '|S_x|, |P_z|, |B_y| per episode and their sum. Effort: variance of the '
              'normalized action, mean over the evaluation episodes. Several sessions (seeds) '
              'of a case: mean ± sample standard deviation.']
    return '\n'.join(lines) + '\n'


def table2_csv(rows) -> str:
    """Return Table II as CSV with mean, std and count columns per metric."""
    import csv
    import io
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    header = ['strategy', 'case_id', 'robot_dof', 'sessions']
    for key, _, _ in METRICS:
        header += [f'{key}_mean', f'{key}_std', f'{key}_n']
    writer.writerow(header)
    for row in rows:
        cells = [row.strategy, row.case_id, row.robot_dof, len(row.sessions)]
        for key, _, _ in METRICS:
            mean, spread, count = row.values[key]
            cells += [_csv_number(mean), _csv_number(spread), count]
        writer.writerow(cells)
    return buffer.getvalue()


def sessions_csv(sessions) -> str:
    """Return one CSV row per session (the values behind Table II)."""
    import csv
    import io
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    keys = [key for key, _, _ in METRICS] + ['evaluation_episodes']
    writer.writerow(['session_id', 'path', 'case_id', 'strategy', 'robot_dof', 'seed',
                     'complete'] + keys)
    for session in sessions:
        metrics = session_metrics(session)
        writer.writerow([session.session_id, str(session.path), session.case_id,
                         session.strategy, session.robot_dof, session.seed, session.complete]
                        + [_csv_number(metrics[key]) for key in keys])
    return buffer.getvalue()


def _csv_number(value: float) -> str:
    return '' if math.isnan(value) else repr(float(value))


# -- figures ---------------------------------------------------------------------------------

def _pyplot():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as pyplot
    return pyplot


def training_curve(session: Session) -> dict:
    """Return the Fig. 5 data of a session: returns per training episode and the marks."""
    training = session.training
    returns = [summary.episode_return for summary in training]
    human_joins, reward_changes = [], []
    for index, summary in enumerate(training):
        before = training[index - 1] if index else None
        if summary.human_involved and (before is None or not before.human_involved):
            human_joins.append(index + 1)
        if before is not None and summary.training_step != before.training_step:
            reward_changes.append(index + 1)
    return {'returns': returns, 'human_joins': human_joins, 'reward_changes': reward_changes}


def _mean_curve(curves) -> tuple:
    """Return (mean, std) per episode index over curves of different lengths."""
    length = max(len(curve) for curve in curves)
    means, spreads = [], []
    for index in range(length):
        mean, spread, _ = mean_and_spread(curve[index] for curve in curves
                                          if index < len(curve))
        means.append(mean)
        spreads.append(spread)
    return means, spreads


def figure_training_curves(rows, path) -> None:
    """Write Fig. 5: training curves per case, marks where the human joins / reward changes."""
    pyplot = _pyplot()
    from matplotlib.ticker import MaxNLocator
    panels = [('translation', '(a) robot: translation, human: rotation'),
              ('rotation', '(b) robot: rotation, human: translation')]
    figure, axes = pyplot.subplots(1, 2, figsize=(13, 4.8), sharey=True)
    for axis, (dof, title) in zip(axes, panels):
        members = [row for row in rows if row.robot_dof == dof]
        for row in members:
            curves = [training_curve(session) for session in row.sessions]
            curves = [curve for curve in curves if curve['returns']]
            if not curves:
                continue
            means, spreads = _mean_curve([curve['returns'] for curve in curves])
            episodes = list(range(1, len(means) + 1))
            label = f'case {row.case_id}' + (f' ({len(curves)} seeds)' if len(curves) > 1
                                             else '')
            line, = axis.plot(episodes, means, marker='.', label=label)
            if len(curves) > 1:
                axis.fill_between(episodes, [m - s for m, s in zip(means, spreads)],
                                  [m + s for m, s in zip(means, spreads)],
                                  color=line.get_color(), alpha=0.2)
            for curve in curves:
                for episode in curve['human_joins']:
                    axis.annotate('', xy=(episode, means[episode - 1]),
                                  xytext=(episode, means[episode - 1] + _arrow_length(means)),
                                  arrowprops={'arrowstyle': '->', 'color': line.get_color(),
                                              'lw': 1.5})
                for episode in curve['reward_changes']:
                    axis.axvline(episode - 0.5, color=line.get_color(), linestyle='--',
                                 linewidth=0.8)
        axis.set_title(title)
        axis.set_xlabel('training episode')
        axis.xaxis.set_major_locator(MaxNLocator(integer=True))
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='lower right')
        else:
            axis.text(0.5, 0.5, 'no session of these cases', transform=axis.transAxes,
                      ha='center', va='center', color='gray')
    axes[0].set_ylabel('episode return (robot reward)')
    figure.suptitle('Fig. 5: training; arrows: the human joins; dashed: the reward changes '
                    '(new training step)')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def _arrow_length(values) -> float:
    finite = [value for value in values if not math.isnan(value)]
    spread = (max(finite) - min(finite)) if finite else 1.0
    return 0.12 * (spread or 1.0)


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


def figure_actions(rows, path, seconds: float = 4.0, start: float = 0.0) -> None:
    """Write Fig. 6: robot and human actions over ``seconds`` of an evaluation episode."""
    pyplot = _pyplot()
    columns = max(1, min(3, len(rows)))
    lines = max(1, math.ceil(len(rows) / columns))
    figure, axes = pyplot.subplots(lines, columns,
                                   figsize=(max(4.6 * columns, 7.5), 3.2 * lines + 0.6),
                                   squeeze=False, sharey=True)
    # the first session of each case (lowest seed) gives the trace
    traces = [action_trace(sorted(row.sessions, key=lambda member: member.seed)[0], seconds,
                           start) for row in rows]
    # one symmetric scale for all cases, so that their action sizes compare
    largest = max([abs(value) for trace in traces for key in ('robot', 'human')
                   for _, value in trace.get(key, [])] + [0.1])
    for index, axis in enumerate(axes.flat):
        if index >= len(rows):
            axis.set_visible(False)
            continue
        row, trace = rows[index], traces[index]
        human_dof = other_dof(row.robot_dof) if row.robot_dof in DOFS else '?'
        if trace:
            for key, label in (('robot', f'robot ({row.robot_dof or "?"})'),
                               ('human', f'human ({human_dof})')):
                points = trace[key]
                if points:
                    axis.step([time for time, _ in points], [value for _, value in points],
                              where='post', label=label)
            axis.set_title(f'case {row.case_id}, evaluation episode {trace["episode"]}')
        else:
            axis.set_title(f'case {row.case_id}: no evaluation episode')
        axis.set_xlim(start, start + seconds)
        axis.set_ylim(-1.1 * largest, 1.1 * largest)
        axis.set_xlabel('time in episode (s)')
        axis.grid(alpha=0.3)
        if axis.get_lines():
            axis.legend(loc='upper right', fontsize='small')
    axes[0][0].set_ylabel('normalized action')
    figure.suptitle(f'Fig. 6: actions of the robot and the human over {seconds:g} s of '
                    f'evaluation')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


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


def figure_three_factor(rows, path) -> None:
    """Write Fig. 7: the three-factor diagram, one polygon per strategy."""
    pyplot = _pyplot()
    factors = three_factors(rows)
    angles = [math.pi / 2 + 2 * math.pi * index / 3 for index in range(3)]
    figure = pyplot.figure(figsize=(6.4, 6.4))
    axis = figure.add_subplot(projection='polar')
    largest = {key: max((entry[key][0] for entry in factors
                         if not math.isnan(entry[key][0])), default=0.0)
               for key, _ in FACTOR_AXES}
    for entry in factors:
        scores = [factor_score(entry[key][0], largest[key]) for key, _ in FACTOR_AXES]
        if any(math.isnan(score) for score in scores):
            scores = [0.0 if math.isnan(score) else score for score in scores]
        label = STRATEGY_TITLES.get(entry['strategy'], entry['strategy'] or 'unknown')
        values = ', '.join(f'{entry[key][0]:.2f}' for key, _ in FACTOR_AXES)
        line, = axis.plot(angles + angles[:1], scores + scores[:1], marker='o',
                          label=f'{label}: {values}')
        axis.fill(angles + angles[:1], scores + scores[:1], color=line.get_color(), alpha=0.15)
        for angle, (key, _) in zip(angles, FACTOR_AXES):
            mean, spread, count = entry[key]
            if count > 1 and spread > 0:
                low = factor_score(mean + spread, largest[key])
                high = factor_score(max(mean - spread, 0.0), largest[key])
                axis.plot([angle, angle], [low, high], color=line.get_color(), linewidth=2)
    axis.set_xticks(angles)
    axis.set_xticklabels([text for _, text in FACTOR_AXES])
    axis.set_ylim(0.0, 1.0)
    axis.set_yticklabels([])
    axis.legend(loc='upper center', bbox_to_anchor=(0.5, -0.06), fontsize='small',
                title='strategy: human-involved, total episodes, total error')
    axis.set_title('Fig. 7: three-factor diagram (outer is better)')
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    pyplot.close(figure)


def three_factors_csv(rows) -> str:
    """Return the Fig. 7 values as CSV."""
    lines = ['strategy,sessions,' + ','.join(f'{key}_mean,{key}_std' for key, _ in FACTOR_AXES)]
    for entry in three_factors(rows):
        cells = [entry['strategy'], str(entry['sessions'])]
        for key, _ in FACTOR_AXES:
            cells += [_csv_number(entry[key][0]), _csv_number(entry[key][1])]
        lines.append(','.join(cells))
    return '\n'.join(lines) + '\n'


def write_report(paths, out_dir, seconds: float = 4.0, start: float = 0.0, log=print) -> dict:
    """Analyse the sessions under ``paths``; write tables and figures into ``out_dir``.

    Returns {'sessions': [...], 'rows': [...], 'files': {name: path}}. Sessions without any
    EpisodeSummary are skipped with a message.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    decoder = bag_reader.MessageDecoder()
    sessions = []
    for path in find_sessions(paths):
        session = load_session(path, decoder)
        if not session.summaries:
            log(f'{path}: no episode summaries, skipped')
            continue
        if not session.complete:
            log(f'{path}: a file was not closed (recorder killed?): read up to its last chunk')
        sessions.append(session)
    rows = table2(sessions)
    files = {}
    if not rows:
        return {'sessions': sessions, 'rows': rows, 'files': files}
    texts = {'table2.md': table2_markdown(rows), 'table2.csv': table2_csv(rows),
             'sessions.csv': sessions_csv(sessions), 'fig7_three_factor.csv':
             three_factors_csv(rows)}
    for name, text in texts.items():
        (out_dir / name).write_text(text)
        files[name] = out_dir / name
    figures = {'fig5_training.png': lambda target: figure_training_curves(rows, target),
               'fig6_actions.png': lambda target: figure_actions(rows, target, seconds, start),
               'fig7_three_factor.png': lambda target: figure_three_factor(rows, target)}
    for name, draw in figures.items():
        draw(out_dir / name)
        files[name] = out_dir / name
    return {'sessions': sessions, 'rows': rows, 'files': files}
