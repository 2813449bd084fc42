"""The six cases (eq. 6-10, roles swapped in 2, 4, 6) and the transitions of every strategy."""

import copy

import pytest
import yaml

from hrc_common.paths import params_dir
from hrc_agent_node.strategies import (cases_from_dict, CasesError, load_cases,
                                       StrategyProgress)
from hrc_agent_node.task_tree import TaskTree

PARAMS = params_dir()
TREE = TaskTree.from_file(f'{PARAMS}/task_tree.yaml')
CASES = load_cases(f'{PARAMS}/cases.yaml', TREE)

GOOD = {'slider': 0.001, 'pendulum': 0.01, 'ball': 0.01}       # within every tolerance
LEVEL_TWO_ONLY = {'slider': 0.001, 'pendulum': 0.01, 'ball': 0.2}
SLIDER_ONLY = {'slider': 0.001, 'pendulum': 1.3, 'ball': 0.24}
PENDULUM_ONLY = {'slider': 0.03, 'pendulum': 0.01, 'ball': 0.2}
BAD = {'slider': 0.03, 'pendulum': 1.3, 'ball': 0.24}


def test_six_cases_match_the_paper():
    assert sorted(CASES) == [1, 2, 3, 4, 5, 6, 7, 8]
    for case_id, strategy in ((1, 'responsibility_guided'), (3, 'level_guided'),
                              (5, 'learn_together')):
        robot_translates, robot_rotates = CASES[case_id], CASES[case_id + 1]
        assert robot_translates.strategy == robot_rotates.strategy == strategy
        assert (robot_translates.robot_dof, robot_translates.human_dof) == \
            ('translation', 'rotation')
        assert (robot_rotates.robot_dof, robot_rotates.human_dof) == ('rotation', 'translation')
    everything = ('ball', 'slider', 'pendulum')
    # eq. 6, 7: robot alone on f_1^2 + f_2^2, then the human joins and f_1^1 is added.
    one = CASES[1].steps
    assert [(s.robot_subtasks, s.human_involved) for s in one] == \
        [(('slider', 'pendulum'), False), (everything, True)]
    assert one[0].human_subtasks == () and one[1].human_subtasks == ('ball', 'pendulum')
    assert CASES[2].steps[1].human_subtasks == ('ball', 'slider')
    # eq. 8, 9: together on level 2 (the human on its own level-2 subtask), then everything.
    three = CASES[3].steps
    assert [(s.robot_subtasks, s.human_involved, s.advance) for s in three] == \
        [(('slider', 'pendulum'), True, 'lower_levels_satisfied'), (everything, True, 'converged')]
    assert three[0].human_subtasks == ('pendulum',)
    assert CASES[4].steps[0].human_subtasks == ('slider',)
    # eq. 10: one step, everything, together.
    assert [(s.robot_subtasks, s.human_involved) for s in CASES[5].steps] == [(everything, True)]
    assert CASES[6].steps[0].human_subtasks == ('ball', 'slider')


def test_responsibility_guided_transitions_case_1():
    progress = StrategyProgress(CASES[1], TREE, convergence_window=3)
    assert progress.step.watch == ('slider',)   # alone, the robot can hold its own subtask
    assert progress.record(SLIDER_ONLY) == (False, '')
    assert progress.record(SLIDER_ONLY) == (False, '')
    assert progress.record(BAD) == (False, '')           # the window restarts
    for _ in range(2):
        assert progress.record(SLIDER_ONLY) == (False, '')
    assert progress.record(SLIDER_ONLY) == (True, 'advanced')
    assert progress.step.index == 1 and progress.step.human_involved
    assert progress.step_history == []                   # episodes are counted per step
    for _ in range(2):
        assert progress.record(GOOD) == (False, '')
    assert progress.record(LEVEL_TWO_ONLY) == (False, '')  # the ball counts now
    for _ in range(2):
        assert progress.record(GOOD) == (False, '')
    assert progress.record(GOOD) == (True, 'finished')
    assert progress.finished
    with pytest.raises(RuntimeError, match='already finished'):
        progress.record(GOOD)


def test_responsibility_guided_case_2_watches_the_pendulum():
    progress = StrategyProgress(CASES[2], TREE, convergence_window=2)
    assert progress.step.watch == ('pendulum',)
    assert progress.record(SLIDER_ONLY) == (False, '')
    assert progress.record(PENDULUM_ONLY) == (False, '')
    assert progress.record(PENDULUM_ONLY) == (True, 'advanced')


@pytest.mark.parametrize('case_id', [3, 4])
def test_level_guided_transitions(case_id):
    progress = StrategyProgress(CASES[case_id], TREE, convergence_window=2, satisfied_window=2)
    assert progress.step.watch == ('slider', 'pendulum')
    assert progress.record(SLIDER_ONLY) == (False, '')
    assert progress.record(PENDULUM_ONLY) == (False, '')
    assert progress.record(LEVEL_TWO_ONLY) == (False, '')
    assert progress.record(LEVEL_TWO_ONLY) == (True, 'advanced')   # the ball is not asked yet
    assert progress.step.robot_subtasks == ('ball', 'slider', 'pendulum')
    assert progress.record(LEVEL_TWO_ONLY) == (False, '')
    assert progress.record(GOOD) == (False, '')
    assert progress.record(GOOD) == (True, 'finished')


