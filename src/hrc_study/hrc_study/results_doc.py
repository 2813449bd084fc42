"""docs/results.md from session records: tables, findings, targets, chooser, figures.

Every number in the document is computed here from the records passed in (and the experiment's
own ``experiment.json`` when present: command, engine, wall time), nothing is typed in except the
paper's Table II (a fact quoted from the paper, labelled as such).
"""

import collections
import csv
import io
import json
import math
import pathlib

import numpy

from hrc_common.contract import paper_case_ids
from hrc_study import figures
from hrc_study.chooser import choice_markdown, choose, PRESETS
from hrc_study.findings import evaluate_findings, significance_note
from hrc_study.sessions import (case_roles, EFFORT_UNITS, measures, other_dof_of,
                                PHYSICAL_EFFORT_KEYS, STRATEGY_SHORT)
from hrc_study.statistics import bca_interval, kaplan_meier, mean_interval

# The paper's Table II (Tao et al.): human-involved, total episodes, total error, human effort.
PAPER_TABLE2 = {1: (18, 25, 1.61, 0.0075), 2: (6, 31, 0.82, 0.0020), 3: (19, 19, 2.04, 0.0078),
                4: (14, 14, 1.14, 0.0021), 5: (24, 24, 6.26, 0.0096), 6: (16, 16, 1.24, 0.0023)}
COLUMNS = [('human_involved_episodes', 'human-involved episodes', 1),
           ('total_episodes', 'episodes', 1),
           ('percentage', 'human %', 0),
           ('slider_error', 'slider (m)', 3),
           ('pendulum_error', 'pendulum (rad)', 3),
           ('ball_error', 'ball (m)', 3),
           ('total_error', 'total error (m + rad)', 3),
           ('human_effort', 'human effort (normalized)', 4),
           ('robot_effort', 'robot effort (normalized)', 4),
           ('human_effort_physical', 'human effort (N^2 or (N*m)^2)', 4),
           ('robot_effort_physical', 'robot effort (N^2 or (N*m)^2)', 4)]
# Physical range of every column (floor, ceiling): an interval never leaves it.
RANGES = {'percentage': (0.0, 100.0)}
DEFAULT_RANGE = (0.0, math.inf)     # counts, errors (absolute values) and variances are >= 0
INTERVALS = ('bca', 'student-t')    # 'student-t': the tables before issue 23, exactly
UNITS_CAVEAT = ("units: our effort is the variance of the normalized command (1 = the sim's "
                'limit; physical units in Table II), our total error sums metres and radians; '
                'the paper gives neither unit, so only the order of the cases compares')
TARGET_HUMAN_EPISODES = 20          # issue #13: case 2 median human-involved episodes
TARGET_CONVERGED = 8                # of 10 seeds, within the episode limit
TARGET_EFFORT_RATIO = 3.0           # human effort within 3x of the paper's
TARGET_PERSON_TIME_RATIO = 2.0      # issue #23: the person's time within 2x of the paper's
PAPER_EPISODE_SECONDS = 40.0        # the paper's episodes (and ours by default): 40 s


def cell(interval, decimals: int) -> str:
    """Return 'mean [low, high]' (or the mean alone, or n/a)."""
    if interval.count == 0 or math.isnan(interval.estimate):
        return 'n/a'
    if interval.count < 2:
        return f'{interval.estimate:.{decimals}f}'
    return (f'{interval.estimate:.{decimals}f} [{interval.low:.{decimals}f}, '
            f'{interval.high:.{decimals}f}]')


def case_measures(sessions, profile: str) -> dict:
    """Return {case_id: [measures of each session]} of one profile."""
    return {case_id: [measures(member) for member in members]
            for case_id, members in figures.by_case(sessions, profile).items()}


def column_interval(values, key: str, intervals: str = 'bca', seed: int = 0,
                    resamples: int = 9999):
    """Return the mean of one Table II column with its 95% interval.

    'bca': BCa bootstrap (seeded), kept within the column's physical range; 'student-t': the
    Student-t interval of the tables before issue 23 (may leave the range).
    """
    if intervals == 'student-t':
        return mean_interval(values)
    floor, ceiling = RANGES.get(key, DEFAULT_RANGE)
    return bca_interval(values, floor=floor, ceiling=ceiling, seed=seed, resamples=resamples)


