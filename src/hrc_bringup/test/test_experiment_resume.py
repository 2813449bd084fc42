"""Resuming a sweep (hrc_bringup.experiment_resume): which sessions count as finished."""

import dataclasses
import json
from types import SimpleNamespace

from hrc_bringup.experiment import resume_plan
from hrc_bringup.experiment_resume import (finished_sessions, journal_line, read_records,
                                           session_key, split_resumed)
from hrc_bringup.experiment_task import SessionTask
from hrc_common.session_plan import SessionSettings


def _settings(**changes) -> dict:
    settings = {'case': 2, 'seed': 0, 'human_profile': 'paper', 'training_episodes': 300,
                'overrides': {'agent.algorithm': 'sac'}, 'session_id': 'case2-seed0',
                'bags_dir': '/a/bags', 'runs_dir': '/a/runs/case2-seed0', 'notes': ''}
    settings.update(changes)
    return settings


def _finish(folder, settings, exit_code=0, bag=True, engine='inprocess'):
    """Journal a session of an earlier run (and its bag folder, if ``bag``)."""
    folder.mkdir(parents=True, exist_ok=True)
    outcome = {'session_id': settings['session_id'], 'exit_code': exit_code}
    with (folder / 'sessions.jsonl').open('a') as journal:
        journal.write(journal_line({'settings': settings, 'engine': engine}, outcome,
                                   'git abc1234') + '\n')
    if bag:
        (folder / settings['session_id']).mkdir(exist_ok=True)
        session_id = settings['session_id']
        (folder / session_id / f'{session_id}_episode0001.mcap').write_bytes(b'')


def test_the_key_ignores_names_and_folders_but_not_what_changes_the_result():
    key = session_key(_settings(), 'inprocess')
    assert key == session_key(_settings(session_id='case2-seed0-paper', bags_dir='/b',
                                        runs_dir='/b/x', notes='n'), 'inprocess')
    assert key != session_key(_settings(seed=1), 'inprocess')
    assert key != session_key(_settings(overrides={'agent.algorithm': 'ppo'}), 'inprocess')
    assert key != session_key(_settings(), 'graph')
    # the same settings read back from a file (tuples became lists) keep their key
    assert key == session_key(json.loads(json.dumps(_settings())), 'inprocess')


def test_only_sessions_that_ended_well_and_kept_their_bags_count_as_finished(tmp_path):
    _finish(tmp_path, _settings(seed=0, session_id='s0'))
    _finish(tmp_path, _settings(seed=1, session_id='s1'), exit_code=1)   # failed
    _finish(tmp_path, _settings(seed=2, session_id='s2'), bag=False)     # bag removed
    with (tmp_path / 'sessions.jsonl').open('a') as journal:
        journal.write('{"task": {"settings"')    # a line cut by a crash
    finished = finished_sessions(tmp_path)
    assert [record['outcome']['session_id'] for record in finished.values()] == ['s0']
    planned = [(f'task{seed}', _settings(seed=seed, session_id=f'case2-seed{seed}-paper'),
                'inprocess') for seed in range(3)]
    reused, to_run, other = split_resumed(planned, finished, 'git abc1234')
    assert [task for task, _ in reused] == ['task0'] and to_run == ['task1', 'task2']
    assert other == []
    # a session another version of the code finished is run again, and said
    reused, to_run, other = split_resumed(planned, finished, 'git def5678')
    assert reused == [] and to_run == ['task0', 'task1', 'task2']
    assert [(task, record['version']) for task, record in other] == [('task0', 'git abc1234')]


def test_the_manifest_of_a_run_that_ended_is_read_with_its_version(tmp_path):
    settings = _settings(session_id='case2-seed0')
    manifest = {'version': 'git 2c854d5', 'tasks': [{'settings': settings,
                                                     'engine': 'inprocess'}],
                'outcomes': [{'session_id': 'case2-seed0', 'exit_code': 0}]}
    (tmp_path / 'experiment.json').write_text(json.dumps(manifest))
    records = read_records(tmp_path)
    assert [record['version'] for record in records] == ['git 2c854d5']
    assert finished_sessions(tmp_path) == {}            # no bag folder: not finished
    (tmp_path / 'case2-seed0').mkdir()
    (tmp_path / 'case2-seed0' / 'case2-seed0_end.mcap').write_bytes(b'')
    assert len(finished_sessions(tmp_path)) == 1


def test_a_resumed_plan_keeps_the_runs_its_sessions_came_from(tmp_path):
    def task(case):
        return SessionTask(SessionSettings(case=case, seed=0, session_id=f'case{case}-seed0'),
                           engine='inprocess', params_dir='params', pull_bags=False)

    planned = [task(1), task(2), task(3)]
    # a finished run of another version (nothing of it is kept) ...
    (tmp_path / 'experiment.json').write_text(json.dumps({'runs': [
        {'started': 'run A', 'version': 'git 0ld0ld0', 'wall_seconds': 100.0,
         'sessions_run': 3}]}))
    # ... then an interrupted run of this version that finished cases 1 and 2
    for case in (1, 2):
        settings = dataclasses.asdict(planned[case - 1].settings)
        _finish(tmp_path, settings, engine='inprocess')
    lines = (tmp_path / 'sessions.jsonl').read_text().splitlines()
    records = [json.loads(line) for line in lines]
    for record, after in zip(records, (40.0, 70.0)):
        record['version'] = 'git new1234'
        record['outcome'].update(run_started='run B', finished_after=after)
    (tmp_path / 'sessions.jsonl').write_text(
        ''.join(json.dumps(record) + '\n' for record in records))
    runs, reused, to_run = resume_plan(SimpleNamespace(resume=True), tmp_path, planned,
                                       'git new1234')
    assert [task.session_id for task in to_run] == ['case3-seed0']
    assert [task.session_id for task, _ in reused] == ['case1-seed0', 'case2-seed0']
    # run A's sessions are not kept, so neither is run A; run B's wall: its last session's end
    assert runs == [{'command': '(interrupted; from the journal)', 'started': 'run B',
                     'wall_seconds': 70.0, 'version': 'git new1234', 'sessions_run': 2}]
    # without --resume nothing is kept
    assert resume_plan(SimpleNamespace(resume=False), tmp_path, planned, 'git new1234') == (
        [], [], planned)