@pytest.mark.parametrize('case_id', [5, 6])
def test_learn_together_transitions(case_id):
    progress = StrategyProgress(CASES[case_id], TREE, convergence_window=3)
    assert progress.is_last_step
    for _ in range(5):
        assert progress.record(LEVEL_TWO_ONLY) == (False, '')
    assert progress.record(GOOD) == (False, '')
    assert progress.record(GOOD) == (False, '')
    assert progress.record(GOOD) == (True, 'finished')


def test_progress_state_round_trip_and_case_check():
    progress = StrategyProgress(CASES[3], TREE, satisfied_window=3)
    progress.record(LEVEL_TWO_ONLY)
    progress.record(LEVEL_TWO_ONLY)
    restored = StrategyProgress(CASES[3], TREE, satisfied_window=3)
    restored.load_state_dict(progress.state_dict())
    assert restored.record(LEVEL_TWO_ONLY) == (True, 'advanced')
    with pytest.raises(ValueError, match='case 3 cannot continue case 5'):
        StrategyProgress(CASES[5], TREE).load_state_dict(progress.state_dict())


def test_missing_errors_are_refused():
    with pytest.raises(ValueError, match="lack subtasks \\['ball'\\]"):
        StrategyProgress(CASES[1], TREE).record({'slider': 0.0, 'pendulum': 0.0})


def cases_document():
    with open(f'{PARAMS}/cases.yaml') as stream:
        return yaml.safe_load(stream)


@pytest.mark.parametrize('change, reason', [
    (lambda d: d['cases'][1].update(strategy='guess'), "unknown strategy 'guess'"),
    (lambda d: d['cases'][1].update(robot_action='jump'), "robot_action 'jump' is not an action"),
    (lambda d: d['strategies']['level_guided']['steps'][0].update(advance='whenever'),
     "advance 'whenever' is not one of"),
    (lambda d: d['strategies']['learn_together']['steps'][0].update(robot_subtasks=['tail']),
     "unknown subtasks ['tail']"),
    (lambda d: d['strategies']['responsibility_guided']['steps'][0].update(
        human_subtasks=['ball']), 'the human is not involved but has subtasks'),
    (lambda d: d['strategies']['level_guided']['steps'][0].update(
        human_subtasks=['direct:dog']), 'must be direct:robot or direct:human'),
    (lambda d: d['strategies']['learn_together'].update(steps=[]), 'non-empty list `steps`'),
    (lambda d: d['strategies']['partners_first']['steps'][1].update(partner='robot'),
     "partner 'robot' is not one of"),
    (lambda d: d['strategies']['partners_first']['steps'][0].update(partner='population'),
     'partner population needs human_involved true'),
    (lambda d: d['strategies']['partners_first']['steps'].reverse(),
     'a population step must come before every step with the person'),
    (lambda d: d['strategies']['partners_first']['steps'][2].update(judge_first='yes'),
     'judge_first must be true or false'),
])
def test_bad_cases_are_refused_with_reason(change, reason):
    document = copy.deepcopy(cases_document())
    change(document)
    with pytest.raises(CasesError) as error:
        cases_from_dict(document, TREE)
    assert reason in str(error.value)


@pytest.mark.parametrize('case_id, robot, human', [(7, 'translation', 'rotation'),
                                                   (8, 'rotation', 'translation')])
def test_partners_first_steps_alone_then_population_then_the_person(case_id, robot, human):
    case = CASES[case_id]
    assert (case.strategy, case.robot_dof, case.human_dof) == ('partners_first', robot, human)
    everything = ('ball', 'slider', 'pendulum')
    assert [(s.robot_subtasks, s.human_involved, s.partner, s.judge_first) for s in case.steps] \
        == [(('slider', 'pendulum'), False, 'person', False),
            (everything, True, 'population', False),
            (everything, True, 'person', True)]
    assert [s.with_person for s in case.steps] == [False, False, True]
    assert case.first_person_step == 2 and case.has_population_steps
    assert case.steps[0].watch == (case.steps[0].robot_subtasks[0 if robot == 'translation'
                                                                else 1],)
    # the paper's cases have no population step; the person is there from the first step
    # they are involved in
    assert not any(CASES[c].has_population_steps for c in range(1, 7))
    assert [CASES[c].first_person_step for c in range(1, 7)] == [1, 1, 0, 0, 0, 0]
    progress = StrategyProgress(case, TREE, convergence_window=2)
    for expected in ('', 'advanced'):                 # alone: the robot's own subtask
        assert progress.record(GOOD)[1] == expected
    assert progress.step.partner == 'population'
    for expected in ('', 'advanced'):
        assert progress.record(GOOD)[1] == expected
    assert progress.step.with_person and progress.is_last_step
    assert progress.record(GOOD) == (False, '') and progress.record(GOOD) == (True, 'finished')
