"""The report by subject: a real study folder (hrc_live.study) and real bags (SessionWriter)."""

import csv
import dataclasses
import io
import json
import os
import subprocess
import sys

from hrc_common.executables import executable_path
from hrc_common.tlx import TLX_SCALES
from hrc_live import study
from hrc_live.study_cli import index_line
import pytest
import yaml

from hrc_bag import report
from hrc_bag.session_writer import SessionWriter

START_NS = 1_700_000_000_000_000_000
PERIOD_NS = 200_000_000                      # control period of the bags: 0.2 s
SOURCE = {'device': 0, 'joy': 1, 'simulated': 2, 'none': 4}   # HumanAction.SOURCE_*
TLX = {'mental': 55, 'physical': 20, 'temporal': 40, 'performance': 25, 'effort': 60,
       'frustration': 10}                    # raw TLX = 210 / 6 = 35
EVALUATED = {'slider_error': 0.012, 'pendulum_error': 0.25, 'ball_error': 0.031,
             'total_error': 0.293}


def write_session(bags, session_id: str, case: int, episodes: list, strategy: str) -> str:
    """Write one session; ``episodes``: [(summary fields or None, [(source, engaged)...])]."""
    writer = SessionWriter(bags, session_id, descriptions={}, session_config={
        'case': case, 'strategy': strategy, 'seeds': {'session': 0},
        'roles': {'robot': 'translation' if case % 2 else 'rotation',
                  'human': 'rotation' if case % 2 else 'translation'},
        'notes': 'Jane Doe said the stick was stiff'})        # notes never reach the table
    clock = START_NS
    for episode, (summary, steps) in enumerate(episodes):
        writer.begin_episode(episode)
        writer.write('/hrc/session', {'session_id': session_id, 'case_id': case,
                                      'strategy': strategy, 'episode': episode}, clock)
        for step, (source, engaged) in enumerate(steps):
            stamp = step * PERIOD_NS
            writer.write('/hrc/human/action', {
                'header': {'stamp': {'sec': stamp // 10**9, 'nanosec': stamp % 10**9}},
                'episode': episode, 'step': step, 'source': SOURCE[source],
                'engaged': engaged}, clock + stamp)
        clock += len(steps) * PERIOD_NS
        if summary is not None:
            writer.write('/hrc/episode', {'session_id': session_id, 'case_id': case,
                                          'episode': episode, 'steps': len(steps),
                                          **summary}, clock)
        writer.end_episode()
    writer.close()
    return str((bags / session_id).resolve())


@pytest.fixture(scope='module')
def study_folder(tmp_path_factory):
    """P01: case 1 with practice and TLX, then case 2 aborted; P02: a practice only."""
    root = tmp_path_factory.mktemp('study_report')
    folder, bags, runs = root / 'study', root / 'bags', root / 'runs'
    subjects = []
    for subject, consent in (('P01', 'yes'), ('P02', 'yes'), ('P03', 'no')):
        study.register(subjects, subject, consent, '2026-11-30', today='2026-11-30')
    study.assign_orders(subjects, cases=(1, 2))
    study.save_registry(folder, subjects)
    assert [subject.order for subject in subjects] == [[1, 2], [2, 1], []]

    # P01 practice: 2 episodes alone on the stick, 5 steps each, 9 of them engaged
    practice = [(None, [('device', True)] * 5),
                (None, [('device', True)] * 4 + [('device', False)])]
    # P01 case 1: robot alone (human not engaged), then with the device, then the evaluation
    # with 2 steps from the simulated stand-in
    case1 = [({'human_involved': False, 'evaluation': False}, [('none', False)] * 5),
             ({'human_involved': True, 'evaluation': False}, [('device', True)] * 5),
             ({'human_involved': True, 'evaluation': True, **EVALUATED},
              [('device', True)] * 3 + [('simulated', True)] * 2)]
    case2 = [({'human_involved': True, 'evaluation': False}, [('joy', True)] * 4)]
    tlx_file = runs / 'p01-c1' / 'tlx.yaml'
    tlx_file.parent.mkdir(parents=True)
    tlx_file.write_text(yaml.safe_dump([
        {'session_id': 'other', 'case': 1, 'answered': '2026-11-30T20:00:00',
         'scales': {scale: 100.0 for scale in TLX_SCALES}, 'raw_tlx': 100.0},
        {'session_id': 'p01-c1', 'case': 1, 'answered': '2026-11-30T21:10:00',
         'scales': {scale: float(score) for scale, score in TLX.items()}, 'raw_tlx': 35.0}]))
    sessions = [
        ('P01', 'p01-c1-practice', 1, 'practice', practice, 0, ''),
        ('P01', 'p01-c1', 1, 'condition', case1, 0, str(tlx_file)),
        ('P01', 'p01-c2', 2, 'condition', case2, 130, ''),
        ('P02', 'p02-c2-practice', 2, 'practice', practice[:1], 1, ''),
    ]
    for hour, (subject, session_id, case, kind, episodes, code, tlx) in enumerate(sessions):
        strategy = 'practice' if kind == 'practice' else 'responsibility_guided'
        study.record_session(folder, study.IndexEntry(
            subject_id=subject, session_id=session_id, case=case, kind=kind,
            position=study.position_of(subjects, subject, case),
            started=f'2026-11-30T1{hour}:00:00', ended=f'2026-11-30T1{hour}:30:00',
            exit_code=code, bags=write_session(bags, session_id, case, episodes, strategy),
            run_dir=str(runs / session_id), tlx_file=tlx))
    return folder


def test_the_by_subject_table_counts_each_condition_and_its_practice_apart(study_folder,
                                                                           tmp_path):
    entries = report.load_study_index(study_folder)
    notices = []
    result = report.write_study_report(entries, tmp_path, log=notices.append)
    rows = result['rows']
    assert [(row['subject_id'], row['case'], row['position'], row['kind']) for row in rows] == [
        ('P01', 1, 1, 'condition'), ('P01', 2, 2, 'condition'), ('P02', 2, 1, 'practice')]
    first, aborted, practice_only = rows
    assert first['practice_episodes'] == 2
    assert first['practice_human_seconds'] == pytest.approx(9 * 0.2)
    assert (first['human_involved_episodes'], first['total_episodes'],
            first['evaluation_episodes']) == (1, 2, 1)          # practice not among them
    assert first['human_seconds'] == pytest.approx({'device': 8 * 0.2, 'simulated': 2 * 0.2,
                                                    'none': 0.0})
    for key, value in EVALUATED.items():
        assert first[key] == pytest.approx(value)
    assert first['tlx'] == TLX and first['raw_tlx'] == pytest.approx(35.0)
    assert aborted['exit_code'] == 130 and aborted['practice_session_id'] == ''
    assert aborted['human_seconds'] == pytest.approx({'joy': 0.8})
    assert aborted['tlx'] == {} and aborted['total_episodes'] == 1
    assert practice_only['practice_episodes'] == 1 and practice_only['session_id'] == ''
    assert notices == []

    markdown = (tmp_path / 'by_subject.md').read_text()
    assert ('| P01 | 1 | 1 | 2 (1.8) | 1 / 2 | 1 | device 1.6; simulated 0.4; none 0.0 | '
            '0.012 | 0.250 | 0.031 | 0.293 | 55 | 20 | 40 | 25 | 60 | 10 | 35.0 | '
            'stopped at the cap | 1 (exit 0) | p01-c1 |') in markdown
    assert ('| P01 | 2 | 2 | none | 1 / 1 | 0 | joy 0.8 | n/a | n/a | n/a | n/a | n/a | n/a | '
            'n/a | n/a | n/a | n/a | n/a | failed (exit 130) | 1 (exit 130) | p01-c2 |'
            ) in markdown
    assert '| P02 | 2 | 1 | 1 (1.0) | n/a / n/a |' in markdown
    assert 'practice only | 1 (exit 1) | p02-c2-practice |' in markdown
    table = list(csv.DictReader(io.StringIO((tmp_path / 'by_subject.csv').read_text())))
    assert float(table[0]['human_seconds_device']) == pytest.approx(1.6)
    assert float(table[0]['human_seconds_joy']) == 0.0
    assert float(table[1]['human_seconds_joy']) == pytest.approx(0.8)
    assert table[0]['tlx_performance'] == '25.0' and float(table[0]['raw_tlx']) == 35.0
    assert (table[0]['practice_episodes'], table[0]['total_episodes']) == ('2', '2')
    assert float(table[0]['practice_human_seconds']) == pytest.approx(1.8)
    assert table[1]['raw_tlx'] == '' and table[2]['human_seconds_device'] == ''
    for name in ('by_subject.md', 'by_subject.csv'):
        text = (tmp_path / name).read_text()
        assert 'Jane' not in text and 'stiff' not in text
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o600        # holds subject ids


def _resumed_condition(folder, bags, runs, index_format: str):
    """Index P01's case 2 aborted (exit 3) and resumed (exit 0) under one session id.

    ``index_format``: 'current' (record_session, twice) or 'before attempts' (the entry written
    once per run, as sessions did before attempts existed: the report must still read it).
    """
    session_id = 'p01-c2'
    episodes = [({'human_involved': True, 'evaluation': False}, [('device', True)] * 4),
                ({'human_involved': True, 'evaluation': True, **EVALUATED},
                 [('device', True)] * 4)]
    tlx_file = runs / session_id / 'tlx.yaml'
    tlx_file.parent.mkdir(parents=True)
    tlx_file.write_text(yaml.safe_dump([{
        'session_id': session_id, 'case': 2, 'answered': '2026-11-30T12:00:00',
        'scales': {scale: float(score) for scale, score in TLX.items()}, 'raw_tlx': 35.0}]))
    runs_of = [('2026-11-30T10:00:00', '2026-11-30T10:10:00', 3, ''),
               ('2026-11-30T11:00:00', '2026-11-30T11:40:00', 0, str(tlx_file))]
    bag_folder = write_session(bags, session_id, 2, episodes, 'responsibility_guided')
    records = []
    for started, ended, code, tlx in runs_of:
        entry = study.IndexEntry(
            subject_id='P01', session_id=session_id, case=2, kind='condition', position=1,
            started=started, ended=ended, exit_code=code, bags=bag_folder,
            run_dir=str(runs / session_id), tlx_file=tlx)
        if index_format == 'current':
            study.record_session(folder, entry)
        else:
            record = dataclasses.asdict(entry)
            del record['attempts']
            records.append(record)
    if records:
        folder.mkdir()
        (folder / 'index.yaml').write_text(yaml.safe_dump(records))


@pytest.mark.parametrize('index_format', ['current', 'before attempts'])
def test_an_aborted_and_resumed_condition_is_one_row_with_its_attempts(tmp_path, index_format):
    folder = tmp_path / 'study'
    _resumed_condition(folder, tmp_path / 'bags', tmp_path / 'runs', index_format)
    if index_format == 'current':
        document = yaml.safe_load((folder / 'index.yaml').read_text())
        assert len(document) == 1 and [attempt['exit_code'] for attempt in
                                       document[0]['attempts']] == [3, 0]
        assert document[0]['started'] == '2026-11-30T10:00:00'
        assert document[0]['exit_code'] == 0 and document[0]['tlx_file']
        assert [entry.exit_code for entry in study.load_index(folder)] == [0]
        assert '(attempts: exit 3, 0)' in index_line(study.load_index(folder)[0])
    command = [str(executable_path('hrc_bringup', 'hrc')), 'bag', 'report', '--study-dir',
               str(folder), '--out', str(tmp_path / 'out')]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    markdown = (tmp_path / 'out' / 'by_subject.md').read_text()
    rows = [line for line in markdown.splitlines() if line.startswith('| P01 ')]
    assert len(rows) == 1, markdown
    assert rows[0].endswith('| 35.0 | stopped at the cap | 2 (exit 3, 0) | p01-c2 |'), rows


def test_concurrent_sessions_and_registrations_keep_every_entry(tmp_path):
    """12 registrations and 12 index records at once: every one stays (each under the lock)."""
    folder = tmp_path / 'study'
    script = (
        'import sys\n'
        'from hrc_live import study\n'
        'from hrc_live.study_cli import main\n'
        'number = int(sys.argv[2])\n'
        "assert main(['--study-dir', sys.argv[1], 'register', f'P{number:02d}', '--consent', "
        "'yes']) == 0\n"
        "study.record_session(sys.argv[1], study.IndexEntry(f'P{number:02d}', f's{number}', 2, "
        "'condition', 1, '2026-11-30T10:00:00', '2026-11-30T10:10:00', 0, 'b', 'r'))\n")
    workers = [subprocess.Popen([sys.executable, '-c', script, str(folder), str(number)])
               for number in range(12)]
    assert [worker.wait(timeout=120) for worker in workers] == [0] * 12
    assert sorted(subject.id for subject in study.load_registry(folder)) == [
        f'P{number:02d}' for number in range(12)]
    assert sorted(entry.session_id for entry in study.load_index(folder)) == sorted(
        f's{number}' for number in range(12))


CLI_SCRIPT = r"""
import json, sys
from hrc_bag.report_cli import main
code = main(sys.argv[1:])
print(json.dumps([code, sorted(name for name in sys.modules if name.split('.')[0] == 'rclpy')]))
"""


def test_the_cli_reads_the_study_folder_without_rclpy(study_folder, tmp_path):
    out = tmp_path / 'out'
    done = subprocess.run([sys.executable, '-c', CLI_SCRIPT, '--study-dir', str(study_folder),
                           '--out', str(out)], capture_output=True, text=True, timeout=120,
                          env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    code, rclpy_modules = json.loads(done.stdout.splitlines()[-1])
    assert code == 0 and rclpy_modules == []
    assert '| P01 | 1 | 1 | 2 (1.8) | 1 / 2 | 1 |' in done.stdout
    # without paths, Table II pools the conditions of the index (cases 1 and 2, one each)
    table2 = list(csv.DictReader(io.StringIO((out / 'table2.csv').read_text())))
    assert [(row['case_id'], row['sessions']) for row in table2] == [('1', '1'), ('2', '1')]


BAD_INDEXES = {
    'a mapping': ({'subject_id': 'P01'}, ['not a list of session entries (a dict)']),
    'bad entries': ([{'subject_id': 'Jane Doe', 'session_id': 's1', 'case': 9, 'kind': 'trial',
                      'position': 1, 'started': 'x', 'ended': 'y', 'exit_code': 'zero',
                      'bags': 'b', 'run_dir': 'r', 'notes': 'free text'}, 'just words'],
                    ["entry 1 (s1): unknown fields ['notes']", "subject_id 'Jane Doe' is not",
                     'case must be one of [1, 2, 3, 4, 5, 6], got 9',
                     "kind must be one of ['practice', 'condition'], got 'trial'",
                     "exit_code must be an integer, got 'zero'",
                     "entry 2: not a mapping ('just words')"]),
}


@pytest.mark.parametrize('kind', sorted(BAD_INDEXES))
def test_a_bad_index_is_refused_with_every_reason(tmp_path, kind):
    document, reasons = BAD_INDEXES[kind]
    (tmp_path / 'index.yaml').write_text(yaml.safe_dump(document))
    command = [str(executable_path('hrc_bringup', 'hrc')),
               'bag', 'report', '--study-dir', str(tmp_path),
               '--out', str(tmp_path / 'out')]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1, done.stdout
    assert 'Traceback' not in done.stderr
    for reason in reasons:
        assert reason in done.stderr, (reason, done.stderr)
    assert not (tmp_path / 'out' / 'by_subject.md').exists()


def test_no_index_is_a_bad_argument_and_a_bad_tlx_answer_is_refused(study_folder, tmp_path):
    command = [str(executable_path('hrc_bringup', 'hrc')),
               'bag', 'report', '--study-dir', str(tmp_path),
               '--out', str(tmp_path / 'out')]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and 'Traceback' not in done.stderr
    assert f'{tmp_path / "index.yaml"}: no study index' in done.stderr
    entry = next(entry for entry in report.load_study_index(study_folder) if entry.tlx_file)
    bad = tmp_path / 'tlx.yaml'
    bad.write_text(yaml.safe_dump([{'session_id': entry.session_id,
                                    'scales': {'mental': 120, 'effort': 'high'}}]))
    entry.tlx_file = str(bad)
    with pytest.raises(report.StudyIndexError) as refused:
        report.load_tlx_answer(entry)
    message = str(refused.value)
    assert 'mental: 120 is outside 0..100' in message and 'physical: missing' in message
    assert "effort: missing or not a number ('high')" in message
