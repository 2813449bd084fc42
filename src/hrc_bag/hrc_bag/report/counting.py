"""The paper's way of counting beside the study's strict rule, floors and a unit-free error. Pure.

The study's rule (:mod:`hrc_agent_node.strategies`) judges convergence on deterministic judging
episodes and counts them; the paper has no judging episodes and trained in MATLAB, whose
``rlTrainingOptions`` stops on an average of the training returns. This module is a *view* of
the same sessions (no second learner): what the paper would have counted on the same
trajectories.

* **The paper's counting**: training episodes only (judging, practice and the final evaluation
  left out); the person's episodes are the human-involved training episodes.
* **A stop in the paper's style** (MATLAB's ``StopTrainingCriteria="AverageReward"``): training
  ends at the first training episode of the strategy's last step at which the mean of the last
  :data:`STOP_WINDOW` training returns of that step reaches :data:`STOP_FRACTION` of the
  maximum return (every reward component of the step at its peak for every control step of the
  episode). Applied to the last step only: there the stop ends training, so the trajectory up to
  it is the one the session ran; an earlier stop in an earlier step would have changed every
  episode after it. The view cannot stop later than the session did: a session whose window
  never reached the fraction is censored at its own count.
  Both numbers were fixed before any result was computed with them. The window is MATLAB's
  default ``ScoreAveragingWindowLength`` (5); the paper gives none. Neither the paper nor MATLAB
  gives a fraction (``StopTrainingValue`` is an absolute return set per problem), so 0.95 is a
  modelling choice: a team that keeps 95% of the peak reward on average.
* **Episodes before the bags** (partners first, cases 7 and 8): the robot-alone and population
  steps run in process before the person's session and the session resumes their checkpoint,
  whose episode counter continues; the first recorded episode index is their count.
* **Floors** (:func:`case_floors`): the fewest episodes the strict rule lets a case take, per
  step ``strategies.episode_floor`` (T + W; W for a ``judge_first`` step); a comparison of two
  cases' counts is also made on the counts above each case's floor.
* **The unit-free error** (:func:`tolerance_error`): each subtask's error over its tolerance
  (``params/task_tree.yaml``), summed; 1 = one subtask at its tolerance. The paper's total sums
  metres and radians; a finding should not hinge on that choice.
"""

import functools
import math

from hrc_common import bounded_yaml
from hrc_common.cases import cases_file_path
from hrc_common.paths import params_file

STOP_WINDOW = 5          # episodes: MATLAB rlTrainingOptions' default ScoreAveragingWindowLength
STOP_FRACTION = 0.95     # of the maximum return: a modelling choice (see the module doc)
SUBTASK_ERRORS = {'slider': 'slider_error', 'pendulum': 'pendulum_error', 'ball': 'ball_error'}
# The agent's defaults (params/agent.yaml) for sessions whose config does not record them.
DEFAULT_WINDOWS = {'convergence_window': 3, 'satisfied_window': 3, 'judging_interval': 0}


@functools.lru_cache(maxsize=None)
def _task_tree() -> dict:
    path = params_file('task_tree.yaml')
    with open(path, 'rb') as stream:
        return bounded_yaml.load(stream.read(), str(path))


@functools.lru_cache(maxsize=None)
def _strategies() -> dict:
    with open(cases_file_path(), 'rb') as stream:
        return bounded_yaml.load(stream.read(), cases_file_path())['strategies']


def tolerances() -> dict:
    """Return {subtask: tolerance} of the task tree (m or rad)."""
    return {entry['id']: float(entry['tolerance']) for entry in _task_tree()['subtasks']}


def tolerance_error(errors: dict) -> float:
    """Return sum of error / tolerance over the subtasks; ``errors``: {error key: value}."""
    limits = tolerances()
    return sum(errors[key] / limits[subtask] for subtask, key in SUBTASK_ERRORS.items())


def reward_peaks(preset: str) -> dict:
    """Return {subtask: peak of its reward component} = alpha / (sigma sqrt(2 pi))."""
    tree = _task_tree()
    shapes = tree['reward_presets'][preset or tree.get('default_preset', 'paper')]['shapes']
    return {subtask: float(shape['alpha']) / (float(shape['sigma']) * math.sqrt(2 * math.pi))
            for subtask, shape in shapes.items()}


def step_reward_peak(strategy: str, step: int, robot_dof: str, preset: str) -> float:
    """Return the largest reward of one control step in a training step of a strategy.

    NaN when the cases file has no such step (a session of another cases file or preset).
    """
    steps = _strategies().get(strategy, {}).get('steps', [])
    try:
        peaks = reward_peaks(preset)
        return sum(peaks[_resolve(name, robot_dof)] for name in steps[step]['robot_subtasks'])
    except (IndexError, KeyError):
        return math.nan


