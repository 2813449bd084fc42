"""The study's reward preset has a slope where the robot starts: at the stops, on every subtask.

Measured on the real task tree file (params/task_tree.yaml) through TaskTree.component, by a
central difference. The slope is made dimensionless as x * |df/dx| / peak: the share of the
peak a straight climb from the stop at x to the goal at that slope would gain. A Gaussian of
width sigma gives z^2 exp(-z^2 / 2) with z = x / sigma (largest, 0.74, at z = sqrt 2).
"""

import types

import pytest

from hrc_agent_node.config import share_file, TREE_FILE_NAME
from hrc_agent_node.task_tree import TaskTree

# Where the robot starts (the measurements): the beam resting on its stop at 0.4 rad,
# the slider at a rod end (0.1 m), the ball at a beam end (0.25 m).
STOPS = {'pendulum': 0.4, 'slider': 0.1, 'ball': 0.25}
# A climb from the stop at the stop's slope gains at least a quarter of the peak.
SLOPE_FLOOR = 0.25
STUDY_PRESET = 'graded'


def at(subtask_id, value):
    values = dict(ball_position=0.0, pendulum_angle=0.0, slider_position=0.0)
    variable = {'ball': 'ball_position', 'pendulum': 'pendulum_angle',
                'slider': 'slider_position'}[subtask_id]
    values[variable] = value
    return types.SimpleNamespace(**values)


def relative_slope(tree, subtask_id, x):
    """Return x * |df/dx| / peak of one subtask's reward at x (central difference)."""
    h = 1e-6
    slope = (tree.component(subtask_id, at(subtask_id, x + h))
             - tree.component(subtask_id, at(subtask_id, x - h))) / (2 * h)
    return abs(x * slope) / tree.shapes[subtask_id].peak


def tree_of(preset):
    return TaskTree.from_file(share_file(TREE_FILE_NAME), preset)


@pytest.mark.parametrize('subtask_id', sorted(STOPS))
@pytest.mark.parametrize('side', (-1.0, 1.0))
def test_study_preset_slopes_towards_the_goal_at_every_stop(subtask_id, side):
    tree = tree_of(STUDY_PRESET)
    x = side * STOPS[subtask_id]
    assert relative_slope(tree, subtask_id, x) >= SLOPE_FLOOR
    # ... and towards the goal: the reward grows on the way in.
    assert tree.component(subtask_id, at(subtask_id, 0.9 * x)) \
        > tree.component(subtask_id, at(subtask_id, x))


@pytest.mark.parametrize('preset, flat', [('paper', ['ball', 'pendulum', 'slider']),
                                          ('tuned', ['ball', 'pendulum', 'slider'])])
def test_the_earlier_presets_are_nearly_flat_at_the_stops(preset, flat):
    """Why the study's preset exists: the paper's and the earlier tuned preset stay, unchanged."""
    tree = tree_of(preset)
    assert [subtask_id for subtask_id in sorted(STOPS)
            if relative_slope(tree, subtask_id, STOPS[subtask_id]) < SLOPE_FLOOR] == flat
    # tuned: the beam on its stop earns e^-8 of the peak (a slope of 0.005 of it)
    if preset == 'tuned':
        assert relative_slope(tree, 'pendulum', 0.4) < 0.01


def test_the_earlier_presets_keep_their_numbers():
    shapes = {name: {subtask_id: (shape.alpha, shape.sigma, shape.mu)
                     for subtask_id, shape in tree_of(name).shapes.items()}
              for name in ('paper', 'tuned')}
    assert shapes == {
        'paper': {subtask_id: (10.0, 1.0, 0.0) for subtask_id in STOPS},
        'tuned': {'slider': (0.3, 0.03, 0.0), 'pendulum': (1.0, 0.1, 0.0),
                  'ball': (0.8, 0.08, 0.0)}}
