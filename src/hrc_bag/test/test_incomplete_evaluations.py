"""Table II leaves out an evaluation episode in which a command came late, and says how many."""

from hrc_bag.report.records import EpisodeRecord, measures, SessionRecord


def evaluation(index, total, missing=0):
    return EpisodeRecord(episode=index, training_step=0, human_involved=True, evaluation=True,
                         converged=False, episode_return=0.0, slider_error=total / 3,
                         pendulum_error=total / 3, ball_error=total / 3, total_error=total,
                         human_effort=0.01, robot_effort=0.01, kind='evaluation',
                         commands_missing=missing)


def session(episodes):
    training = EpisodeRecord(episode=0, training_step=0, human_involved=True, evaluation=False,
                             converged=True, episode_return=0.0, slider_error=0.0,
                             pendulum_error=0.0, ball_error=0.0, total_error=0.0,
                             human_effort=0.0, robot_effort=0.0, kind='judging')
    return SessionRecord(session_id='s', case_id=5, strategy='learn_together',
                         robot_dof='translation', seed=0, profile='paper',
                         episodes=[training] + episodes)


def test_the_late_episode_is_left_out_when_complete_ones_exist():
    values = measures(session([evaluation(1, 0.9, missing=12), evaluation(2, 0.03),
                               evaluation(3, 0.05)]))
    assert values['total_error'] == 0.04 and values['evaluation_episodes'] == 2
    assert values['incomplete_evaluations'] == 1


def test_only_late_episodes_still_give_a_number_and_say_so():
    values = measures(session([evaluation(1, 0.9, missing=3), evaluation(2, 0.7, missing=1)]))
    assert values['total_error'] == 0.8 and values['incomplete_evaluations'] == 2
