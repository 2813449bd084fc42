"""The display's pure core: words, numbering, the scene's box, console data, valid JSON.

The words for the person in each situation, the numbering that agrees everywhere, the box of
the whole reachable configuration, the console's data and the documents the pages get.
"""

import json
import math

from hrc_live.display_core import (AgentPlan, DisplayModel, HumanView, ResultView, SessionView,
                                   StateView)
from hrc_live.display_documents import (configuration_points, console_document, scene_bounds,
                                        state_document, status_document)
from hrc_common.session_control import STOPPED_FOR_INPUT
from hrc_live.display_words import INPUT_LOST_BANNER, INPUT_LOST_NOTICE, overlay
from hrc_sim_node.physics import PhysicsParams
import pytest

WIDTH, HEIGHT = 800, 480
PLAN = AgentPlan(max_training_episodes=30, evaluation_episodes=2, episode_break=4.0)


def session(**changes):
    values = dict(session_id='case1-seed0-t', case_id=1, strategy='responsibility_guided',
                  training_step=1, training_step_count=2, human_dof='rotation',
                  human_involved=True, human_subtasks=('pendulum', 'ball'), episode=6,
                  total_episodes=6, human_involved_episodes=2, phase='training')
    values.update(changes)
    return SessionView(**values)


def model_in_episode(state=StateView(6, 12, 0.04, 0.15, 0.1, False), **session_changes):
    model = DisplayModel()
    model.set_plan(PLAN)
    model.on_session(session(**session_changes), now=0.0)
    model.on_state(StateView(state.episode, 0, 0.0, 0.0, 0.0, False), now=1.0)
    model.on_state(state, now=3.4)
    return model


def test_the_person_is_told_their_task_and_their_control_during_an_episode():
    words = overlay(model_in_episode().snapshot(now=3.5))
    assert words.tone == 'act'
    assert words.banner == ('Your turn: keep the pendulum level and keep the ball in the '
                            'middle of the pendulum')
    assert words.lines[0] == 'Round 7 of at most 30' == words.episode_label
    assert 'Part 2 of 2' in words.lines
    assert 'You tilt the pendulum (stick up = right end up).' in words.lines
    # 12 of 200 steps done at 0.2 s each: 37.6 s left, shown whole.
    assert 'Time left: 38 s' in words.lines
    assert words.result == () and words.countdown is None


def test_the_robot_learning_alone_asks_the_person_to_wait():
    words = overlay(model_in_episode(human_involved=False, human_subtasks=(),
                                     training_step=0).snapshot(now=3.5))
    assert words.banner == 'The robot is practising alone: please wait'
    assert words.tone == 'wait'
    assert 'The robot works alone in this part.' in words.lines
    assert not any(line.startswith('You ') for line in words.lines)


def test_the_console_says_the_human_sends_nothing_while_the_robot_learns_alone():
    """No HumanAction comes then; the console says why, not "no command yet"."""
    model = model_in_episode(human_involved=False, human_subtasks=(), training_step=0)
    model.on_human(HumanView('sim', 'paper', True, 0.3, received=0.5))   # an earlier step's
    document = console_document(model.snapshot(now=3.5))
    assert document['input']['source'] == 'none' and not document['input']['healthy']
    assert document['input']['detail'].startswith('not involved in this training step')


