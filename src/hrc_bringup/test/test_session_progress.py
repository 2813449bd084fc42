"""The runner's progress lines: what each episode was for, and the verdict when training ends."""

from hrc_bringup.session_progress import episode_label, Progress
from hrc_msgs.msg import EpisodeSummary, SessionStatus
import rclpy
from rclpy.context import Context


def test_a_judging_episode_is_not_called_training():
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_JUDGING)) == 'judging'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_TRAINING)) == 'training'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_PRACTICE)) == 'practice'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_EVALUATION,
                                        evaluation=True)) == 'evaluation'
    # a summary without a kind (older bags replayed): the evaluation flag decides
    assert episode_label(EpisodeSummary(evaluation=True)) == 'evaluation'
    assert episode_label(EpisodeSummary()) == 'training'


def test_the_verdict_waits_for_the_episodes_when_the_status_comes_first(capsys):
    """The verdict names the step trained in even when the status came before the summaries.

    Under load the status that ends training can be handed over before the last summaries (two
    topics; a runner that joined late gets both as history): the 'did not converge' line said
    step 2 of 2 there before the fix (test_live_session failed so on a fresh clone).
    """
    context = Context()
    rclpy.init(context=context)
    try:
        progress = Progress(context, interactive=False, max_training_episodes=2)
        ended = SessionStatus(case_id=2, strategy='responsibility_guided', training_step=1,
                              training_step_count=2, total_episodes=2, human_involved=True,
                              phase=SessionStatus.PHASE_EVALUATION, human_subtasks=['ball'])
        progress._on_status(ended)                    # first: no training summary seen yet
        assert 'did not converge' not in capsys.readouterr().out
        for episode in (0, 1):
            progress._on_episode(EpisodeSummary(case_id=2, episode=episode, training_step=0,
                                                kind=EpisodeSummary.KIND_TRAINING))
        out = capsys.readouterr().out
        assert ('[session] the robot did not converge in 2 episodes (training step 1 of 2, at '
                'most 2); the person never trained with the robot; the test episodes start'
                in out), out
        assert out.index('episode   1') < out.index('did not converge')
        progress.close()
    finally:
        rclpy.shutdown(context=context)


def test_a_runner_that_first_sees_the_session_done_still_says_the_test_episodes_follow(capsys):
    """A late runner's first status says 'done'; the test episodes still followed training.

    The agent keeps only the newest status, so a runner that joined late may get 'done' first;
    the session still ran its test episodes after training, so the verdict says so
    (test_live_session failed so in CI at c7c4283: the suffix was missing).
    """
    context = Context()
    rclpy.init(context=context)
    try:
        for evaluation_episodes, suffix in ((1, True), (0, False)):
            progress = Progress(context, interactive=False, max_training_episodes=2,
                                evaluation_episodes=evaluation_episodes)
            done = SessionStatus(case_id=2, strategy='responsibility_guided', training_step=1,
                                 training_step_count=2, total_episodes=2, human_involved=True,
                                 phase=SessionStatus.PHASE_DONE, human_subtasks=['ball'])
            progress._on_status(done)
            for episode in (0, 1):
                progress._on_episode(EpisodeSummary(case_id=2, episode=episode, training_step=0,
                                                    kind=EpisodeSummary.KIND_TRAINING))
            out = capsys.readouterr().out
            verdict = ('[session] the robot did not converge in 2 episodes (training step 1 of '
                       '2, at most 2); the person never trained with the robot')
            assert verdict in out, out
            assert ('; the test episodes start' in out) == suffix, out
            progress.close()
    finally:
        rclpy.shutdown(context=context)
