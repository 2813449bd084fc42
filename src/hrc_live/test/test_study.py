"""The study protocol's pure parts: registry validation, Williams-square balance, the index."""

import dataclasses
import collections
import itertools

from hrc_live.study import (assign_orders, case_orders, consent_problem,
                            IndexEntry, load_index, load_registry, record_session, register,
                            save_registry,
                            StudyError, williams_rows)
from hrc_live.study_cli import main
import pytest
import yaml


@pytest.mark.parametrize('count', [2, 3, 4, 5, 6])
def test_williams_design_is_balanced_for_position_and_first_order_carryover(count):
    rows = williams_rows(count)
    assert len(rows) == (count if count % 2 == 0 else 2 * count)
    repeats = len(rows) // count
    for row in rows:
        assert sorted(row) == list(range(count))
    for position in range(count):  # each item equally often in each position
        assert collections.Counter(row[position] for row in rows) == {
            item: repeats for item in range(count)}
    pairs = collections.Counter((a, b) for row in rows for a, b in zip(row, row[1:]))
    expected = {pair: repeats for pair in itertools.permutations(range(count), 2)}
    assert pairs == expected  # each case directly followed by each other equally often


def test_case_orders_of_the_researchers_set_and_bad_sets():
    orders = case_orders([1, 2, 5])
    assert len(orders) == 6 and all(sorted(order) == [1, 2, 5] for order in orders)
    for cases in ([], [1, 1], [0, 7]):
        with pytest.raises(StudyError):
            case_orders(cases)


def test_assignment_rotates_through_the_rows_and_never_changes_earlier_ones():
    subjects = []
    for index in range(8):
        register(subjects, f'P{index:02d}', 'no' if index == 3 else 'yes', '2026-11-30')
    assigned = assign_orders(subjects)
    assert [s.id for s in assigned] == ['P00', 'P01', 'P02', 'P04', 'P05', 'P06', 'P07']
    rows = case_orders([1, 2, 3, 4, 5, 6])
    assert [s.order for s in assigned[:6]] == rows and assigned[6].order == rows[0]
    assert subjects[3].order == []  # no consent: no order
    before = [list(s.order) for s in subjects]
    register(subjects, 'P08', 'yes', '2026-12-01')
    assert [s.id for s in assign_orders(subjects)] == ['P08']
    assert [s.order for s in subjects[:8]] == before and subjects[8].order == rows[1]


def test_registry_refuses_names_bad_ids_and_consent_and_says_every_reason(tmp_path):
    with pytest.raises(StudyError) as error:
        register([], 'Jane Doe', 'maybe', '30.11.2026')
    message = str(error.value)
    assert "subject id 'Jane Doe' is not valid" in message
    assert "consent must be 'yes' or 'no'" in message and 'not a date' in message
    (tmp_path / 'subjects.yaml').write_text(yaml.safe_dump([
        {'id': 'P01', 'consent': 'yes', 'consent_date': '2026-11-30',
         'registered': '2026-11-30', 'name': 'Jane Doe'},
        {'id': 'P01', 'consent': 'yes', 'consent_date': '2026-11-30',
         'registered': '2026-11-30'}]))
    with pytest.raises(StudyError) as error:
        load_registry(tmp_path)
    assert "fields ['name'] are not allowed" in str(error.value)
    assert "'P01' is registered twice" in str(error.value)


def test_registry_and_index_files_are_private_and_read_back(tmp_path):
    subjects = []
    register(subjects, 'P07', 'yes', '2026-11-30')
    path = save_registry(tmp_path, subjects)
    assert path.stat().st_mode & 0o777 == 0o600
    assert load_registry(tmp_path)[0].id == 'P07'
    assert consent_problem(subjects, 'P07') == ''
    register(subjects, 'P07', 'no', '2026-12-01')  # consent withdrawn
    assert 'no session without consent' in consent_problem(subjects, 'P07')
    assert 'not in the registry' in consent_problem(subjects, 'P99')
    entry = IndexEntry('P07', 'case2-seed0-x', 2, 'condition', 1, '2026-11-30T10:00:00',
                       '2026-11-30T10:20:00', 0, 'bags/case2-seed0-x', 'runs/case2-seed0-x')
    index = record_session(tmp_path, entry)
    assert index.stat().st_mode & 0o777 == 0o600
    assert load_index(tmp_path) == [dataclasses.replace(entry, attempts=[
        {'started': '2026-11-30T10:00:00', 'ended': '2026-11-30T10:20:00', 'exit_code': 0}])]


