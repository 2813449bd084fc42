"""docs/results.md from session records: the report, then findings, targets and the chooser.

The report's part (Table II, the person's time, Fig. 5-7, sessions.csv) is
:func:`hrc_bag.report.write_report`, the same as ``hrc bag report``'s; this module adds the
study's analyses (:mod:`hrc_study.results_tables`, :mod:`hrc_study.findings`,
:mod:`hrc_study.chooser`). Every number in the document is computed from the records passed in
(and the experiment's own ``experiment.json`` when present: command, engine, wall time),
nothing is typed in except the paper's Table II (a fact quoted from the paper, labelled as such).
"""

import pathlib

from hrc_bag.report import describe, learning_configurations, write_report
from hrc_bag.report.intervals import RESAMPLES
from hrc_bag.report.metrics import case_measures, primary_profile
from hrc_bag.report.tables import (CHATTER_NOTE, PERSON_TIME_NOTE, person_time_markdown,
                                   TABLE2_NOTE, table2_markdown)

from hrc_study.chooser import choice_markdown, choose, PRESETS
from hrc_study.convergence import figure_convergence
from hrc_study.findings import evaluate_findings, significance_note
from hrc_study.paper_view import (paper_counting_markdown, paper_counting_note,
                                  robustness_markdown)
from hrc_study.results_tables import (convergence_markdown, findings_markdown, met_cell,
                                      paper_markdown, persons_sentence, run_record_lines,
                                      targets)


def choices_of(sessions, primary: str, priorities: dict, seed: int, resamples: int) -> tuple:
    """Return ({name: Choice}, problem): the chooser's presets, the user's, by role assignment."""
    choices = {}
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
        return choices, str(error)
    return choices, ''


def write_results(sessions, out_dir, command: str, experiment: dict = None,
                  priorities: dict = None, seed: int = 0, note: str = '',
                  resamples: int = 2000, table_resamples: int = RESAMPLES) -> dict:
    """Write ``out_dir/results.md`` and ``out_dir/results/*``; return {name: path} and more.

    ``resamples``: the chooser's bootstrap; ``table_resamples``: Table II's.
    """
    experiment = experiment or {}
    out_dir = pathlib.Path(out_dir)
    assets = out_dir / 'results'
    report = write_report(sessions, assets, seed=seed, resamples=table_resamples)
    primary = report['profile']
    rows = case_measures(sessions, primary)
    findings = evaluate_findings(sessions, primary)
    files = dict(report['files'])
    figure_convergence(sessions, primary, assets / 'convergence.png')
    files['convergence.png'] = assets / 'convergence.png'
    choices, chooser_problem = choices_of(sessions, primary, priorities, seed, resamples)
    study = {'rows': rows, 'findings': findings, 'choices': choices,
             'robustness': robustness_markdown(sessions, primary, findings),
             'chooser_problem': chooser_problem, 'experiment': experiment,
             'table2': table2_markdown(report['groups'], intervals=report['intervals'])}
    (out_dir / 'results.md').write_text(document(sessions, study, command, note))
    files['results.md'] = out_dir / 'results.md'
    return {'files': files, 'findings': findings, 'choices': choices, 'rows': rows,
            'targets': targets(rows, experiment)}


def _introduction(sessions, command: str, experiment: dict, note: str) -> list:
    profiles = sorted({session.profile for session in sessions},
                      key=lambda name: (name != 'paper', name))
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
              f'{seeds[0]}..{seeds[-1]}; {persons_sentence(sessions)}; episode '
              f'limit {", ".join(map(str, limits)) or "?"}; learning configuration '
              f'{describe(learning_configurations(sessions))}. Tables and findings below are '
              f"for profile `{primary_profile(sessions)}` unless named (the other profiles' "
              'Table II: [results/table2.md](results/table2.md)).', '']
    return parts


def _tables(study: dict) -> list:
    rows = study['rows']
    parts = ['## Table II: mean [95% confidence interval] over seeds', '', study['table2'],
             TABLE2_NOTE + ' The next table and the findings treat them as censored. '
             + CHATTER_NOTE, '',
             '## Episodes to convergence (censored at the limit)', '',
             convergence_markdown(rows),
             'Kaplan-Meier median with the Brookmeyer-Crowley 95% interval (log-log); "not '
             'reached": fewer than half of the seeds converged by then. Restricted mean: mean '
             'of min(episodes, limit).', '',
             '![Convergence](results/convergence.png)', '',
             "## Beside the paper's Table II", '', paper_markdown(rows),
             'The paper\'s numbers are one person per case; its error is "cumulative" and not '
             'defined further, so only the order of the errors compares, not their size.', '',
             '## Counted as the paper counts', '', paper_counting_markdown(rows),
             paper_counting_note(rows), '',
             "## The person's time (what a lab budgets)", '', person_time_markdown(rows),
             PERSON_TIME_NOTE, '', "## The study's targets", '',
             '| target | measured | met |', '|---|---|---|']
    parts += [f'| {target} | {measured} | {met_cell(met)} |'
              for target, measured, met in targets(rows, study['experiment'])]
    return parts


def _chooser_and_figures(study: dict) -> list:
    parts = ['', "## The paper's findings", '', findings_markdown(study['findings']), '',
             significance_note(), '', '## The findings under other measures', '',
             study['robustness'],
             'The same tests on the unit-free total error (slider / 0.01 m + pendulum / 0.1 rad '
             '+ ball / 0.05 m: each subtask over its tolerance, params/task_tree.yaml) instead '
             "of the sum of metres and radians, and on the episode counts less each case's "
             "floor (the strict rule's fewest episodes, in the convergence table). A finding "
             'whose verdict changes with a view hinges on that choice.', '',
             '## Strategy chooser', '',
             "Ranks the strategies by the three factors and a user's weights "
             '(`hrc results ... --priorities performance=3,human=1,time=1`); each factor is '
             'scored relative to the worst strategy (1 - value / worst) and the score is the '
             'weighted mean; intervals and "first in" come from a stratified bootstrap over '
             'seeds. Both role assignments pooled, as in Fig. 7; then the balanced ranking '
             'within each role assignment.', '']
    for name, choice in study['choices'].items():
        parts += [choice_markdown(choice, name), '']
    if study['chooser_problem']:
        parts += [f'Not computed: {study["chooser_problem"]}.', '']
    parts += ['## Figures', '', '![Fig. 5](results/fig5_training.png)', '',
              'Fig. 5: training episodes (top) and the deterministic judging episodes (bottom) '
              'apart (EpisodeSummary.kind; bags recorded before that field cannot tell them '
              'apart and show both on top). Line: median over all seeds of the case; band: '
              'inter-quartile range across the seeds (half of them lie inside); a session '
              'that converged or hit the limit is carried at its last value (tick: where it '
              'stopped), so no average is over the survivors only.', '',
              '![Fig. 6](results/fig6_actions.png)', '',
              '![Fig. 7](results/fig7_three_factor.png)', '',
              'Fig. 7: the three factors per strategy, means over its sessions with their 95% '
              'BCa intervals ([results/fig7_three_factor.csv](results/fig7_three_factor.csv)).',
              '', 'Per-session values: [results/sessions.csv](results/sessions.csv).', '']
    return parts


def document(sessions, study: dict, command: str, note: str = '') -> str:
    """Return the Markdown of docs/results.md (``study``: see :func:`write_results`)."""
    return '\n'.join(_introduction(sessions, command, study['experiment'], note)
                     + _tables(study) + _chooser_and_figures(study))
