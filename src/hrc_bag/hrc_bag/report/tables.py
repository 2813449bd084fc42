"""Tables of the report (pure, no rclpy): Table II, sessions.csv, the person's time, human time.

Table II gives per case (one simulated-human profile) the mean over its sessions (seeds) with
the 95% BCa interval (:mod:`hrc_bag.report.intervals`); one session: its values.
"""

import csv
import io
import math

import numpy

from hrc_bag.report.intervals import cell, column_interval, INTERVAL_NOTE, RESAMPLES
from hrc_bag.report.metrics import FACTOR_AXES, human_time
from hrc_bag.report.paper import PAPER_TABLE2, paper_person_minutes, TARGET_PERSON_TIME_RATIO
from hrc_bag.report.records import (EFFORT_UNITS, measures, other_dof_of, PHYSICAL_EFFORT_KEYS,
                                    REVERSAL_KEYS, STRATEGY_SHORT)
from hrc_common.smoothness import HUMAN_REVERSALS_PER_S

# (measure, Table II column title, decimals)
COLUMNS = [('human_involved_episodes', 'human-involved episodes', 1),
           ('total_episodes', 'episodes', 1),
           ('percentage', 'human %', 0),
           ('slider_error', 'slider (m)', 3),
           ('pendulum_error', 'pendulum (rad)', 3),
           ('ball_error', 'ball (m)', 3),
           ('total_error', 'total error (m + rad)', 3),
           ('tolerance_error', 'total error (over tolerances)', 2),
           ('human_effort', 'human effort (normalized)', 4),
           ('robot_effort', 'robot effort (normalized)', 4),
           ('human_effort_physical', 'human effort (N^2 or (N*m)^2)', 4),
           ('robot_effort_physical', 'robot effort (N^2 or (N*m)^2)', 4),
           ('human_reversals', 'human reversals (1/s)', 2),
           ('robot_reversals', 'robot reversals (1/s)', 2)]
CHATTER_TITLE = 'robots that chatter'
CHATTER_NOTE = (
    "Reversals: sign changes per second of an actor's normalized command outside a 5% dead "
    'band, over the final evaluation episodes. A robot chatters when it reverses more often '
    f'than {HUMAN_REVERSALS_PER_S:g} times per second, the rate at which people correct an '
    'unstable load (about 2 corrections per second, Loram et al. 2011; hrc_common/'
    'smoothness.py); the 0.2 s control period allows 5.')
TABLE2_NOTE = (
    'Episodes count every episode until training ended, the evaluation episodes that judged '
    'convergence included; human-involved episodes count those in which the human acted (the '
    "person's time). Errors and efforts: mean over the final evaluation episodes of the frozen "
    'deterministic policy (mean |S_x| m, |P_z| rad, |B_y| m per episode, their sum; effort = '
    "variance of the normalized action, 1 = the sim's limit; the physical columns multiply it "
    "by the limit squared: N^2 for the slider's force, (N*m)^2 for the pendulum's torque, from "
    "the session's recorded sim parameters or the sim's defaults). Total error sums metres and "
    "radians (mixed units, as the paper's sum); over tolerances: slider / 0.01 m + pendulum / "
    '0.1 rad + ball / 0.05 m, unit-free (1 = one subtask at its tolerance). ' + INTERVAL_NOTE
    + ' Sessions that hit the episode limit enter the episode counts at the limit: those '
    'columns are restricted means (a lower bound of the unrestricted mean). An evaluation '
    'episode in which a command came late (the sim applied zero) is left out when complete '
    'ones exist (the agent runs it again), and a judging episode with one judged nothing.')
OUTCOME_TITLE = 'converged / at the cap / unfinished'
OUTCOME_NOTE = (
    'Converged / at the cap / unfinished: sessions whose training met the convergence rule in '
    'its last step; that ran to the episode cap without meeting it (their episode counts are '
    'the cap); that did not finish (no final evaluation, or bags not closed: an abort, a '
    'crash). A case whose sessions stopped at the cap did not learn the task in the budget.')
