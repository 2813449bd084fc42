"""hrc_common.contract: the definitions every package shares."""

import datetime
import os
import subprocess
import sys

import pytest

from hrc_common import contract
from hrc_common.cases import case_problem, case_table, CaseTableError, load_case_table
from hrc_common.contract import (atomic_write, check_id, id_problem, make_session_id, other_dof,
                                 Phase, phase_label, ROTATION, TRANSLATION)


def test_phases_equal_the_message_constants():
    from hrc_msgs.msg import SessionStatus
    for phase in Phase:
        assert getattr(SessionStatus, f'PHASE_{phase.name}') == phase.value
    declared = {name for name in dir(SessionStatus) if name.startswith('PHASE_')}
    assert declared == {f'PHASE_{phase.name}' for phase in Phase}
    assert Phase.from_label('evaluation') is Phase.EVALUATION
    assert Phase.PAUSED.label == 'paused'
    assert phase_label(5) == 'aborted' and phase_label(9) == 'phase 9'
    assert phase_label(9, '?') == '?'
    with pytest.raises(ValueError, match='unknown phase'):
        Phase.from_label('resting')


def test_a_phase_equals_its_label_and_its_code():
    # AgentCore.phase is a Phase; code that names phases by label keeps working with it
    assert Phase.DONE == 'done' and 'done' == Phase.DONE and Phase.DONE != 'training'
    assert not Phase.DONE != 'done'
    assert Phase.DONE == 4 and Phase.DONE in contract.FINISHED_PHASES
    assert 4 in contract.FINISHED_PHASES and {Phase.DONE: 'x'}[4] == 'x'   # hashed as its code
    assert Phase.UPDATING in ('training', 'updating') and 'paused' in (Phase.PAUSED,)
    assert str(Phase.PAUSED) == 'paused' and f'phase {Phase.EVALUATION}' == 'phase evaluation'
    assert Phase.from_label(Phase.ABORTED) is Phase.ABORTED


def test_input_sources_equal_the_message_constants():
    from hrc_msgs.msg import HumanAction
    declared = {name for name in dir(HumanAction) if name.startswith('SOURCE_')}
    assert declared == {f'SOURCE_{source.name}' for source in contract.InputSource}
    for source in contract.InputSource:
        assert getattr(HumanAction, f'SOURCE_{source.name}') == source.value
    assert contract.source_label(2) == 'simulated' and contract.source_label(9, '?') == '?'
    assert contract.source_label(9) == 'source 9'


def test_episode_kinds_equal_the_message_constants_and_old_bags_infer_them():
    from hrc_msgs.msg import EpisodeSummary
    declared = {name for name in dir(EpisodeSummary) if name.startswith('KIND_')}
    assert declared == {f'KIND_{kind.name}' for kind in contract.EpisodeKind}
    for kind in contract.EpisodeKind:
        assert getattr(EpisodeSummary, f'KIND_{kind.name}') == kind.value
    kind_of = contract.episode_kind
    assert kind_of(EpisodeSummary.KIND_JUDGING, evaluation=True) is contract.EpisodeKind.JUDGING
    # unknown (old bags): the flags decide, training by default
    assert kind_of(0, evaluation=True) is contract.EpisodeKind.EVALUATION
    assert kind_of(0, judging=True) is contract.EpisodeKind.JUDGING
    assert kind_of(0, practice=True).label == 'practice'
    assert kind_of(None).label == 'training' and kind_of(99).label == 'training'


def test_dof_indices_and_types_equal_the_messages():
    from hrc_msgs.msg import HumanAction, SessionStatus
    assert contract.DOF_INDEX == {TRANSLATION: SessionStatus.DOF_TRANSLATION,
                                  ROTATION: SessionStatus.DOF_ROTATION}
    assert HumanAction.DOF_TRANSLATION == 0 and contract.dof_name(1) == ROTATION
    assert contract.dof_name(7) == 'dof 7'
    from hrc_msgs.msg import AgentStep, EpisodeSummary, TaskState
    for name, cls in ((contract.TASK_STATE_TYPE, TaskState),
                      (contract.HUMAN_ACTION_TYPE, HumanAction),
                      (contract.SESSION_STATUS_TYPE, SessionStatus),
                      (contract.EPISODE_SUMMARY_TYPE, EpisodeSummary),
                      (contract.AGENT_STEP_TYPE, AgentStep)):
        assert name == f'hrc_msgs/msg/{cls.__name__}'


