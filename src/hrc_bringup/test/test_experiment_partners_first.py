"""The experiment runner pre-trains a partners-first case before its session (in process).

Tiny: 10-step episodes and a task tree whose tolerances every state meets.
"""

import json

import pytest
import yaml

from hrc_bringup.experiment_task import run_task, SessionTask
from hrc_common.session_plan import parse_overrides, SessionSettings
from hrc_common.paths import params_dir
from hrc_bag.report import load_records


@pytest.mark.slow
def test_a_case_8_task_pretrains_then_runs_the_person_from_the_checkpoint(tmp_path):
    tree = yaml.safe_load((params_dir() / 'task_tree.yaml').read_text())
    for subtask in tree['subtasks']:
        subtask['tolerance'] = 100.0
    easy = tmp_path / 'easy_tree.yaml'
    easy.write_text(yaml.safe_dump(tree))
    settings = SessionSettings(
        case=8, seed=0, session_id='case8-seed0', bags_dir=str(tmp_path / 'bags'),
        runs_dir=str(tmp_path / 'runs' / 'case8-seed0'), training_episodes=30,
        evaluation_episodes=1,
        overrides=parse_overrides(('sim.episode_duration=2.0', 'agent.horizon=20',
                                   'agent.minibatch_size=10', 'agent.convergence_window=1',
                                   f'agent.task_tree_file={easy}', 'human.person=0')))
    task = SessionTask(settings, engine='inprocess', params_dir=str(params_dir()),
                       pull_bags=False)
    outcome = run_task(task)
    assert outcome['exit_code'] == 0, outcome['error']
    record = json.loads((tmp_path / 'runs' / 'case8-seed0' / 'case8-seed0'
                         / 'pretrain.json').read_text())
    assert record['reached_person_step'] and record['person'] == 'person:paper:0'
    assert record['population_episodes'] > 0 and record['person'] not in record['partners_met']
    # the study reads the session: the person's step only, from the pre-trained episode count
    sessions = load_records([tmp_path / 'bags'])
    assert [session.strategy for session in sessions] == ['partners_first']
    episodes = sessions[0].episodes
    assert episodes[0].episode == record['episodes']
    assert {episode.training_step for episode in episodes} == {2}
    assert [episode.kind for episode in episodes] == ['judging', 'evaluation']
