"""The runner's progress line names what each episode was for (EpisodeSummary.kind)."""

from hrc_bringup.session_progress import episode_label
from hrc_msgs.msg import EpisodeSummary


def test_a_judging_episode_is_not_called_training():
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_JUDGING)) == 'judging'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_TRAINING)) == 'training'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_PRACTICE)) == 'practice'
    assert episode_label(EpisodeSummary(kind=EpisodeSummary.KIND_EVALUATION,
                                        evaluation=True)) == 'evaluation'
    # a summary without a kind (older bags replayed): the evaluation flag decides
    assert episode_label(EpisodeSummary(evaluation=True)) == 'evaluation'
    assert episode_label(EpisodeSummary()) == 'training'