def _units_of(key: str, case_id: int) -> str:
    """Return the physical unit of a physical-effort cell of ``case_id``."""
    robot = case_roles().get(case_id, ('', ''))[1]
    if not robot:
        return ''
    dof = robot if key.startswith('robot') else other_dof_of(robot)
    return ' ' + EFFORT_UNITS[dof]


INTERVAL_NOTES = {
    'bca': ('Intervals: 95% BCa bootstrap over the seeds of a case (scipy.stats.bootstrap, '
            "seeded), kept within each quantity's physical range (>= 0; percentages <= 100)."),
    'student-t': 'Intervals: Student t over the seeds of a case.'}


def table2_markdown(rows: dict, intervals: str = 'bca', seed: int = 0,
                    resamples: int = 9999) -> str:
    """Return Table II: mean and 95% interval over seeds per cell (see column_interval)."""
    header = ['case', 'strategy', 'robot', 'seeds'] + [title for _, title, _ in COLUMNS]
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    for case_id, values in rows.items():
        strategy, robot = case_roles().get(case_id, ('?', '?'))
        cells = [str(case_id), STRATEGY_SHORT.get(strategy, strategy), robot, str(len(values))]
        for key, _, decimals in COLUMNS:
            text = cell(column_interval([value[key] for value in values], key, intervals, seed,
                                        resamples), decimals)
            if key in PHYSICAL_EFFORT_KEYS and text != 'n/a':
                text += _units_of(key, case_id)
            cells.append(text)
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines) + '\n'


def convergence_markdown(rows: dict) -> str:
    """Return episodes to convergence per case: converged count, KM median, restricted mean.

    Also the human-involved episodes to convergence (finding (b)'s measure), censored likewise.
    """
    lines = ['| case | converged | Kaplan-Meier median [95% CI] | restricted mean | '
             'human-involved episodes to convergence, KM median [95% CI] | paper (episodes) |',
             '|---|---|---|---|---|---|']
    for case_id, values in rows.items():
        times = [value['total_episodes'] for value in values]
        events = [value['converged'] for value in values]
        summary = kaplan_meier(times, events)
        human = kaplan_meier([value['human_involved_episodes'] for value in values], events)
        paper = PAPER_TABLE2.get(case_id)
        paper_text = (f'{paper[1]}' + (' (failed)' if case_id == 5 else '')) if paper else ''
        lines.append(f'| {case_id} | {sum(events)}/{len(events)} | {summary.describe()} | '
                     f'{numpy.mean(times):.1f} | {human.describe()} | {paper_text} |')
    lines += ['', 'Paper column: its episodes per case (one person); ours count the judging '
              'episodes too, so the definitions differ as well as the people.']
    return '\n'.join(lines) + '\n'


def paper_markdown(rows: dict) -> str:
    """Return our means beside the paper's Table II values and the effort ratio."""
    lines = ['| case | human-involved (ours / paper) | episodes (ours / paper) | total error '
             '(ours / paper) | human effort (ours / paper) | effort ratio | units caveat |',
             '|---|---|---|---|---|---|---|']
    for case_id, values in rows.items():
        paper = PAPER_TABLE2.get(case_id)
        if paper is None:
            continue
        ours = {key: numpy.nanmean([value[key] for value in values])
                for key in ('human_involved_episodes', 'total_episodes', 'total_error',
                            'human_effort')}
        lines.append(f'| {case_id} | {ours["human_involved_episodes"]:.1f} / {paper[0]} | '
                     f'{ours["total_episodes"]:.1f} / {paper[1]} | '
                     f'{ours["total_error"]:.3f} / {paper[2]} | '
                     f'{ours["human_effort"]:.4f} / {paper[3]} | '
                     f'{ours["human_effort"] / paper[3]:.2f}x | {UNITS_CAVEAT} |')
    return '\n'.join(lines) + '\n'


def paper_person_minutes(case_id: int) -> float:
    """Return the paper's person time in a case (its human-involved episodes x 40 s), min."""
    return PAPER_TABLE2[case_id][0] * PAPER_EPISODE_SECONDS / 60.0


def person_time_markdown(rows: dict) -> str:
    """Return the table of the person's time per case: median [IQR] minutes beside the paper."""
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


