"""Tables of the report (pure, no rclpy).

Table II (Markdown, CSV), the values per session, the Fig. 7 values, human time by input
source.
"""

import csv
import io
import math

from hrc_bag.report.metrics import (FACTOR_AXES, human_time, METRICS, session_metrics,
                                    three_factors)

STRATEGY_TITLES = {
    'responsibility_guided': 'Learn task first (responsibility-guided)',
    'level_guided': 'Learn human first (level-guided)',
    'learn_together': 'Learn together (baseline)',
}


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


def three_factors_csv(rows) -> str:
    """Return the Fig. 7 values as CSV."""
    lines = ['strategy,sessions,' + ','.join(f'{key}_mean,{key}_std' for key, _ in FACTOR_AXES)]
    for entry in three_factors(rows):
        cells = [entry['strategy'], str(entry['sessions'])]
        for key, _ in FACTOR_AXES:
            cells += [_csv_number(entry[key][0]), _csv_number(entry[key][1])]
        lines.append(','.join(cells))
    return '\n'.join(lines) + '\n'




def human_time_rows(sessions) -> list:
    """Return one row per session and input source: the values behind human_time.md."""
    rows = []
    for session in sessions:
        for source, entry in sorted(human_time(session).items()):
            rows.append({'session_id': session.session_id, 'case_id': session.case_id,
                         'source': source, **entry})
    return rows


def human_time_markdown(sessions) -> str:
    """Return the human time by input source, per session, as Markdown."""
    lines = ['| Session | Case | Input source | Human time (s) | Engaged steps | Steps | '
             'Episodes driven |', '|---|---|---|---|---|---|---|']
    for row in human_time_rows(sessions):
        lines.append(f"| {row['session_id']} | {row['case_id']} | {row['source']} | "
                     f"{row['seconds']:.1f} | {row['engaged_steps']} | {row['steps']} | "
                     f"{row['episodes']} |")
    lines += ['', 'Human time: simulated seconds in which the human was engaged, by the input '
              'that drove him (HumanAction.source: device, joy, simulated, replay, none); '
              'episodes driven: episodes whose engaged steps that source drove most.']
    return '\n'.join(lines) + '\n'


def human_time_csv(sessions) -> str:
    """Return the human time by input source as CSV."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(['session_id', 'case_id', 'source', 'seconds', 'engaged_steps', 'steps',
                     'episodes'])
    for row in human_time_rows(sessions):
        writer.writerow([row['session_id'], row['case_id'], row['source'],
                         repr(float(row['seconds'])), row['engaged_steps'], row['steps'],
                         row['episodes']])
    return buffer.getvalue()