def test_after_an_episode_the_result_and_a_countdown_to_the_next_one():
    model = model_in_episode()
    model.on_result(ResultView(5, False, True, 0.02, 0.10, 0.05, 0.17, False), now=0.5)
    model.on_state(StateView(6, 200, 0.01, -0.05, 0.03, True), now=10.0)
    model.on_result(ResultView(6, False, True, 0.01, 0.08, 0.03, 0.12, True), now=10.1)
    model.on_session(session(episode=7, total_episodes=7, human_involved_episodes=3), now=10.2)
    words = overlay(model.snapshot(now=11.5))
    assert words.countdown == 3  # the break of 4 s began at 10.0
    assert words.banner == 'Get ready: the next round starts in 3 s'
    assert words.lines[0] == 'Round 8 of at most 30'
    assert words.result[0] == 'Round 7 done'
    assert words.result[1] == 'ball off centre: 3.0 cm on average'
    assert words.result[2] == f'pendulum tilt: {math.degrees(0.08):.1f} deg, slider: 1.0 cm'
    assert 'Better than the round before.' in words.result
    assert 'The team reached the goal of this part.' in words.result
    # The break is over: "starting", and the result stays up 5 s into the next episode.
    assert overlay(model.snapshot(now=14.5)).banner == 'The next round is starting'
    model.on_state(StateView(7, 0, 0.0, 0.0, 0.0, False), now=14.6)
    assert overlay(model.snapshot(now=16.0), result_seconds=5.0).result[0] == 'Round 7 done'
    assert overlay(model.snapshot(now=20.0), result_seconds=5.0).result == ()


def test_updating_paused_aborted_done_and_evaluation_words():
    model = model_in_episode()
    model.on_state(StateView(6, 200, 0.0, 0.0, 0.0, True), now=10.0)
    model.on_session(session(phase='updating', total_episodes=7), now=10.1)
    assert overlay(model.snapshot(now=10.2)).banner.startswith('The robot is learning from')
    model.on_session(session(phase='paused', total_episodes=7), now=11.0)
    words = overlay(model.snapshot(now=30.0))
    assert (words.banner, words.tone, words.countdown) == (
        'Paused by the operator: please wait', 'wait', None)
    # Resumed: the agent waits a whole break again before the next episode.
    model.on_session(session(phase='training', total_episodes=7), now=40.0)
    assert overlay(model.snapshot(now=40.5)).countdown == 4
    model.on_session(session(phase='aborted', total_episodes=7), now=41.0)
    assert overlay(model.snapshot(now=41.1)).tone == 'stop'
    model.on_session(session(phase='done', total_episodes=7), now=42.0)
    words = overlay(model.snapshot(now=42.1))
    assert words.banner == 'The session is finished. Thank you!'
    assert words.episode_label == '7 rounds done'
    model.on_session(session(phase='evaluation', episode=8, total_episodes=7), now=43.0)
    assert overlay(model.snapshot(now=43.1)).episode_label == 'Test round 2 of 2'


def test_without_session_or_plan_the_display_still_says_something_sensible():
    model = DisplayModel()
    words = overlay(model.snapshot(now=0.0))
    assert words.banner == 'Please wait: the session is starting'
    model.on_session(session(), now=0.0)
    assert overlay(model.snapshot(now=0.0)).episode_label == 'Round 7'  # no "of y" yet
    # A new session id forgets the old agent's plan.
    model.set_plan(PLAN)
    model.on_session(session(session_id='other'), now=1.0)
    assert model.plan is None


def test_numbering_agrees_between_the_label_and_the_result_in_evaluation():
    # 10 training episodes (0..9); test episodes are 10, 11, 12 of 3.
    plan = AgentPlan(max_training_episodes=30, evaluation_episodes=3, episode_break=2.0)
    model = DisplayModel()
    model.set_plan(plan)
    model.on_session(session(phase='evaluation', episode=12, total_episodes=10,
                             human_involved_episodes=10), now=0.0)
    for episode in (10, 11):
        model.on_result(ResultView(episode, True, True, 0.01, 0.05, 0.02, 0.08, False),
                        now=1.0)
    model.on_state(StateView(11, 200, 0.0, 0.0, 0.0, True), now=1.0)
    words = overlay(model.snapshot(now=1.5))
    assert words.episode_label == 'Test round 3 of 3'
    assert words.result[0] == 'Test round 2 done'
    # The person played 10 training and 2 test episodes so far.
    assert 'Rounds you played so far: 12' in words.lines


