"""The practice phase the agent runs (hrc_agent_node.practice): pure, hand-made states."""

import types

from hrc_agent_node.practice import practice_subtask, PracticeRun
from hrc_common.contract import DOF_INDEX, EpisodeKind, Phase
from hrc_msgs.msg import EpisodeSummary, SessionStatus
import pytest


def state(episode, step, final=False, slider=0.0, angle=0.0, ball=0.0):
    return types.SimpleNamespace(episode=episode, step=step, truncated=final, terminated=False,
                                 slider_position=slider, pendulum_angle=angle,
                                 ball_position=ball)


def error(subtask, reached):
    """|x - 0| of the subtask's variable (the paper preset's mu is 0)."""
    return abs({'slider': reached.slider_position, 'pendulum': reached.pendulum_angle,
                'ball': reached.ball_position}[subtask])


def practice(episodes=2, human_dof='translation'):
    robot_dof = 'rotation' if human_dof == 'translation' else 'translation'
    return PracticeRun(episodes, 'case2-practice', 2, robot_dof, human_dof, error)


def test_the_status_is_the_one_the_session_runner_published():
    run = practice()
    status = SessionStatus(**run.status())   # every field is a SessionStatus field
    assert (status.session_id, status.case_id, status.strategy, status.training_step,
            status.training_step_count) == ('case2-practice', 2, 'practice', 0, 1)
    assert (status.robot_dof, status.human_dof) == (DOF_INDEX['rotation'],
                                                     DOF_INDEX['translation'])
    assert status.human_involved and list(status.human_subtasks) == ['slider']
    assert not list(status.robot_subtasks)
    assert (status.episode, status.total_episodes, status.human_involved_episodes) == (0, 0, 0)
    assert status.phase == Phase.TRAINING
    assert status.message == ('practice: episode 1 of 2, the person alone (the robot does '
                              'not act)')
    assert practice_subtask('rotation') == 'pendulum'


def test_each_episode_is_reset_in_realtime_and_summarized_as_practice():
    run = practice()
    reset = run.start_episode()
    assert (reset.seed, reset.episode, reset.clock_mode) == (-1, 0, 'realtime')
    assert run.on_state(state(0, 0, slider=9.0)) is None      # step 0: not a state reached
    assert run.on_state(state(0, 1, slider=0.2, angle=-0.1)) is None
    assert run.on_state(state(0, 1, slider=5.0)) is None      # seen before: ignored
    assert run.on_state(state(1, 2, final=True)) is None      # another episode: ignored
    fields = run.on_state(state(0, 2, final=True, slider=0.4, ball=0.02))
    summary = EpisodeSummary(**fields)
    assert summary.kind == EpisodeKind.PRACTICE == EpisodeSummary.KIND_PRACTICE
    assert (summary.episode, summary.steps, summary.truncated, summary.human_involved,
            summary.evaluation, summary.converged) == (0, 2, True, True, False, False)
    assert summary.slider_error == pytest.approx(0.3)
    assert summary.pendulum_error == pytest.approx(0.05)
    assert summary.ball_error == pytest.approx(0.01)
    assert summary.total_error == pytest.approx(0.36)
    assert summary.episode_return == 0.0 and summary.robot_effort == 0.0
    assert run.status()['episode'] == 1 and not run.finished
    assert 'episode 2 of 2' in run.status()['message']
    assert run.start_episode().episode == 1
    assert run.on_state(state(1, 1, final=True)) is not None
    assert run.finished and run.status()['total_episodes'] == 2
    assert 'episode 2 of 2' in run.status()['message']
    with pytest.raises(RuntimeError):
        run.start_episode()


def test_a_practice_needs_an_episode():
    with pytest.raises(ValueError, match='at least one episode'):
        practice(episodes=0)
