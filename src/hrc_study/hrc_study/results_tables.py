"""The study's own tables of docs/results.md (pure, no ROS).

Convergence, the paper beside ours, the targets, the findings, and how the sessions were run.
Table II, the person's time and the figures are the report's (:mod:`hrc_bag.report`).
"""

import collections
import json
import math
import pathlib

from hrc_bag.report.paper import PAPER_TABLE2, paper_person_minutes, TARGET_PERSON_TIME_RATIO
from hrc_common.cases import paper_case_ids
import numpy

from hrc_study.statistics import kaplan_meier

UNITS_CAVEAT = ("units: our effort is the variance of the normalized command (1 = the sim's "
                'limit; physical units in Table II), our total error sums metres and radians; '
                'the paper gives neither unit, so only the order of the cases compares')
TARGET_HUMAN_EPISODES = 20          # case 2: median human-involved episodes
TARGET_CONVERGED = 8                # of 10 seeds, within the episode limit
TARGET_EFFORT_RATIO = 3.0           # human effort within 3x of the paper's


def convergence_markdown(rows: dict) -> str:
    """Return episodes to convergence per case: converged count, KM median, restricted mean.

    Also the human-involved episodes to convergence (finding (b)'s measure), censored likewise.
    """
    lines = ['| case | converged | Kaplan-Meier median [95% CI] | restricted mean | '
             'human-involved episodes to convergence, KM median [95% CI] | floor (all / the '
             "person's) | paper (episodes) |",
             '|---|---|---|---|---|---|---|']
    for case_id, values in rows.items():
        times = [value['total_episodes'] for value in values]
        events = [value['converged'] for value in values]
        summary = kaplan_meier(times, events)
        human = kaplan_meier([value['human_involved_episodes'] for value in values], events)
        paper = PAPER_TABLE2.get(case_id)
        paper_text = (f'{paper[1]}' + (' (failed)' if case_id == 5 else '')) if paper else ''
        floors = '/'.join(sorted({f"{value['episode_floor']:.0f} / "
                                  f"{value['person_floor']:.0f}" for value in values}))
        lines.append(f'| {case_id} | {sum(events)}/{len(events)} | {summary.describe()} | '
                     f'{numpy.mean(times):.1f} | {human.describe()} | {floors} | '
                     f'{paper_text} |')
    lines += ['', 'Paper column: its episodes per case (one person); ours count the judging '
              'episodes too, so the definitions differ as well as the people (the next '
              "section counts them the paper's way). Floor: the fewest episodes the strict rule "
              'lets the case take (per step T + W: a window of W judging episodes after T '
              'training episodes; W for the step that judges the pre-trained policy first); '
              'the findings are also tested on the counts above it.']
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


def targets(rows: dict, experiment: dict) -> list:
    """Return [(target, measured, met)] of the study's targets (met None: not measurable)."""
    result = []
    case2 = rows.get(2, [])
    if case2:
        # the Kaplan-Meier median, the number the convergence table gives (censored counts)
        median = kaplan_meier([value['human_involved_episodes'] for value in case2],
                              [value['converged'] for value in case2]).median
        result.append((f'case 2: median human-involved episodes <= {TARGET_HUMAN_EPISODES} '
                       f'(paper: 6)', f'{median:g} over {len(case2)} seeds (Kaplan-Meier)',
                       bool(median <= TARGET_HUMAN_EPISODES)))
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
    # the paper's converging cases converge; the person's time a lab would budget
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
    """Return the wall-time row: six cases x 10 seeds of one profile, if they ran.

    That is when the last of those 60 sessions finished (``finished_after``); other sessions of
    the sweep (a control profile, the cases beyond the paper's) may have run beside them, and
    the row says how many.
    """
    paper_cases = set(paper_case_ids())
    by_profile = {}
    for outcome in completed(experiment):
        if outcome.get('case') in paper_cases:
            by_profile.setdefault(outcome.get('profile', ''), []).append(outcome)
    target = 'six cases x 10 seeds, in-process engine, < 10 min wall'
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


def met_cell(met) -> str:
    return 'n/a (not a 6 x 10 run)' if met is None else ('yes' if met else '**no**')


def findings_markdown(findings) -> str:
    """Return the findings table."""
    lines = ['| | claim | comparison | test | effect | p | Holm p | verdict | reason |',
             '|---|---|---|---|---|---|---|---|---|']
    for finding in findings:
        lines.append(f'| ({finding.key}) | {finding.claim} | {finding.comparison} | '
                     f'{finding.test} | {finding.effect} | {_p(finding.p_value)} | '
                     f'{_p(finding.p_holm)} | **{finding.verdict}** | {finding.reason}'
                     + ''.join(f'; {branch}' for branch in finding.branches) + ' |')
    return '\n'.join(lines) + '\n'


def _p(value: float) -> str:
    return 'n/a' if math.isnan(value) else f'{value:.3g}'


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


def persons_sentence(sessions) -> str:
    persons = sorted({session.extra.get('person', -1) for session in sessions})
    if persons == [-1]:
        return 'every session with the profile itself (no population draw)'
    return (f'simulated persons {", ".join(map(str, persons))} of the population around the '
            f'profile (human.person; -1 = the profile itself)')