def test_the_robot_practising_alone_is_told_and_the_first_episode_is_counted_down():
    model = DisplayModel()
    model.set_plan(PLAN)
    model.on_session(session(human_involved=False, human_subtasks=(), training_step=0,
                             episode=0, total_episodes=0, human_involved_episodes=0), now=0.0)
    model.on_session(session(human_involved=False, human_subtasks=(), training_step=0,
                             episode=50, total_episodes=50, human_involved_episodes=0), now=20.0)
    words = overlay(model.snapshot(now=20.0))
    assert 'The robot is practising alone: 50 rounds in 20 s.' in words.lines
    assert words.banner == 'The robot is practising alone: please wait'
    # The last lonely episode ends at 39.6 s; the person joins with a 4 s break.
    model.on_state(StateView(107, 200, 0.0, 0.0, 0.0, True), now=39.6)
    model.on_session(session(episode=108, total_episodes=108, human_involved_episodes=0),
                     now=40.0)
    words = overlay(model.snapshot(now=40.1))
    assert 'The robot practised alone: 108 rounds in 40 s.' in words.lines
    assert words.banner == 'Get ready: your first round starts in 4 s'
    assert words.countdown == 4


def test_the_whole_reachable_configuration_is_inside_the_scene_box():
    physics = PhysicsParams()
    box = scene_bounds(physics)
    for slider in (-0.1, 0.0, 0.1):
        for angle in (-math.pi / 2, -1.0, -0.3, 0.0, 0.7, math.pi / 2):
            for ball in (-0.25, 0.0, 0.25):
                for y, z in configuration_points(physics, slider, angle, ball):
                    assert box['y_min'] < y < box['y_max'] and box['z_min'] < z < box['z_max']
    # Not padded beyond the 3 cm margin: the top is the ball at the beam's end near +90 deg
    # (slider 0.1 m up, the ball's centre 0.5 m along and 0.025 m above the beam, radius 0.02).
    assert box['z_max'] == pytest.approx(0.1 + math.hypot(0.5, 0.025) + 0.02 + 0.03, abs=1e-3)


def test_a_non_finite_state_gives_a_notice_and_valid_json():
    model = model_in_episode()
    model.on_state(StateView(6, 13, float('nan'), 0.0, float('inf'), False), now=4.0)
    snapshot = model.snapshot(now=4.1)
    words = overlay(snapshot)
    assert 'invalid state' in words.notice
    assert snapshot.state.step == 12  # the last good state stays
    json.dumps(status_document(snapshot, words), allow_nan=False)
    document = state_document(StateView(6, 13, float('nan'), 0.0, 0.0, False), 1.0)
    assert document == {'valid': False, 'episode': 6, 'step': 13, 'sent_ms': 1.0}
    model.on_state(StateView(6, 14, 0.0, 0.0, 0.0, False), now=4.2)
    assert overlay(model.snapshot(now=4.3)).notice == ''


def test_console_reports_input_health_errors_and_totals():
    model = model_in_episode()
    model.on_state(StateView(6, 13, -0.02, 0.1, 0.04, False, human_command_missing=True),
                   now=3.6)
    model.on_human(HumanView('device', '/dev/input/js0', True, 0.3, received=3.0))
    document = console_document(model.snapshot(now=3.5))
    assert document['input']['source'] == 'device' and document['input']['healthy']
    # Three states of episode 6: |S_x| 0, 0.04, 0.02 -> mean 0.02 m.
    assert document['episode']['steps'] == 3
    assert document['episode']['slider_error_m'] == pytest.approx(0.02)
    assert document['episode']['human_missing'] == 1
    assert document['totals']['training_episodes'] == 6
    stale = console_document(model.snapshot(now=4.5))
    assert stale['input']['age_s'] == 1.5 and not stale['input']['healthy']
    model.set_input_lost('/dev/input/js0 unplugged')
    snapshot = model.snapshot(now=3.5)
    assert not console_document(snapshot)['input']['healthy']
    words = overlay(snapshot)
    assert words.tone == 'stop' and words.banner.startswith('The joystick is disconnected')


