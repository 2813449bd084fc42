"""One report for 1..N sessions: ``hrc bag report`` and ``hrc results`` write the same one.

Real bags (the recorder's EpisodeRecorder fed in-process) of case 2 over three seeds and case 5
over one, recorded with a learning configuration in their session config as ``session.yaml``
carries it; then a session of another configuration and one recorded before the entry existed,
which ``hrc results`` (and ``hrc bag report``) refuse to pool unless told.
"""

import csv
import io
import shutil
import subprocess

from hrc_bag import report_cli
from hrc_bag.report import load_records
from hrc_bag.report.records import measures
from hrc_testing.bag_traffic import record_in_process, strategy_plan
from hrc_common.executables import executable_path
import pytest

from hrc_study import results_cli

SAC = {'name': 'sac', 'settings': {'algorithm': 'sac', 'gradient_steps': 1}}
PPO = {'name': 'ppo', 'settings': {'algorithm': 'ppo', 'epochs': 10}}
SESSIONS = [(2, 'responsibility_guided', 0), (2, 'responsibility_guided', 1),
            (2, 'responsibility_guided', 2), (5, 'learn_together', 0)]
SAME_FILES = ('table2.md', 'table2.csv', 'sessions.csv', 'human_time.md', 'human_time.csv',
              'fig7_three_factor.csv')


def config(case: int, strategy: str, seed: int, learning=None) -> dict:
    """Return a session config as session.yaml holds it (``learning`` None: before the entry)."""
    values = {'session_id': f'case{case}-seed{seed}', 'case': case, 'strategy': strategy,
              'seed': seed, 'parameters': {'agent': {'seed': seed, 'lr': 0.0003},
                                           'sim': {'episode_duration': 40.0}}}
    if learning is not None:
        values['learning'] = learning
    return values


def record(folder, case: int, strategy: str, seed: int, learning=None, name: str = '') -> None:
    plan = strategy_plan(strategy, 1 + seed, 1, 2)     # training length varies with the seed
    record_in_process(folder, name or f'case{case}-seed{seed}', case, strategy, seed, plan,
                      steps=6, session_config=config(case, strategy, seed, learning))


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Four sessions of configuration sac in bags/sac."""
    folder = tmp_path_factory.mktemp('one_report') / 'sac'
    for case, strategy, seed in SESSIONS:
        record(folder, case, strategy, seed, SAC)
    return folder


def rows_of(text: str) -> list:
    return list(csv.DictReader(io.StringIO(text)))


def test_the_report_of_one_session_holds_its_values(bags, tmp_path):
    assert report_cli.main([str(bags / 'case2-seed1'), '--out', str(tmp_path)]) == 0
    record_, = load_records([bags / 'case2-seed1'], log=lambda text: None)
    values = measures(record_)
    row, = rows_of((tmp_path / 'table2.csv').read_text())
    assert (row['case_id'], row['sessions']) == ('2', '1')
    for key in ('human_involved_episodes', 'total_episodes', 'total_error', 'human_effort'):
        assert float(row[f'{key}_mean']) == pytest.approx(values[key]), key
        assert (row[f'{key}_low'], row[f'{key}_high'], row[f'{key}_n']) == ('', '', '1')
    assert values['total_episodes'] == 3 and values['human_involved_episodes'] == 1
    text = (tmp_path / 'table2.md').read_text()
    assert 'Learning configuration: sac (1 session).' in text
    # the person's time: 1 human-involved episode of 40 s
    assert '| 2 | 1 | 0.7 [0.7, 0.7] | 4.0 | 0.17x | yes |' in text
    session, = rows_of((tmp_path / 'sessions.csv').read_text())
    assert (session['learning'], session['complete'], session['seed']) == ('sac', 'True', '1')


def test_hrc_results_writes_the_same_report_as_hrc_bag_report(bags, tmp_path):
    assert report_cli.main([str(bags), '--out', str(tmp_path / 'bag')]) == 0
    assert results_cli.main([str(bags), '--out', str(tmp_path / 'study')]) == 0
    for name in SAME_FILES:
        assert (tmp_path / 'study' / 'results' / name).read_text() == (
            tmp_path / 'bag' / name).read_text(), name
    table = {row['case_id']: row for row in rows_of((tmp_path / 'bag' / 'table2.csv')
                                                     .read_text())}
    assert (table['2']['sessions'], table['5']['sessions']) == ('3', '1')
    case2 = [measures(record_) for record_ in load_records([bags], log=lambda text: None)
             if record_.case_id == 2]
    mean = sum(value['total_episodes'] for value in case2) / 3
    assert float(table['2']['total_episodes_mean']) == pytest.approx(mean)
    assert float(table['2']['total_episodes_low']) <= mean <= float(
        table['2']['total_episodes_high'])
    document = (tmp_path / 'study' / 'results.md').read_text()
    assert 'learning configuration sac (4 sessions)' in document
    report_rows = [line for line in (tmp_path / 'bag' / 'table2.md').read_text().splitlines()
                   if line.startswith(('| 2 |', '| 5 |'))]
    assert report_rows and all(line in document for line in report_rows)
    for name in ('fig5_training.png', 'fig6_actions.png', 'fig7_three_factor.png'):
        assert (tmp_path / 'study' / 'results' / name).stat().st_size > 20_000, name


def test_sessions_of_different_learning_configurations_are_refused_unless_told(bags, tmp_path):
    mixed = tmp_path / 'mixed'
    shutil.copytree(bags, mixed)
    record(mixed, 2, 'responsibility_guided', 3, PPO)
    record(mixed, 2, 'responsibility_guided', 4, None)           # recorded before the entry
    hrc = str(executable_path('hrc_bringup', 'hrc'))
    for command in ([hrc, 'results', str(mixed), '--out', str(tmp_path / 'study')],
                    [hrc, 'bag', 'report', str(mixed), '--out', str(tmp_path / 'bag')]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=300)
        assert done.returncode == 2, (command, done.stderr)
        assert 'Traceback' not in done.stderr
        assert ('the sessions were run with 3 learning configurations: sac (4 sessions), ppo '
                '(1 session), unrecorded (1 session)') in done.stderr, done.stderr
        assert '--pool-configurations' in done.stderr
    assert not (tmp_path / 'study' / 'results.md').exists()
    assert not (tmp_path / 'bag' / 'table2.md').exists()
    # the same name with other settings is another configuration
    edited = tmp_path / 'edited'
    shutil.copytree(bags, edited)
    record(edited, 5, 'learn_together', 1, {'name': 'sac', 'settings': {'algorithm': 'sac',
                                                                        'gradient_steps': 4}})
    assert report_cli.main([str(edited), '--out', str(tmp_path / 'edited-out')]) == 2
    # told to pool: one Table II over every configuration, and the document names them
    assert results_cli.main([str(mixed), '--out', str(tmp_path / 'pooled'),
                             '--pool-configurations']) == 0
    document = (tmp_path / 'pooled' / 'results.md').read_text()
    assert 'learning configuration sac (4 sessions), ppo (1 session), unrecorded (1 session)' \
        in document
    table = {row['case_id']: row for row in rows_of(
        (tmp_path / 'pooled' / 'results' / 'table2.csv').read_text())}
    assert table['2']['sessions'] == '5'
