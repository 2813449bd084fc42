"""The by-subject table of a live study (pure, no rclpy): Markdown and CSV.

Rows: :func:`hrc_bag.report.study.subject_rows` (one per condition a subject took part in).
"""

import csv
import io
import math

from hrc_bag.report.records import ERROR_KEYS
from hrc_bag.report.study import outcome, source_columns


def _csv_number(value: float) -> str:
    return '' if math.isnan(value) else repr(float(value))


def _cell(value: float, decimals: int) -> str:
    return 'n/a' if value is None or math.isnan(value) else f'{value:.{decimals}f}'


def _csv_count(value: float) -> str:
    return '' if math.isnan(value) else str(int(value))


def _attempts_cell(codes) -> str:
    """Return the attempts of a condition: their count and exit codes, e.g. '2 (exit 3, 0)'."""
    if not codes:
        return ''
    return f"{len(codes)} (exit {', '.join(str(code) for code in codes)})"


def by_subject_markdown(rows, tlx_scales: tuple) -> str:
    """Return the by-subject table (rows of :func:`hrc_bag.report.study.subject_rows`)."""
    header = ['Subject', 'Case', 'Position', 'Practice episodes (human s)',
              'Human-involved / training episodes', 'Evaluation episodes',
              'Human time by input (s)', 'Slider error (m)', 'Pendulum error (rad)',
              'Ball error (m)', 'Total error'] + [f'TLX {scale}' for scale in tlx_scales] + [
              'Raw TLX', 'Outcome', 'Attempts', 'Session']
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
                  outcome(row) if row['kind'] == 'condition' else 'practice only',
                  _attempts_cell(row['attempts']), row['session_id'] or row['practice_session_id']]
        lines.append('| ' + ' | '.join(cells) + ' |')
    lines += ['', 'One row per condition a subject took part in (pseudonymous ids from the '
              "study index; no names or notes). Position: the case's place in the subject's "
              'counterbalanced order. Practice: episodes of the person alone before the '
              'condition (its own bags, <session>-practice), counted apart, with their '
              'engaged human seconds. Training episodes exclude evaluation and practice. '
              'Human time: simulated seconds the human was engaged, by the input that drove '
              "him, over the condition's episodes. Errors: mean over the evaluation "
              'episodes (Table II "Performance"). TLX: the raw NASA-TLX (0-100, performance '
              '0 = perfect) and its unweighted mean; n/a = not stored. Outcome: converged (the '
              'convergence rule met), stopped at the cap (ran every episode without '
              'converging), aborted by the operator, or failed; attempts: every run of the '
              'condition (an abort resumed later is two) with its exit code.']
    return '\n'.join(lines) + '\n'


def by_subject_csv(rows, tlx_scales: tuple) -> str:
    """Return the by-subject table as CSV (empty cells where there is no value)."""
    sources = source_columns(rows)
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    counts = ['practice_episodes', 'human_involved_episodes', 'total_episodes',
              'evaluation_episodes']
    writer.writerow(['subject_id', 'case', 'position', 'kind', 'session_id', 'exit_code',
                     'outcome', 'attempts', 'practice_session_id', 'practice_exit_code'] + counts
                    + ['practice_human_seconds']
                    + [f'human_seconds_{source}' for source in sources] + list(ERROR_KEYS)
                    + [f'tlx_{scale}' for scale in tlx_scales] + ['raw_tlx'])
    for row in rows:
        def code(value):
            return '' if value is None else value
        has_bag = bool(row['human_seconds']) or not math.isnan(row['total_episodes'])
        writer.writerow(
            [row['subject_id'], row['case'], row['position'], row['kind'], row['session_id'],
             code(row['exit_code']), outcome(row) if row['kind'] == 'condition' else '',
             ' '.join(str(code) for code in row['attempts']), row['practice_session_id'],
             code(row['practice_exit_code'])]
            + [_csv_count(row[key]) for key in counts]
            + [_csv_number(row['practice_human_seconds'])]
            + [repr(float(row['human_seconds'].get(source, 0.0))) if has_bag else ''
               for source in sources]
            + [_csv_number(row[key]) for key in ERROR_KEYS]
            + [_csv_number(row['tlx'].get(scale, math.nan)) for scale in tlx_scales]
            + [_csv_number(row['raw_tlx'])])
    return buffer.getvalue()
