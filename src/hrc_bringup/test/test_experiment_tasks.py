"""The experiment's tasks carry the one session configuration; the graph runs it unchanged."""

import dataclasses
import pathlib

from hrc_bringup import experiment, session_args
from hrc_bringup.experiment_task import graph_arguments
from hrc_common.cases import paper_case_ids
from hrc_common.session_plan import SessionSettings


def test_each_task_is_a_session_configuration(tmp_path):
    options = experiment.parse_args(['--cases', '2', '5', '--seeds', '2', '--episodes', '7',
                                     '--eval-episodes', '1', '--profiles', 'novice',
                                     '--set', 'sim.episode_duration=4.0'])
    tasks = experiment.plan_tasks(options, tmp_path / 'bags', tmp_path / 'runs')
    assert [(task.settings.case, task.settings.seed) for task in tasks] == \
        [(2, 0), (5, 0), (2, 1), (5, 1)]
    settings = tasks[3].settings
    assert settings == SessionSettings(
        case=5, seed=1, human_profile='novice', session_id='case5-seed1',
        bags_dir=str((tmp_path / 'bags').resolve()),
        runs_dir=str((tmp_path / 'runs').resolve() / 'case5-seed1'), training_episodes=7,
        evaluation_episodes=1, overrides={'human.person': 1, 'sim.episode_duration': 4.0})
    assert settings.check() == []
    assert tasks[3].sweep_runs_dir == (tmp_path / 'runs').resolve()
    # the default cases: the paper's, from params/cases.yaml
    default = experiment.parse_args([])
    assert tuple(default.cases) == paper_case_ids() == (1, 2, 3, 4, 5, 6)


def test_the_graph_session_parses_back_into_the_same_settings(tmp_path):
    """What ``hrc experiment --engine graph`` passes to ``hrc session`` loses nothing."""
    settings = SessionSettings(
        case=7, seed=3, human_profile='skilled', session_id='case7-seed3-skilled',
        bags_dir=str(tmp_path / 'bags'), runs_dir=str(tmp_path / 'runs' / 'x'),
        training_episodes=12, evaluation_episodes=0, resume_from=str(tmp_path / 'a b.pt'),
        overrides={'human.person': 3, 'sim.episode_duration': 4.0, 'agent.learning_rate': 3e-4,
                   'sim.expected_actors': ['robot', 'human'], 'agent.preset': 'graded',
                   'agent.task_tree_file': str(tmp_path / 'tree: easy.yaml')})
    parsed, options = session_args.parse_args(graph_arguments(settings, str(tmp_path), 41))
    assert parsed == settings
    assert options.domain_id == 41 and not options.report
    assert pathlib.Path(options.params_dir) == tmp_path
    # a task without profile, resume or budgets passes none (the files' values hold)
    bare = dataclasses.replace(settings, human_profile='', resume_from='', training_episodes=0,
                               evaluation_episodes=-1, overrides={})
    arguments = graph_arguments(bare, str(tmp_path), 41)
    assert not {'--profile', '--resume-from', '--episodes', '--eval-episodes', '--set'} \
        & set(arguments)
    assert session_args.parse_args(arguments)[0] == bare
