"""Episode kinds (EpisodeSummary.kind) through a bag and the report's loading and measures."""

import types

from hrc_bag import report
from hrc_bag.report.curves import training_returns
from hrc_bag.report.loading import kind_of
from hrc_bag.report.records import measures, record_from_bag_session
from hrc_testing.bag_traffic import record_in_process
from hrc_common.contract import EpisodeKind
from hrc_msgs.msg import EpisodeSummary


def test_episode_kinds_are_recorded_and_read_and_old_bags_infer_them(tmp_path):
    plan = [(0, True, False, EpisodeSummary.KIND_PRACTICE),
            (0, True, False, EpisodeSummary.KIND_TRAINING),
            (0, True, False, EpisodeSummary.KIND_JUDGING),
            (0, True, False, EpisodeSummary.KIND_UNKNOWN),      # as a bag before the field
            (0, True, True, EpisodeSummary.KIND_EVALUATION),
            (0, True, True)]                                   # kind from the flag
    record_in_process(tmp_path, 'kinds', 5, 'learn_together', 0, plan, steps=4)
    session, = report.load_sessions([tmp_path / 'kinds'], log=lambda text: None)
    assert [summary.kind for summary in session.summaries] == [4, 1, 2, 0, 3, 3]
    assert [summary.episode for summary in session.practice] == [0]
    assert [summary.episode for summary in session.training] == [1, 2, 3]   # judging included
    assert [summary.episode for summary in session.evaluation] == [4, 5]
    # a summary decoded from a bag recorded before EpisodeSummary.kind has no such field
    old = types.SimpleNamespace(evaluation=True)
    assert kind_of(old) is EpisodeKind.EVALUATION
    assert kind_of(types.SimpleNamespace(evaluation=False)) is EpisodeKind.TRAINING
    # the records read the kinds: judging apart from training, practice in neither count
    record = record_from_bag_session(session)
    assert [episode.kind for episode in record.episodes] == [
        'practice', 'training', 'judging', '', 'evaluation', 'evaluation']
    values = measures(record)
    assert values['total_episodes'] == 3 and values['practice_episodes'] == 1
    assert values['evaluation_episodes'] == 2
    # Fig. 5's training curve leaves the judging episode out (its return is deterministic)
    assert len(training_returns(record)) == 2