def _resolve(name: str, robot_dof: str) -> str:
    """Return the subtask id of a selector ('direct:robot' / 'direct:human') or the id."""
    if not name.startswith('direct:'):
        return name
    actor_dof = robot_dof if name == 'direct:robot' else (
        'rotation' if robot_dof == 'translation' else 'translation')
    return 'slider' if actor_dof == 'translation' else 'pendulum'


def agent_setting(session, name: str, default=None):
    """Return an agent parameter of a session (its recorded value, else ``default``).

    Looked up in the session's recorded agent parameters, then its learning configuration's
    settings; the windows default to :data:`DEFAULT_WINDOWS` (the agent's defaults).
    """
    fallback = DEFAULT_WINDOWS.get(name, default)
    value = session.extra.get('agent', {}).get(name, session.learning_settings.get(name))
    return fallback if value is None or isinstance(value, bool) else value


def case_floors(session) -> tuple:
    """Return (the person's floor, the whole floor): the fewest episodes the strict rule allows.

    Per step (``strategies.episode_floor``): T + W (W: the step's window, T: training episodes
    per judging run, ``judging_interval`` or 1); a ``judge_first`` step: W. The person's floor
    sums the steps in which the session's person acts (not a population step).
    """
    trigger = max(1, int(agent_setting(session, 'judging_interval')))
    person, whole = 0, 0
    if session.strategy not in _strategies():
        return math.nan, math.nan
    for step in _strategies()[session.strategy]['steps']:
        window = int(agent_setting(session, 'convergence_window' if step['advance'] ==
                                   'converged' else 'satisfied_window'))
        floor = window if step.get('judge_first') else trigger + window
        whole += floor
        if step['human_involved'] and step.get('partner', 'person') == 'person':
            person += floor
    return person, whole


def episodes_before(session) -> int:
    """Return the episodes the agent ran before the session's first recorded one (pre-training)."""
    return min((episode.episode for episode in session.episodes), default=0)


def window_stop(session, training_episodes) -> int:
    """Return the 1-based count of training episodes of the last step at the paper-style stop.

    ``training_episodes``: the session's training-kind episodes in order. 0: the window never
    reached the fraction before the session ended (or episode lengths are not recorded).
    """
    last_step = session.steps - 1
    peak = step_reward_peak(session.strategy, last_step, session.robot_dof,
                            str(agent_setting(session, 'preset', 'paper')))
    fractions = []
    for episode in training_episodes:
        if episode.training_step != last_step:
            continue
        if episode.steps <= 0 or not peak > 0:
            return 0
        fractions.append(episode.episode_return / (peak * episode.steps))
        if len(fractions) >= STOP_WINDOW and \
                sum(fractions[-STOP_WINDOW:]) / STOP_WINDOW >= STOP_FRACTION:
            return len(fractions)
    return 0


def paper_counts(session, kinds) -> dict:
    """Return the paper's counts of a session (``kinds``: each episode's kind, in order).

    Keys: paper_person_episodes and paper_episodes (training episodes only: human-involved,
    all), window_stopped (bool), window_person_episodes and window_episodes (the counts at the
    paper-style stop; the session's own counts when it never stopped: censored). NaN when the
    summaries do not say their kind (judging episodes cannot be told apart).
    """
    if not any(kind != '' for kind in kinds):
        return {key: math.nan for key in ('paper_person_episodes', 'paper_episodes',
                                          'window_person_episodes', 'window_episodes')} | {
            'window_stopped': False}
    training = [episode for episode, kind in zip(session.episodes, kinds) if kind == 'training']
    before = episodes_before(session)
    person = sum(1 for episode in training if episode.human_involved)
    values = {'paper_person_episodes': float(person),
              'paper_episodes': float(len(training) + before)}
    stop = window_stop(session, training)
    values['window_stopped'] = stop > 0
    if stop:
        last_step = session.steps - 1
        earlier = [episode for episode in training if episode.training_step != last_step]
        in_last = [episode for episode in training if episode.training_step == last_step][:stop]
        values['window_episodes'] = float(before + len(earlier) + stop)
        values['window_person_episodes'] = float(sum(
            1 for episode in earlier + in_last if episode.human_involved))
    else:
        values['window_episodes'] = values['paper_episodes']
        values['window_person_episodes'] = values['paper_person_episodes']
    return values