# --------------------------------------------------------------------------- a lost joystick
def test_an_unplug_mid_episode_then_a_resume_the_person_reads_one_clear_message_each():
    model = model_in_episode()                        # episode 6 at step 12, the person acts
    # The runner stops the agent for the lost joystick: the agent says "aborted" first.
    model.set_input_lost('joystick disconnected (zero held, session should pause): no writer '
                         'has the FIFO open')
    model.on_session(session(phase='aborted'), now=4.0)
    words = overlay(model.snapshot(now=4.1))
    assert (words.banner, words.tone, words.notice) == (INPUT_LOST_BANNER, 'stop',
                                                        INPUT_LOST_NOTICE)
    assert 'FIFO' not in words.notice and 'operator' not in words.banner.split(':')[0]
    assert console_document(model.snapshot(now=4.1))['input']['detail'].endswith(
        'no writer has the FIFO open')              # the technical reason: the console only
    runner_says = ('joystick disconnected (zero held, session should pause): no writer has '
                   'the FIFO open: paused; resume after it is back')   # the agent's hold
    model.on_session(session(phase='paused', message=runner_says), now=4.5)
    assert overlay(model.snapshot(now=5.0)).banner == INPUT_LOST_BANNER
    # Plugged in again: the operator resumes (not "paused by the operator": it was not).
    model.set_input_lost('')
    assert overlay(model.snapshot(now=6.0)).banner == (
        'The joystick is connected again: please wait for the operator')
    # Resumed (the agent holds in its process): the interrupted episode starts again after a
    # break, counted down, although the newest state is still its step 12.
    model.on_session(session(phase='training'), now=20.0)
    words = overlay(model.snapshot(now=21.2))
    assert (words.banner, words.countdown, words.notice) == (
        'Get ready: the next round starts in 3 s', 3, '')
    assert not any(line.startswith('Time left') for line in words.lines)
    model.on_state(StateView(6, 0, 0.0, 0.0, 0.0, False), now=24.0)   # the re-run starts
    assert overlay(model.snapshot(now=24.1)).banner.startswith('Your turn')


def test_a_lost_joystick_is_told_whichever_of_the_runners_two_words_comes_first():
    """The agent's aborted status for a lost joystick says so itself.

    The runner says the loss on /hrc/session/input_lost and has the agent abort: two topics
    from two processes. Before, an aborted status that came first read "Stopped by the
    operator" until the other topic's message arrived.
    """
    model = model_in_episode()
    model.on_session(session(phase='aborted', message=f'aborted: {STOPPED_FOR_INPUT} in '
                             'episode 7 at step 12 (dropped, not learned from)'), now=4.0)
    assert model.snapshot(now=4.0).input_lost == ''          # the runner's word is not here yet
    words = overlay(model.snapshot(now=4.1))
    assert (words.banner, words.tone) == (INPUT_LOST_BANNER, 'stop')
    # an operator's abort is still one
    model = model_in_episode()
    model.on_session(session(phase='aborted', message='aborted: by the operator in episode 7'),
                     now=4.0)
    assert overlay(model.snapshot(now=4.1)).banner.startswith('Stopped by the operator')


def test_every_resume_counts_down_the_next_episode():
    model = model_in_episode()
    model.on_state(StateView(6, 200, 0.0, 0.0, 0.0, True), now=10.0)
    for pause, resume in ((11.0, 30.0), (40.0, 50.0)):
        model.on_session(session(phase='paused', total_episodes=7, episode=7), now=pause)
        model.on_session(session(phase='training', total_episodes=7, episode=7), now=resume)
        words = overlay(model.snapshot(now=resume + 0.5))
        assert words.banner == 'Get ready: the next round starts in 4 s', resume