def test_cli_register_assign_plan(tmp_path, capsys):
    study = str(tmp_path / 'study')
    assert main(['--study-dir', study, 'register', 'P01', '--consent', 'yes']) == 0
    assert main(['--study-dir', study, 'plan', 'P01']) == 2
    assert 'no case order yet' in capsys.readouterr().err
    assert main(['--study-dir', study, 'assign', '--cases', '2', '5']) == 0
    assert 'P01: cases in the order [2, 5]' in capsys.readouterr().out
    assert main(['--study-dir', study, 'plan', 'P01', '--practice', '2',
                 '--joystick-params', str(tmp_path / 'stick.yaml')]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines.pop(0) == (f'# {tmp_path / "stick.yaml"} does not exist yet: run "hrc joystick '
                            f'setup -o {tmp_path / "stick.yaml"}" with the subject\'s joystick '
                            'first')
    assert lines[0] == '# condition 1 of 2: case 2'
    assert lines[1].startswith('hrc session --case 2 --mode realtime')
    assert f'--params {tmp_path / "stick.yaml"}' in lines[1]
    assert '--subject-id P01' in lines[1] and '--practice 2' in lines[1]
    # Every condition names its learning configuration (the default: what the simulated study
    # measured best), so the live study runs what a simulated one predicts; no --set at all.
    assert lines[1].endswith('--learning sac') and lines[3].endswith('--learning sac'), lines
    assert '--set' not in lines[1] and '--set' not in lines[3]
    assert main(['--study-dir', study, 'plan', 'P01', '--learning', 'ppo']) == 0
    commands = [line for line in capsys.readouterr().out.splitlines() if line.startswith('hrc')]
    assert commands[0].endswith('--learning ppo')
    assert main(['--study-dir', study, 'plan', 'P01', '--learning', 'fast']) == 2
    assert ("--learning 'fast': not a learning configuration (there are: paper, partner_aware, "
            'ppo, sac)') in capsys.readouterr().err
    assert main(['--study-dir', study, 'register', 'Jane Doe', '--consent', 'yes']) == 2
    assert 'is not valid' in capsys.readouterr().err


def test_plan_names_the_joystick_file_and_the_episodes_and_refuses_bad_ones(tmp_path, capsys):
    study, stick = str(tmp_path / 'study'), tmp_path / 'joystick.yaml'
    stick.write_text('human:\n  ros__parameters: {axis: 1}\n')
    main(['--study-dir', study, 'register', 'P01', '--consent', 'yes'])
    main(['--study-dir', study, 'assign', '--cases', '2', '5'])
    capsys.readouterr()
    assert main(['--study-dir', study, 'plan', 'P01', '--joystick-params', str(stick),
                 '--episodes', '40']) == 0
    commands = [line for line in capsys.readouterr().out.splitlines()
                if not line.startswith('#')]
    assert len(commands) == 2 and all(f'--params {stick} ' in line and '--episodes 40 ' in line
                                      for line in commands), commands
    assert main(['--study-dir', study, 'plan', 'P01', '--episodes', '-3']) == 2
    assert '--episodes must be >= 1' in capsys.readouterr().err
    assert main(['--study-dir', study, 'plan', 'P01', '--human', 'joy']) == 0
    assert '--params' not in capsys.readouterr().out     # the joy node maps the stick


def _entry(case, exit_code, kind='condition'):
    from hrc_live.study import IndexEntry
    return IndexEntry(subject_id='P01', session_id=f'c{case}-{exit_code}', case=case, kind=kind,
                      position=0, started='', ended='', exit_code=exit_code, bags='',
                      run_dir='', tlx_file='')


def test_a_condition_out_of_the_registered_order_is_named():
    from hrc_live.study import order_warning, Subject
    subjects = [Subject(id='P01', consent='yes', consent_date='2026-12-01',
                        registered='2026-12-01', order=[2, 5, 4])]
    assert order_warning(subjects, [], 'P01', 2) == ''
    assert order_warning(subjects, [_entry(2, 0)], 'P01', 5) == ''
    assert order_warning(subjects, [_entry(2, 3), _entry(2, 0, 'practice')], 'P01', 4) == (
        'case 4 is condition 3 of P01 (order [2, 5, 4]) but case 2, case 5 before it have not '
        'run to the end: out of the registered order')
    assert order_warning(subjects, [_entry(2, 0)], 'P01', 2) == (
        'case 2 (condition 1 of P01) was run to its end already: this run is a repeat')
    assert order_warning(subjects, [], 'P01', 6) == 'case 6 is not in the order of P01 [2, 5, 4]'