def test_import_is_pure():
    """Importing the contract loads neither rclpy nor any message package."""
    code = ('import sys, hrc_common.contract; '
            'print(sorted(m for m in sys.modules if m.startswith(("rclpy", "hrc_msgs"))))')
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == '[]'


def test_time_and_colours():
    assert contract.seconds_to_ns(0.1) == 100_000_000
    assert contract.ns_to_seconds(contract.NS_PER_S * 3) == 3.0
    assert contract.rgb8(contract.BODY_COLOURS['slider']) == (255, 140, 26)


@pytest.mark.parametrize('text', ['case2-seed0-20260101-120000', 'S01', 'p.7_a-b', 'a' * 64])
def test_valid_ids(text):
    assert id_problem(text) is None and check_id(text) == text


@pytest.mark.parametrize('text', ['', '../../x', '/abs', 'a/b', 'a\\b', '..', 'a..b', '.hidden',
                                  '-rf', 'with space', 'a' * 65, 'naïve', 'x\n', 3])
def test_invalid_ids_give_a_reason(text):
    reason = id_problem(text, 'subject id')
    assert reason and reason.startswith('subject id')
    with pytest.raises(ValueError):
        check_id(text)


def test_session_id_format():
    when = datetime.datetime(2026, 11, 30, 20, 5, 9)
    made = make_session_id(3, 12, when)
    assert made == 'case3-seed12-20261130-200509'
    assert id_problem(made) is None
    assert make_session_id(3, 12, timestamped=False) == 'case3-seed12'


def test_case_table_from_the_repository_file():
    table = case_table()
    assert sorted(table) == [1, 2, 3, 4, 5, 6, 7, 8]   # the paper's six, and partners first
    for case_id, spec in table.items():
        assert spec.robot_dof == (TRANSLATION if case_id % 2 else ROTATION)
        assert spec.human_dof == other_dof(spec.robot_dof)
    assert [table[c].strategy for c in (1, 3, 5, 7)] == ['responsibility_guided', 'level_guided',
                                                         'learn_together', 'partners_first']
    assert table[8].strategy == 'partners_first'
    assert case_problem(6) is None and case_problem(8) is None
    assert case_problem(9) == 'case must be one of 1..8, got 9'
    assert case_problem(True) and case_problem('2')


@pytest.mark.parametrize('text, reasons', [
    ('- 1\n- 2\n', ['expected a mapping']),
    ('{', ['not YAML']),
    ('strategies: {a: {}}\n'
     'cases: {1: {strategy: b, robot_action: twist, extra: 1}, 0: {}, x: 5, 2: 3}\n',
     ['case id 0', "strategy 'b'", "robot_action 'twist'", "unknown keys ['extra']",
      "case id 'x'", 'case 2: expected a mapping']),
    ('strategies: 3\n', ['strategies must be a mapping', 'cases must be a non-empty mapping']),
])
def test_bad_case_tables_give_every_reason(tmp_path, text, reasons):
    path = tmp_path / 'cases.yaml'
    path.write_text(text)
    with pytest.raises(CaseTableError) as error:
        load_case_table(path)
    for reason in reasons:
        assert reason in str(error.value)


def test_missing_or_binary_case_table(tmp_path):
    with pytest.raises(CaseTableError, match='cannot read'):
        load_case_table(tmp_path / 'none.yaml')
    binary = tmp_path / 'bin.yaml'
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(CaseTableError, match='not YAML'):
        load_case_table(binary)


def test_atomic_write_modes_and_replacement(tmp_path):
    old_umask = os.umask(0o077)
    try:
        public = tmp_path / 'public.yaml'
        atomic_write(public, 'a: 1\n')
        assert public.read_text() == 'a: 1\n'
        assert public.stat().st_mode & 0o777 == 0o644
    finally:
        os.umask(old_umask)
    personal = tmp_path / 'session.yaml'
    personal.write_text('old')
    personal.chmod(0o644)
    atomic_write(personal, b'subject_id: S01\n', mode=contract.PERSONAL_FILE_MODE)
    assert personal.read_bytes() == b'subject_id: S01\n'
    assert personal.stat().st_mode & 0o777 == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ['public.yaml', 'session.yaml']


def test_atomic_write_leaves_the_old_file_on_failure(tmp_path):
    path = tmp_path / 'kept.txt'
    path.write_text('old')
    with pytest.raises(TypeError):
        atomic_write(path, 5.0)
    assert path.read_text() == 'old'
    assert [p.name for p in tmp_path.iterdir()] == ['kept.txt']
