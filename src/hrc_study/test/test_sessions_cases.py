"""The study reads the paper's cases and strategies from params/cases.yaml (no copy of its own)."""

from hrc_common.cases import case_table
from hrc_bag.report.records import case_roles, SessionRecord, strategy_step_counts


def test_the_cases_are_the_case_table():
    assert case_roles() == {case_id: (spec.strategy, spec.robot_dof)
                            for case_id, spec in case_table().items()}
    # the paper's six cases (section IV), as the study used to hard-code them
    assert case_roles() == {
        1: ('responsibility_guided', 'translation'), 2: ('responsibility_guided', 'rotation'),
        3: ('level_guided', 'translation'), 4: ('level_guided', 'rotation'),
        5: ('learn_together', 'translation'), 6: ('learn_together', 'rotation'),
        # beyond the paper: partners first
        7: ('partners_first', 'translation'), 8: ('partners_first', 'rotation')}


def test_the_step_counts_are_the_strategies_of_the_cases_file():
    assert strategy_step_counts() == {'responsibility_guided': 2, 'level_guided': 2,
                                      'learn_together': 1, 'partners_first': 3}
    record = SessionRecord(session_id='s', case_id=5, strategy='learn_together',
                           robot_dof='translation', seed=0, profile='paper', episodes=[])
    assert record.steps == 1
