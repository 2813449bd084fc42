"""Task tree: loading, the decomposition rules' errors, the reward formula (eq. 2-5), rendering."""

import copy
import math
import types

import pytest
import yaml

from hrc_common.paths import params_dir
from hrc_agent_node.task_tree import RewardShape, TaskTree, TaskTreeError

TREE_FILE = f'{params_dir()}/task_tree.yaml'


def tree_document():
    with open(TREE_FILE) as stream:
        return yaml.safe_load(stream)


def state(slider=0.0, angle=0.0, ball=0.0):
    return types.SimpleNamespace(slider_position=slider, pendulum_angle=angle,
                                 ball_position=ball)


def paper_formula(x, alpha=10.0, sigma=1.0, mu=0.0):
    """Eq. 3-5 written out independently of the code under test."""
    return alpha * (1.0 / (sigma * math.sqrt(2 * math.pi))) \
        * math.exp(-0.5 * ((x - mu) / sigma) ** 2)


def test_repository_tree_is_the_papers():
    tree = TaskTree.from_file(TREE_FILE)
    assert tree.preset == 'paper'
    assert tree.levels == (1, 2)
    assert tree.subtasks_at(1) == ['ball']
    assert tree.subtasks_at(2) == ['slider', 'pendulum']
    assert set(tree.subtasks['ball'].children) == {'slider', 'pendulum'}
    assert tree.leaf_actions('ball') == {'translation', 'rotation'}
    assert tree.direct_subtasks('translation') == ['slider']
    assert tree.direct_subtasks('rotation') == ['pendulum']
    for subtask_id in tree.subtasks:
        assert tree.shapes[subtask_id] == RewardShape(10.0, 1.0, 0.0)


@pytest.mark.parametrize('slider, angle, ball', [
    (0.0, 0.0, 0.0), (0.1, -0.3, 0.25), (-0.05, 1.2, -0.1), (0.02, math.pi / 2, 0.2)])
def test_paper_reward_equals_the_formula(slider, angle, ball):
    tree = TaskTree.from_file(TREE_FILE, 'paper')
    reached = state(slider, angle, ball)
    components, total = tree.reward(reached, ['ball', 'slider', 'pendulum'])
    expected = [paper_formula(ball), paper_formula(slider), paper_formula(angle)]
    assert components == pytest.approx(expected, rel=1e-12)
    assert total == pytest.approx(sum(expected), rel=1e-12)
    # eq. 6: only the level-2 components
    _, level_two = tree.reward(reached, ['slider', 'pendulum'])
    assert level_two == pytest.approx(expected[1] + expected[2], rel=1e-12)


def test_paper_reward_peak_and_flatness():
    tree = TaskTree.from_file(TREE_FILE, 'paper')
    assert tree.peak_reward(['slider']) == pytest.approx(10 / math.sqrt(2 * math.pi))
    # Units: over the slider's whole range the paper's component changes by 0.5 %.
    ratio = tree.component('slider', state(slider=0.1)) / tree.component('slider', state())
    assert ratio == pytest.approx(math.exp(-0.005), rel=1e-12)


def test_tuned_preset_keeps_the_peak_and_is_steep():
    tree = TaskTree.from_file(TREE_FILE, 'tuned')
    for subtask_id, shape in tree.shapes.items():
        assert shape.peak == pytest.approx(10 / math.sqrt(2 * math.pi))
        one_sigma = {'slider': state(slider=shape.sigma), 'pendulum': state(angle=shape.sigma),
                     'ball': state(ball=shape.sigma)}[subtask_id]
        assert tree.component(subtask_id, one_sigma) == pytest.approx(
            paper_formula(shape.sigma, shape.alpha, shape.sigma, shape.mu))
    assert tree.component('ball', state(ball=0.25)) < 0.01 * tree.component('ball', state())


def test_unknown_preset_is_refused():
    with pytest.raises(TaskTreeError, match="unknown reward preset 'fancy'"):
        TaskTree.from_file(TREE_FILE, 'fancy')


def broken(change):
    document = copy.deepcopy(tree_document())
    change(document)
    return document


def subtask(document, subtask_id):
    return next(entry for entry in document['subtasks'] if entry['id'] == subtask_id)


@pytest.mark.parametrize('change, reason', [
    (lambda d: subtask(d, 'ball').update(children=[]),
     "rule 1: subtask 'ball' on level 1 has no lower-level subtask branch"),
    (lambda d: [subtask(d, name).update(actions=[], direct_action='')
                for name in ('slider', 'pendulum')],
     "rule 2: subtask 'slider' does not trace down to any action"),
    (lambda d: subtask(d, 'pendulum').update(id='slider'),
     "id 'slider' is used more than once"),
    (lambda d: d['actions'][0].update(id='slider'), "id 'slider' is used more than once"),
    (lambda d: d.update(executors=['robot', 'dog']), "unknown executors ['dog']"),
    (lambda d: subtask(d, 'slider').update(actions=['teleport']),
     "action 'teleport' is not an action of the tree"),
    (lambda d: subtask(d, 'ball').update(children=['slider', 'wheel']),
     "child 'wheel' is not a subtask"),
    (lambda d: subtask(d, 'slider').update(level=1),
     "child 'slider' must be on a lower-priority level"),
    (lambda d: subtask(d, 'ball').update(state_variable='ball_colour'),
     "state_variable 'ball_colour' is not one of"),
    (lambda d: d['reward_presets']['paper']['shapes']['ball'].update(sigma=0.0),
     'sigma must be positive'),
    (lambda d: d['reward_presets']['paper']['shapes'].pop('pendulum'),
     "no shape for subtasks ['pendulum']"),
    (lambda d: d.update(levels=[1, 3]), 'levels must be 1, 2, ... without gaps'),
    (lambda d: subtask(d, 'slider').update(tolerance=-1),
     'tolerance must be a positive number'),
    (lambda d: subtask(d, 'slider').update(direct_action='rotation', actions=['translation']),
     "direct_action 'rotation' is not among its actions"),
])
def test_decomposition_rule_violations_are_named(change, reason):
    with pytest.raises(TaskTreeError) as error:
        TaskTree.from_dict(broken(change))
    assert reason in str(error.value)


def test_every_problem_is_reported_at_once():
    def change(document):
        document['executors'] = ['alien']
        subtask(document, 'ball')['state_variable'] = 'nothing'
    with pytest.raises(TaskTreeError) as error:
        TaskTree.from_dict(broken(change))
    assert 'alien' in str(error.value) and 'nothing' in str(error.value)


def test_missing_file_and_bad_yaml_are_clear(tmp_path):
    with pytest.raises(TaskTreeError, match='cannot read task tree file'):
        TaskTree.from_file(tmp_path / 'missing.yaml')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('levels: [1, 2\n')
    with pytest.raises(TaskTreeError, match='not valid YAML'):
        TaskTree.from_file(bad)


def test_text_and_png_rendering(tmp_path):
    from hrc_agent_node.tree_figure import draw_tree

    tree = TaskTree.from_file(TREE_FILE)
    text = tree.render_text({'translation': 'robot', 'rotation': 'human'}, ['slider'])
    assert '[L1] ball (T_1^1)' in text
    assert '* [L2] slider' in text and '  [L2] pendulum' in text
    assert 'action translation (direct) <- robot' in text
    png = tmp_path / 'tree.png'
    draw_tree(tree, png)
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert png.stat().st_size > 10000
