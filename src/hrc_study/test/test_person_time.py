"""The person's time a lab budgets: human-involved training episodes x episode duration."""

import math

from hrc_bag.report.paper import paper_person_minutes
from hrc_bag.report.records import EpisodeRecord, measures, SessionRecord
from hrc_bag.report.tables import person_time_markdown
from hrc_study.results_tables import targets


def episode(index, human, evaluation=False, converged=False, kind='training'):
    return EpisodeRecord(episode=index, training_step=1 if human else 0, human_involved=human,
                         evaluation=evaluation, converged=converged, episode_return=0.0,
                         slider_error=0.0, pendulum_error=0.0, ball_error=0.0, total_error=0.0,
                         human_effort=0.0, robot_effort=0.0, final_evaluation=evaluation,
                         kind='evaluation' if evaluation else kind)


def session(seed, alone, with_person, seconds=40.0):
    """Return a case-2 session: robot alone, then the person, converged, 2 evaluation episodes."""
    episodes = [episode(index, False) for index in range(alone)]
    episodes += [episode(alone + index, True, converged=index == with_person - 1)
                 for index in range(with_person)]
    episodes += [episode(alone + with_person + index, True, evaluation=True) for index in range(2)]
    extra = {} if seconds is None else {'episode_seconds': seconds}
    return SessionRecord(session_id=f's{seed}', case_id=2, strategy='responsibility_guided',
                         robot_dof='rotation', seed=seed, profile='paper', episodes=episodes,
                         extra=extra)


def test_the_person_minutes_count_the_persons_training_episodes_at_their_duration():
    values = measures(session(0, alone=10, with_person=9))
    assert values['human_involved_episodes'] == 9
    assert values['person_minutes'] == 9 * 40.0 / 60.0          # evaluation excluded
    assert math.isnan(measures(session(0, 10, 9, seconds=None))['person_minutes'])
    assert paper_person_minutes(2) == 4.0                         # 6 episodes x 40 s


def test_the_table_and_the_target_say_the_ratio_to_the_paper():
    rows = {2: [measures(session(seed, 10, count)) for seed, count in enumerate((6, 9, 12, 15))]}
    table = person_time_markdown(rows)
    # minutes 4, 6, 8, 10: median 7.0 [5.5, 8.5], paper 4.0 -> 1.75x, within 2x
    assert '| 2 | 4 | 7.0 [5.5, 8.5] | 4.0 | 1.75x | yes |' in table
    rows = {2: [measures(session(seed, 10, 15)) for seed in range(3)]}    # 10 min: 2.5x
    row = [target for target in targets(rows, {}) if "person's time" in target[0]][0]
    assert row[1] == 'case 2: 2.50x' and row[2] is False