def targets(rows: dict, experiment: dict) -> list:
    """Return [(target, measured, met)] of issue #13 (and #12's wall time; met None: n/a)."""
    result = []
    case2 = rows.get(2, [])
    if case2:
        median = float(numpy.median([value['human_involved_episodes'] for value in case2]))
        result.append((f'case 2: median human-involved episodes <= {TARGET_HUMAN_EPISODES} '
                       f'(paper: 6)', f'{median:g} over {len(case2)} seeds',
                       median <= TARGET_HUMAN_EPISODES))
    converged = {case_id: sum(value['converged'] for value in values)
                 for case_id, values in rows.items()}
    counts = {case_id: len(values) for case_id, values in rows.items()}

    def convergence_row(title, cases):
        return (title, ', '.join(f'case {case_id}: {converged[case_id]}/{counts[case_id]}'
                                 for case_id in cases),
                all(converged[case_id] >= TARGET_CONVERGED * counts[case_id] / 10
                    for case_id in cases))
    if rows:
        result.append(convergence_row(f'every case converges in >= {TARGET_CONVERGED}/10 seeds',
                                      list(rows)))
    ratios = {}
    for case_id, values in rows.items():
        if case_id in PAPER_TABLE2:
            ratios[case_id] = numpy.nanmean([value['human_effort'] for value in values]) \
                / PAPER_TABLE2[case_id][3]
    if ratios:
        result.append((f'human effort within {TARGET_EFFORT_RATIO:g}x of the paper per case',
                       ', '.join(f'case {case_id}: {ratio:.2f}x'
                                 for case_id, ratio in ratios.items()) + f' ({UNITS_CAVEAT})',
                       all(1 / TARGET_EFFORT_RATIO <= ratio <= TARGET_EFFORT_RATIO
                           for ratio in ratios.values())))
    # issue #23: the paper's converging cases converge; the person's time a lab would budget
    converging = [case_id for case_id in (1, 2, 3, 4, 6) if case_id in rows]
    if converging:
        result.append(convergence_row(
            f'cases 1, 2, 3, 4, 6 converge in >= {TARGET_CONVERGED}/10 seeds each', converging))
    budget = {}
    for case_id in (2, 4, 6):
        minutes = [value['person_minutes'] for value in rows.get(case_id, [])
                   if math.isfinite(value['person_minutes'])]
        if minutes:
            budget[case_id] = float(numpy.median(minutes)) / paper_person_minutes(case_id)
    if budget:
        result.append((f"the person's time within {TARGET_PERSON_TIME_RATIO:g}x of the paper's "
                       '(median minutes; cases 2, 4, 6: 4.0, 9.3, 10.7 min in the paper)',
                       ', '.join(f'case {case_id}: {ratio:.2f}x'
                                 for case_id, ratio in budget.items()),
                       all(ratio <= TARGET_PERSON_TIME_RATIO for ratio in budget.values())))
    if experiment.get('wall_seconds'):
        result.append(wall_target(experiment))
    return result


def completed(experiment: dict) -> list:
    """Return the outcomes of the sessions that ran to the end (exit code 0)."""
    return [outcome for outcome in experiment.get('outcomes', [])
            if outcome.get('exit_code') == 0]