def test_episode_counters_never_exceed_their_maximum():
    model = DisplayModel()
    model.set_plan(PLAN)                            # at most 30 training, 2 test episodes
    model.on_session(session(phase='aborted', episode=30, total_episodes=30), now=0.0)
    assert overlay(model.snapshot(now=0.1)).episode_label == 'Round 30 of at most 30'
    model.on_session(session(phase='evaluation', episode=33, total_episodes=30), now=1.0)
    assert overlay(model.snapshot(now=1.1)).episode_label == 'Test round 2 of 2'


def alone_status(done, phase='training'):
    return session(human_involved=False, human_subtasks=(), training_step=0, episode=done,
                   total_episodes=done, human_involved_episodes=0, phase=phase)


def test_the_robots_lonely_count_survives_a_pause_and_the_wait_is_estimated():
    model = DisplayModel()
    model.set_plan(AgentPlan(max_training_episodes=100, evaluation_episodes=2,
                             episode_break=4.0))
    model.on_session(alone_status(0), now=0.0)
    model.on_session(alone_status(20), now=10.0)
    model.on_session(alone_status(20, 'paused'), now=10.0)           # 20 s of pause
    model.on_session(alone_status(20), now=30.0)
    model.on_session(alone_status(40), now=40.0)
    words = overlay(model.snapshot(now=40.0))
    # 40 episodes in 20 s of practice (not 20 episodes: the count goes on after the pause);
    # 60 episodes left under the cap at 0.5 s each: at most about 30 s.
    assert 'The robot is practising alone: 40 rounds in 20 s.' in words.lines
    assert 'You join in at most about 30 s (the robot may be ready sooner).' in words.lines
    assert words.banner == 'The robot is practising alone: please wait'
    console = console_document(model.snapshot(now=40.0))
    assert console['milestone'] == ('The robot is practising alone: 40 episodes in 20 s; the '
                                    'person joins in at most about 30 s')
    # The person joins: the console says so, with the numbers.
    model.on_session(session(episode=41, total_episodes=41, human_involved_episodes=0),
                     now=41.0)
    assert console_document(model.snapshot(now=42.0))['milestone'] == (
        'the person joins now, at episode 42 (the robot practised alone: 41 episodes in 21 s)')


def test_the_console_says_when_the_robot_did_not_converge():
    model = DisplayModel()
    model.set_plan(AgentPlan(max_training_episodes=60, evaluation_episodes=5,
                             episode_break=4.0))
    model.on_session(alone_status(59), now=0.0)
    model.on_result(ResultView(59, False, False, 0.05, 0.3, 0.1, 0.45, False), now=1.0)
    model.on_session(session(phase='evaluation', episode=60, total_episodes=60,
                             human_involved_episodes=0, human_subtasks=('slider', 'ball')),
                     now=1.1)
    assert console_document(model.snapshot(now=1.2))['milestone'] == (
        'the robot did not converge in 60 episodes (at most 60); the person never trained '
        'with it')


def test_practice_is_labelled_as_practice_on_the_page_and_the_console():
    model = DisplayModel()
    model.set_plan(PLAN)
    model.on_session(session(strategy='practice', training_step=0, training_step_count=1,
                             episode=1, total_episodes=1, human_involved_episodes=1,
                             message='practice: episode 2 of 3, the person alone (the robot '
                                     'does not act)'), now=0.0)
    snapshot = model.snapshot(now=0.5)
    assert overlay(snapshot).episode_label == 'Practice round 2 of 3'
    console = console_document(snapshot)
    assert console['practice'] is True and console['milestone'] == '' and console['alone'] == ''
    model.on_session(session(strategy='practice', training_step=0, training_step_count=1,
                             episode=3, total_episodes=3, human_involved_episodes=3,
                             message='practice: episode 3 of 3, the person alone'), now=1.0)
    assert overlay(model.snapshot(now=1.1)).episode_label == 'Practice: 3 rounds done'