PERSON_TIME_NOTE = (
    "The person's minutes: the human-involved episodes of training (judging episodes "
    "included) at the session's episode duration; breaks, practice and the final evaluation "
    "excluded. The paper's: its human-involved episodes x 40 s.")


def _roles(members) -> tuple:
    return members[0].strategy, members[0].robot_dof


def _units_of(key: str, robot: str) -> str:
    """Return the physical unit of a physical-effort cell of a case whose robot has ``robot``."""
    if robot not in EFFORT_UNITS:
        return ''
    dof = robot if key.startswith('robot') else other_dof_of(robot)
    return ' ' + EFFORT_UNITS[dof]


def session_outcome(session) -> str:
    """Return 'converged', 'cap' or 'unfinished' of one session (from its bags)."""
    values = measures(session)
    bag = session.extra.get('bag_session')
    if (bag is not None and not bag.complete) or not values['evaluation_episodes']:
        return 'unfinished'
    return 'converged' if values['converged'] else 'cap'


def outcome_cell(members) -> str:
    """Return "converged / at the cap / unfinished" counts of a case's sessions."""
    outcomes = [session_outcome(member) for member in members]
    return ' / '.join(str(outcomes.count(name)) for name in ('converged', 'cap', 'unfinished'))


def chatter_cell(members) -> str:
    """Return "k / n" sessions whose robot chatters (n: those with recorded reversals)."""
    values = [measures(member) for member in members]
    known = [value for value in values if math.isfinite(value['robot_reversals'])]
    if not known:
        return 'not recorded'
    return f"{sum(value['robot_chatters'] for value in known)} / {len(known)}"


def table2_intervals(groups: dict, seed: int = 0, resamples: int = RESAMPLES) -> dict:
    """Return {case_id: {measure: Interval}} of ``groups`` ({case_id: [SessionRecord]})."""
    result = {}
    for case_id, members in groups.items():
        values = [measures(member) for member in members]
        result[case_id] = {key: column_interval([value[key] for value in values], key, seed,
                                                resamples) for key, _, _ in COLUMNS}
    return result


def table2_markdown(groups: dict, seed: int = 0, resamples: int = RESAMPLES,
                    intervals: dict = None) -> str:
    """Return Table II: mean and 95% interval over seeds per cell (see column_interval)."""
    intervals = intervals or table2_intervals(groups, seed, resamples)
    header = (['case', 'strategy', 'robot', 'seeds'] + [title for _, title, _ in COLUMNS]
              + [OUTCOME_TITLE, CHATTER_TITLE])
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for case_id, members in groups.items():
        strategy, robot = _roles(members)
        cells = [str(case_id) if case_id else 'custom',
                 STRATEGY_SHORT.get(strategy, strategy or '?'), robot or '?', str(len(members))]
        for key, _, decimals in COLUMNS:
            text = cell(intervals[case_id][key], decimals)
            if key in PHYSICAL_EFFORT_KEYS and text != 'n/a':
                text += _units_of(key, robot)
            cells.append(text)
        cells += [outcome_cell(members), chatter_cell(members)]
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines) + '\n'


def _csv_number(value: float) -> str:
    return '' if value is None or math.isnan(value) else repr(float(value))