def wall_target(experiment: dict) -> tuple:
    """Return #12's row: the wall time of six cases x 10 seeds of one profile, if they ran.

    That is when the last of those 60 sessions finished (``finished_after``); other sessions of
    the sweep (a control profile, the cases beyond the paper's) may have run beside them, and
    the row says how many.
    """
    paper_cases = set(paper_case_ids())
    by_profile = {}
    for outcome in completed(experiment):
        if outcome.get('case') in paper_cases:
            by_profile.setdefault(outcome.get('profile', ''), []).append(outcome)
    target = 'six cases x 10 seeds, in-process engine, < 10 min wall (#12)'
    full = {profile: members for profile, members in by_profile.items()
            if len({(m['case'], m['seed']) for m in members}) >= 60}
    engine = experiment.get('engine', '?')
    cpu = [outcome['cpu_seconds'] for outcome in completed(experiment)
           if 'cpu_seconds' in outcome]
    cores = experiment.get('host_cpus') or 1
    cpu_text = (f'; the finished sessions used {sum(cpu):.0f} CPU s, {sum(cpu) / len(cpu):.0f} '
                f'per session: 60 sessions need {60 * sum(cpu) / len(cpu) / cores / 60:.1f} '
                f'min on {cores} free cores' if cpu else '')
    if len(experiment.get('runs') or []) > 1:
        return (target, f'not measured: the sessions came from {len(experiment["runs"])} runs '
                '(resumed), so no one wall time covers them', None)
    if not full:
        done = len(completed(experiment))
        return (target, f'not measured: no profile has 60 finished sessions ({done} of '
                f'{experiment.get("sessions", "?")} planned finished in '
                f'{experiment["wall_seconds"] / 60:.1f} min wall, engine {engine}, '
                f'{experiment.get("executor", "?")}){cpu_text}', None)
    profile, members = next(iter(full.items()))
    wall = max(member.get('finished_after', math.nan) for member in members)
    beside = len(completed(experiment)) - len(members)
    return (target, f'{wall / 60:.1f} min wall for the {len(members)} sessions of profile '
            f'{profile or "default"} (engine {engine}, {experiment.get("executor", "?")}'
            + (f'; {beside} other sessions of the sweep ran beside them' if beside else '')
            + ')' + cpu_text,
            wall < 600 and engine == 'inprocess')


def _met(met) -> str:
    return 'n/a (not a 6 x 10 run)' if met is None else ('yes' if met else '**no**')


def findings_markdown(findings) -> str:
    """Return the findings table."""
    lines = ['| | claim | comparison | test | effect | p | Holm p | verdict | reason |',
             '|---|---|---|---|---|---|---|---|---|']
    for finding in findings:
        lines.append(f'| ({finding.key}) | {finding.claim} | {finding.comparison} | '
                     f'{finding.test} | {finding.effect} | {_p(finding.p_value)} | '
                     f'{_p(finding.p_holm)} | **{finding.verdict}** | {finding.reason} |')
    return '\n'.join(lines) + '\n'


def _p(value: float) -> str:
    return 'n/a' if math.isnan(value) else f'{value:.3g}'


