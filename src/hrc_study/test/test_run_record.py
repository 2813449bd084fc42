"""How results.md says the sessions were run: one run, or a folder resumed over several."""

from hrc_study.results_tables import run_record_lines, wall_target


def _outcome(case, seed, version=None, after=60.0):
    outcome = {'session_id': f'case{case}-seed{seed}', 'case': case, 'seed': seed,
               'profile': 'paper', 'exit_code': 0, 'finished_after': after}
    if version:
        outcome['version'] = version
    return outcome


def test_a_resumed_folder_lists_its_runs_and_the_versions_of_its_sessions():
    runs = [{'started': '2026-12-02 00:33:06 UTC', 'version': 'git a35b056', 'wall_seconds': 600.0,
             'sessions_run': 50, 'command': 'hrc experiment --seeds 10'},
            {'started': '2026-12-02 06:10:00 UTC', 'version': 'git c0ffee1', 'wall_seconds': 300.0,
             'sessions_run': 10, 'command': 'hrc experiment --seeds 10 --resume'}]
    outcomes = ([_outcome(case, seed, 'git a35b056') for case in range(1, 7)
                 for seed in range(9)][:50]
                + [_outcome(case, 9, 'git c0ffee1') for case in range(1, 7)][:10])
    experiment = {'runs': runs, 'outcomes': outcomes, 'wall_seconds': 900.0, 'sessions': 60,
                  'command': runs[-1]['command'], 'engine': 'inprocess', 'version': 'git c0ffee1'}
    text = '\n'.join(run_record_lines(experiment))
    assert 'in 2 runs of the same folder' in text
    assert '1. 2026-12-02 00:33:06 UTC, git a35b056: 50 sessions in 10.0 min wall' in text
    assert 'git a35b056 50, git c0ffee1 6' in text      # six outcomes were new in run 2
    assert 'run by (the last run)' in text and '15.0 min wall' in text
    # no single wall time covers sessions of two runs: the wall-time target is not measured
    assert wall_target(experiment)[2] is None and 'resumed' in wall_target(experiment)[1]


def test_one_run_reads_as_before():
    experiment = {'outcomes': [_outcome(2, 0)], 'wall_seconds': 120.0, 'sessions': 1,
                  'command': 'hrc experiment --cases 2', 'engine': 'inprocess',
                  'version': 'git 2c854d5', 'host_cpus': 2, 'started': 'then'}
    text = '\n'.join(run_record_lines(experiment))
    assert 'runs of the same folder' not in text and 'run by\n' in text
    assert '1 of 1 planned sessions finished in 2.0 min wall on 2 CPUs (then, git 2c854d5)' in text


def test_the_wall_target_times_the_papers_six_cases_and_says_what_ran_beside_them():
    """With cases 7 and 8 in the sweep, the wall-time row timed the last of 80 sessions as '60'.

    Here cases 7 and 8 finish last (at 900 s): the row must time the paper's 60 sessions (the
    last at 60 + 9 * 10 + 6 = 156 s) and say that 20 other sessions ran beside them.
    """
    outcomes = [_outcome(case, seed, after=60.0 + seed * 10 + case) for case in range(1, 7)
                for seed in range(10)]
    outcomes += [_outcome(case, seed, after=900.0) for case in (7, 8) for seed in range(10)]
    experiment = {'outcomes': outcomes, 'wall_seconds': 900.0, 'sessions': 80,
                  'engine': 'inprocess', 'executor': 'local process pool (2 workers)'}
    target, measured, met = wall_target(experiment)
    assert measured.startswith('2.6 min wall for the 60 sessions of profile paper'), measured
    assert '20 other sessions of the sweep ran beside them' in measured
    assert met is True