def table2_csv(groups: dict, intervals: dict) -> str:
    """Return Table II as CSV: per measure its mean, interval bounds and count."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    header = ['strategy', 'case_id', 'robot_dof', 'sessions']
    for key, _, _ in COLUMNS:
        header += [f'{key}_mean', f'{key}_low', f'{key}_high', f'{key}_n']
    header += ['sessions_converged', 'sessions_at_cap', 'sessions_unfinished']
    writer.writerow(header)
    for case_id, members in groups.items():
        strategy, robot = _roles(members)
        cells = [strategy, case_id, robot, len(members)]
        for key, _, _ in COLUMNS:
            interval = intervals[case_id][key]
            cells += [_csv_number(interval.estimate), _csv_number(interval.low),
                      _csv_number(interval.high), interval.count]
        outcomes = [session_outcome(member) for member in members]
        cells += [outcomes.count(name) for name in ('converged', 'cap', 'unfinished')]
        writer.writerow(cells)
    return buffer.getvalue()


# the measures of sessions.csv, in its column order (later columns appended: earlier ones stay)
SESSION_KEYS = (['human_involved_episodes', 'total_episodes', 'converged',
                 'evaluation_episodes']
                + [key for key, _, _ in COLUMNS[3:]
                   if key not in PHYSICAL_EFFORT_KEYS + REVERSAL_KEYS + ('tolerance_error',)]
                + list(PHYSICAL_EFFORT_KEYS) + ['person_minutes']
                + ['tolerance_error', 'pretraining_episodes', 'episode_floor', 'person_floor',
                   'paper_episodes', 'paper_person_episodes', 'window_stopped',
                   'window_episodes', 'window_person_episodes', 'incomplete_evaluations']
                + list(REVERSAL_KEYS) + ['robot_chatters'])


def sessions_csv(sessions) -> str:
    """Return one CSV row per session: the values behind every table."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(['session_id', 'profile', 'person', 'case_id', 'strategy', 'robot_dof',
                     'seed'] + SESSION_KEYS + ['learning', 'complete'])
    for session in sessions:
        values = measures(session)
        bag = session.extra.get('bag_session')
        writer.writerow([session.session_id, session.profile, session.extra.get('person', ''),
                         session.case_id, session.strategy, session.robot_dof, session.seed]
                        + [values[key] for key in SESSION_KEYS]
                        + [session.learning, '' if bag is None else bag.complete])
    return buffer.getvalue()


def _met(met: bool) -> str:
    return 'yes' if met else '**no**'


def person_time_markdown(rows: dict) -> str:
    """Return the person's time per case: median [IQR] minutes beside the paper's.

    ``rows``: {case_id: [measures of each session]}.
    """
    lines = ["| case | sessions | person's minutes, median [IQR] | paper (min) | ratio | "
             'within 2x |', '|---|---|---|---|---|---|']
    for case_id, values in sorted(rows.items()):
        minutes = numpy.array([value['person_minutes'] for value in values], dtype=float)
        minutes = minutes[numpy.isfinite(minutes)]
        if not len(minutes):
            continue
        low, median, high = numpy.percentile(minutes, [25, 50, 75])
        paper = paper_person_minutes(case_id) if case_id in PAPER_TABLE2 else None
        ratio = median / paper if paper else None
        lines.append(f'| {case_id} | {len(minutes)} | {median:.1f} [{low:.1f}, {high:.1f}] | '
                     + (f'{paper:.1f} | {ratio:.2f}x | '
                        f'{_met(ratio <= TARGET_PERSON_TIME_RATIO)} |' if paper
                        else 'not in the paper | | |'))
    return '\n'.join(lines) + '\n'


def three_factors_csv(factors) -> str:
    """Return the Fig. 7 values (:func:`hrc_bag.report.metrics.three_factors`) as CSV."""
    lines = ['strategy,sessions,' + ','.join(f'{key}_mean,{key}_low,{key}_high'
                                             for key, _ in FACTOR_AXES)]
    for entry in factors:
        cells = [entry['strategy'], str(entry['sessions'])]
        for key, _ in FACTOR_AXES:
            cells += [_csv_number(entry[key].estimate), _csv_number(entry[key].low),
                      _csv_number(entry[key].high)]
        lines.append(','.join(cells))
    return '\n'.join(lines) + '\n'


def human_time_rows(sessions) -> list:
    """Return one row per session and input source: the values behind human_time.md."""
    rows = []
    for session in sessions:
        bag = session.extra.get('bag_session')
        for source, entry in sorted((human_time(bag) if bag else {}).items()):
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