def sessions_csv(sessions) -> str:
    """Return one CSV row per session: the values behind every table."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    keys = ['human_involved_episodes', 'total_episodes', 'converged',
            'evaluation_episodes'] + [key for key, _, _ in COLUMNS[3:]
                                      if key not in PHYSICAL_EFFORT_KEYS]
    keys += list(PHYSICAL_EFFORT_KEYS) + ['person_minutes']   # appended: earlier columns stay
    writer.writerow(['session_id', 'profile', 'person', 'case_id', 'strategy', 'robot_dof',
                     'seed'] + keys)
    for session in sessions:
        values = measures(session)
        writer.writerow([session.session_id, session.profile, session.extra.get('person', ''),
                         session.case_id, session.strategy, session.robot_dof, session.seed]
                        + [values[key] for key in keys])
    return buffer.getvalue()


def read_experiment(paths) -> dict:
    """Return the experiment.json written by the experiment runner next to the sessions."""
    for path in map(pathlib.Path, paths):
        candidate = path / 'experiment.json'
        if candidate.is_file():
            try:
                return json.loads(candidate.read_text())
            except (OSError, ValueError):
                return {}
    return {}


def write_results(sessions, out_dir, command: str, experiment: dict = None,
                  priorities: dict = None, seed: int = 0, note: str = '',
                  resamples: int = 2000, intervals: str = 'bca') -> dict:
    """Write ``out_dir/results.md`` and ``out_dir/results/*``; return {name: path} and more."""
    experiment = experiment or {}
    out_dir = pathlib.Path(out_dir)
    assets = out_dir / 'results'
    assets.mkdir(parents=True, exist_ok=True)
    profiles = sorted({session.profile for session in sessions},
                      key=lambda name: (name != 'paper', name))
    primary = profiles[0]
    rows = case_measures(sessions, primary)
    findings = evaluate_findings(sessions, primary)
    files = {}
    figures.figure_training(sessions, primary, assets / 'fig5_training.png')
    figures.figure_actions(sessions, primary, assets / 'fig6_actions.png')
    figures.figure_convergence(sessions, primary, assets / 'convergence.png')
    choices, chooser_problem = {}, ''
    weights_by_name = dict(PRESETS, **({'your priorities': priorities} if priorities else {}))
    try:
        for name, weights in weights_by_name.items():
            choices[name] = choose(sessions, weights, profile=primary, seed=seed,
                                   resamples=resamples)
        # the role assignment is a choice too: the balanced ranking within each
        for robot_dof, cases in (('rotation', '2, 4, 6'), ('translation', '1, 3, 5')):
            choices[f'balanced, robot on {robot_dof} only (cases {cases})'] = choose(
                sessions, PRESETS['balanced'], robot_dof=robot_dof, profile=primary,
                seed=seed, resamples=resamples)
    except ValueError as error:   # fewer than two strategies in the data
        chooser_problem = str(error)
    names = ['fig5_training.png', 'fig6_actions.png', 'convergence.png', 'sessions.csv']
    if choices:
        figures.figure_three_factor(choices['balanced'], assets / 'fig7_three_factor.png')
        names.append('fig7_three_factor.png')
    (assets / 'sessions.csv').write_text(sessions_csv(sessions))
    for name in names:
        files[name] = assets / name
    text = document(sessions, profiles, rows, findings, choices, command, experiment,
                    chooser_problem, note, intervals=intervals, seed=seed)
    (out_dir / 'results.md').write_text(text)
    files['results.md'] = out_dir / 'results.md'
    return {'files': files, 'findings': findings, 'choices': choices, 'rows': rows,
            'targets': targets(rows, experiment)}


def run_record_lines(experiment: dict) -> list:
    """Return the Markdown lines that say how the sessions were run (from experiment.json).

    A folder resumed over several runs (``hrc experiment --resume``) lists each run and how
    many finished sessions each git version contributed; its wall time is the runs' sum.
    """
    lines = []
    runs = experiment.get('runs') or []
    if len(runs) > 1:
        lines += [f'The sessions were run in {len(runs)} runs of the same folder, each later one '
                  'with `--resume` (it keeps every session an earlier run finished):', '']
        lines += [f'{number}. {run.get("started", "?")}, {run.get("version", "?")}: '
                  f'{run.get("sessions_run", "?")} sessions in '
                  f'{(run.get("wall_seconds") or math.nan) / 60:.1f} min wall: '
                  f'`{run.get("command", "?")}`' for number, run in enumerate(runs, 1)]
        versions = collections.Counter(outcome.get('version') or experiment.get('version', '?')
                                       for outcome in completed(experiment))
        lines += ['', 'Finished sessions by the version that ran them: '
                  + ', '.join(f'{version} {count}' for version, count in sorted(versions.items()))
                  + '; the wall time below is the sum over the runs.', '']
    if experiment:
        lines += [f'The sessions were run by{" (the last run)" if len(runs) > 1 else ""}', '',
                  '```bash', experiment.get('command', '?'),
                  '```', '',
                  f'Engine `{experiment.get("engine", "?")}`, executor '
                  f'`{experiment.get("executor", "?")}`: {len(completed(experiment))} of '
                  f'{experiment.get("sessions", "?")} planned sessions finished in '
                  f'{experiment.get("wall_seconds", math.nan) / 60:.1f} min wall on '
                  f'{experiment.get("host_cpus", "?")} CPUs ({experiment.get("started", "?")}'
                  f', {experiment.get("version", "?")})'
                  + (f'; {len(experiment["skipped"])} not started (--stop-after)'
                     if experiment.get('skipped') else '')
                  + (f'; failed: {", ".join(experiment["failed"])}'
                     if experiment.get('failed') else '') + '.', '']
    return lines


def _persons(sessions) -> str:
    persons = sorted({session.extra.get('person', -1) for session in sessions})
    if persons == [-1]:
        return 'every session with the profile itself (no population draw)'
    return (f'simulated persons {", ".join(map(str, persons))} of the population around the '
            f'profile (human.person; -1 = the profile itself)')


def document(sessions, profiles, rows, findings, choices, command, experiment,
             chooser_problem: str = '', note: str = '', intervals: str = 'bca',
             seed: int = 0) -> str:
    """Return the Markdown of docs/results.md."""
    primary = profiles[0]
    seeds = sorted({session.seed for session in sessions})
    limits = sorted({session.episode_limit for session in sessions if session.episode_limit})
    cases = sorted({session.case_id for session in sessions})
    parts = [f'# Results: {len(cases)} cases over seeds, with statistics', '',
             'Generated from the bags by', '', '```bash', command, '```', '']
    parts += run_record_lines(experiment)
    if note:
        parts += [note, '']
    parts += [f'{len(sessions)} sessions: simulated-human profiles '
              f'{", ".join(f"`{profile}`" for profile in profiles)}; seeds '
              f'{seeds[0]}..{seeds[-1]}; {_persons(sessions)}; episode '
              f'limit {", ".join(map(str, limits)) or "?"}. Tables and findings below are for '
              f'profile `{primary}` unless named.', '',
              '## Table II: mean [95% confidence interval] over seeds', '',
              table2_markdown(rows, intervals, seed),
              'Episodes count every episode until training ended, the evaluation episodes '
              'that judged convergence included; human-involved episodes count those in which '
              "the simulated human acted (the person's time). Errors and efforts: mean over "
              'the final evaluation episodes of the frozen deterministic policy (mean |S_x| m, '
              '|P_z| rad, |B_y| m per episode, their sum; effort = variance of the '
              "normalized action, 1 = the sim's limit; the physical columns multiply it by the "
              'limit '
              "squared: N^2 for the slider's force, (N*m)^2 for the pendulum's torque, "
              "from the session's recorded sim parameters or the sim's defaults). Total error "
              "sums metres and radians (mixed units, as the paper's sum). "
              + (INTERVAL_NOTES[intervals]) + ' Sessions that hit the episode limit enter '
              'the episode counts at the limit: those columns are restricted means (a lower '
              'bound of the unrestricted mean); the next table and the findings treat them as '
              'censored.', '',
              '## Episodes to convergence (censored at the limit)', '',
              convergence_markdown(rows),
              'Kaplan-Meier median with the Brookmeyer-Crowley 95% interval (log-log); "not '
              'reached": fewer than half of the seeds converged by then. Restricted mean: mean '
              'of min(episodes, limit).', '',
              '![Convergence](results/convergence.png)', '',
              "## Beside the paper's Table II", '', paper_markdown(rows),
              'The paper\'s numbers are one person per case; its error is "cumulative" and not '
              'defined further, so only the order of the errors compares, not their size.', '',
              "## The person's time (what a lab budgets)", '', person_time_markdown(rows),
              "The person's minutes: the human-involved episodes of training (judging "
              "episodes included) at the session's episode duration; breaks, practice and the "
              "final evaluation excluded. The paper's: its human-involved episodes x 40 s.", '',
              "## Targets of issues #13 and #23 (and #12's wall time)", '',
              '| target | measured | met |', '|---|---|---|']
    parts += [f'| {target} | {measured} | {_met(met)} |'
              for target, measured, met in targets(rows, experiment)]
    parts += ['', "## The paper's findings", '', findings_markdown(findings), '',
              significance_note(), '',
              '## Strategy chooser', '',
              "Ranks the strategies by the three factors and a user's weights "
              '(`hrc_results ... --priorities performance=3,human=1,time=1`); each factor is '
              'scored relative to the worst strategy (1 - value / worst) and the score is the '
              'weighted mean; intervals and "first in" come from a stratified bootstrap over '
              'seeds. Both role assignments pooled, as in Fig. 7; then the balanced ranking '
              'within each role assignment.', '']
    for name, choice in choices.items():
        parts += [choice_markdown(choice, name), '']
    if chooser_problem:
        parts += [f'Not computed: {chooser_problem}.', '']
    parts += ['## Figures', '', '![Fig. 5](results/fig5_training.png)', '',
              'Fig. 5: training episodes (top) and the deterministic judging episodes (bottom) '
              'apart (EpisodeSummary.kind; bags recorded before that field cannot tell them '
              'apart and show both on top). Line: median over all seeds of the case; band: '
              'inter-quartile range across the seeds (half of them lie inside); a session '
              'that converged or hit the limit is carried at its last value (tick: where it '
              'stopped), so no average is over the survivors only.', '',
              '![Fig. 6](results/fig6_actions.png)', '']
    if choices:
        parts += ['![Fig. 7](results/fig7_three_factor.png)', '']
    parts += [
              'Per-session values: [results/sessions.csv](results/sessions.csv).', '']
    return '\n'.join(parts)
