"""Tables of the report (pure, no rclpy).

Table II (Markdown, CSV), the values per session, the Fig. 7 values, human time by input
source, the by-subject table of a live study.
"""

import csv
import io
import math

from hrc_bag.report.metrics import (FACTOR_AXES, human_time, METRICS, session_metrics,
                                    three_factors)
from hrc_bag.report.study import ERROR_KEYS, source_columns

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


# ---------------------------------------------------------------------------- by subject

def _cell(value: float, decimals: int) -> str:
    return 'n/a' if value is None or math.isnan(value) else f'{value:.{decimals}f}'


def _csv_count(value: float) -> str:
    return '' if math.isnan(value) else str(int(value))


def _exit_cell(code) -> str:
    return '' if code is None else ('done' if code == 0 else f'exit {code}')


def by_subject_markdown(rows, tlx_scales: tuple) -> str:
    """Return the by-subject table (rows of :func:`hrc_bag.report.study.subject_rows`)."""
    header = ['Subject', 'Case', 'Position', 'Practice episodes (human s)',
              'Human-involved / training episodes', 'Evaluation episodes',
              'Human time by input (s)', 'Slider error (m)', 'Pendulum error (rad)',
              'Ball error (m)', 'Total error'] + [f'TLX {scale}' for scale in tlx_scales] + [
              'Raw TLX', 'Condition', 'Session']
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for row in rows:
        practice = 'none'
        if row['practice_session_id']:
            practice = (f"{_cell(row['practice_episodes'], 0)} "
                        f"({_cell(row['practice_human_seconds'], 1)})")
        times = '; '.join(f'{source} {row["human_seconds"][source]:.1f}'
                          for source in source_columns([row]) if source in row['human_seconds'])
        cells = [row['subject_id'], str(row['case']), str(row['position'] or '?'), practice,
                 f"{_cell(row['human_involved_episodes'], 0)} / "
                 f"{_cell(row['total_episodes'], 0)}",
                 _cell(row['evaluation_episodes'], 0), times or 'n/a',
                 _cell(row['slider_error'], 3), _cell(row['pendulum_error'], 3),
                 _cell(row['ball_error'], 3), _cell(row['total_error'], 3)]
        cells += [_cell(row['tlx'].get(scale, math.nan), 0) for scale in tlx_scales]
        cells += [_cell(row['raw_tlx'], 1),
                  _exit_cell(row['exit_code']) if row['kind'] == 'condition'
                  else 'practice only', row['session_id'] or row['practice_session_id']]
        lines.append('| ' + ' | '.join(cells) + ' |')
    lines += ['', 'One row per condition a subject took part in (pseudonymous ids from the '
              "study index; no names or notes). Position: the case's place in the subject's "
              'counterbalanced order. Practice: episodes of the person alone before the '
              'condition (its own bags, <session>-practice), counted apart, with their '
              'engaged human seconds. Training episodes exclude evaluation and practice. '
              'Human time: simulated seconds the human was engaged, by the input that drove '
              "him, over the condition's episodes. Errors: mean over the evaluation "
              'episodes (Table II "Performance"). TLX: the raw NASA-TLX (0-100, performance '
              '0 = perfect) and its unweighted mean; n/a = not stored.']
    return '\n'.join(lines) + '\n'


def by_subject_csv(rows, tlx_scales: tuple) -> str:
    """Return the by-subject table as CSV (empty cells where there is no value)."""
    sources = source_columns(rows)
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    counts = ['practice_episodes', 'human_involved_episodes', 'total_episodes',
              'evaluation_episodes']
    writer.writerow(['subject_id', 'case', 'position', 'kind', 'session_id', 'exit_code',
                     'practice_session_id', 'practice_exit_code'] + counts
                    + ['practice_human_seconds']
                    + [f'human_seconds_{source}' for source in sources] + list(ERROR_KEYS)
                    + [f'tlx_{scale}' for scale in tlx_scales] + ['raw_tlx'])
    for row in rows:
        def code(value):
            return '' if value is None else value
        has_bag = bool(row['human_seconds']) or not math.isnan(row['total_episodes'])
        writer.writerow(
            [row['subject_id'], row['case'], row['position'], row['kind'], row['session_id'],
             code(row['exit_code']), row['practice_session_id'],
             code(row['practice_exit_code'])]
            + [_csv_count(row[key]) for key in counts]
            + [_csv_number(row['practice_human_seconds'])]
            + [repr(float(row['human_seconds'].get(source, 0.0))) if has_bag else ''
               for source in sources]
            + [_csv_number(row[key]) for key in ERROR_KEYS]
            + [_csv_number(row['tlx'].get(scale, math.nan)) for scale in tlx_scales]
            + [_csv_number(row['raw_tlx'])])
    return buffer.getvalue()
