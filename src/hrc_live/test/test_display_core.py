"""The display's pure core: the words for the person in each situation, and the drawing."""

import io
import math

from hrc_live.display_core import (AgentPlan, BACKGROUND_COLOR, BALL_COLOR, DisplayModel,
                                   layout, overlay, PENDULUM_COLOR, render, render_png,
                                   ResultView, ROD_COLOR, SessionView, SLIDER_COLOR, StateView,
                                   status_document)
from hrc_sim_node.physics import body_poses, PhysicsParams, PhysicsState
from PIL import Image
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


def close_to(pixel, color, tolerance=12):
    return all(abs(int(a) - int(b)) <= tolerance for a, b in zip(pixel, color))


def test_the_person_is_told_their_task_and_their_control_during_an_episode():
    words = overlay(model_in_episode().snapshot(now=3.5))
    assert words.tone == 'act'
    assert words.banner == ('Your turn: keep the pendulum level and keep the ball in the '
                            'middle of the pendulum')
    assert words.lines[0] == 'Episode 7 of at most 30' == words.episode_label
    assert 'Training step 2 of 2' in words.lines
    assert 'You tilt the pendulum (stick up = right end up).' in words.lines
    # 12 of 200 steps done at 0.2 s each: 37.6 s left, shown whole.
    assert 'Time left: 38 s' in words.lines
    assert words.result == () and words.countdown is None


def test_the_robot_learning_alone_asks_the_person_to_wait():
    words = overlay(model_in_episode(human_involved=False, human_subtasks=(),
                                     training_step=0).snapshot(now=3.5))
    assert words.banner == 'The robot is learning alone, please wait'
    assert words.tone == 'wait'
    assert 'The robot works alone in this step.' in words.lines
    assert not any(line.startswith('You ') for line in words.lines)


def test_after_an_episode_the_result_and_a_countdown_to_the_next_one():
    model = model_in_episode()
    model.on_result(ResultView(5, False, True, 0.02, 0.10, 0.05, 0.17, False), now=0.5)
    model.on_state(StateView(6, 200, 0.01, -0.05, 0.03, True), now=10.0)
    model.on_result(ResultView(6, False, True, 0.01, 0.08, 0.03, 0.12, True), now=10.1)
    model.on_session(session(episode=7, total_episodes=7, human_involved_episodes=3), now=10.2)
    words = overlay(model.snapshot(now=11.5))
    assert words.countdown == 3  # the break of 4 s began at 10.0
    assert words.banner == 'Next episode in 3 s'
    assert words.lines[0] == 'Episode 8 of at most 30'
    assert words.result[0] == 'Episode 7 done'
    assert words.result[1] == 'ball off centre: 3.0 cm on average'
    assert words.result[2] == f'pendulum tilt: {math.degrees(0.08):.1f} deg, slider: 1.0 cm'
    assert 'Better than the episode before.' in words.result
    assert 'Goal reached for this training step.' in words.result
    # The break is over: "starting", and the result stays up 5 s into the next episode.
    assert overlay(model.snapshot(now=14.5)).banner == 'The next episode is starting'
    model.on_state(StateView(7, 0, 0.0, 0.0, 0.0, False), now=14.6)
    assert overlay(model.snapshot(now=16.0), result_seconds=5.0).result[0] == 'Episode 7 done'
    assert overlay(model.snapshot(now=20.0), result_seconds=5.0).result == ()


def test_updating_paused_aborted_done_and_evaluation_words():
    model = model_in_episode()
    model.on_state(StateView(6, 200, 0.0, 0.0, 0.0, True), now=10.0)
    model.on_session(session(phase='updating', total_episodes=7), now=10.1)
    assert overlay(model.snapshot(now=10.2)).banner.startswith('The robot is learning from')
    model.on_session(session(phase='paused', total_episodes=7), now=11.0)
    words = overlay(model.snapshot(now=30.0))
    assert (words.banner, words.tone, words.countdown) == (
        'Paused: please wait for the operator', 'wait', None)
    # Resumed: the agent waits a whole break again before the next episode.
    model.on_session(session(phase='training', total_episodes=7), now=40.0)
    assert overlay(model.snapshot(now=40.5)).countdown == 4
    model.on_session(session(phase='aborted', total_episodes=7), now=41.0)
    assert overlay(model.snapshot(now=41.1)).tone == 'stop'
    model.on_session(session(phase='done', total_episodes=7), now=42.0)
    words = overlay(model.snapshot(now=42.1))
    assert words.banner == 'The session is finished. Thank you!'
    assert words.episode_label == '7 training episodes done'
    model.on_session(session(phase='evaluation', episode=8, total_episodes=7), now=43.0)
    assert overlay(model.snapshot(now=43.1)).episode_label == 'Test episode 2 of 2'


def test_without_session_or_plan_the_display_still_says_something_sensible():
    model = DisplayModel()
    words = overlay(model.snapshot(now=0.0))
    assert words.banner == 'Please wait: the session is starting'
    model.on_session(session(), now=0.0)
    assert overlay(model.snapshot(now=0.0)).episode_label == 'Episode 7'  # no "of y" yet
    # A new session id forgets the old agent's plan.
    model.set_plan(PLAN)
    model.on_session(session(session_id='other'), now=1.0)
    assert model.plan is None


def pixel_of(frame, physics, y, z):
    column, row = frame.to_pixels(y, z)
    return int(round(column)), int(round(row))


@pytest.mark.parametrize('slider, angle, ball', [(0.04, 0.15, 0.1), (-0.07, -0.3, -0.15),
                                                 (0.0, 0.0, 0.2)])
def test_the_bodies_are_drawn_where_the_state_puts_them(slider, angle, ball):
    physics = PhysicsParams()
    model = model_in_episode(StateView(6, 12, slider, angle, ball, False))
    image, _ = render(model.snapshot(now=3.5), WIDTH, HEIGHT)
    frame = layout(physics, WIDTH, HEIGHT)
    state = PhysicsState(12, 2.4, slider, 0.0, angle, 0.0, ball, 0.0, 0.0, 0.0, False, False)
    poses = body_poses(state, physics)
    # Ball: at its centre.
    ball_y, ball_z = poses['ball'][0][1], poses['ball'][0][2]
    assert close_to(image.getpixel(pixel_of(frame, physics, ball_y, ball_z)), BALL_COLOR)
    # Pendulum: a quarter of the way along the beam (away from the ball and the slider).
    along = 0.25 * physics.pendulum_length if ball > 0 else 0.8 * physics.pendulum_length
    beam = pixel_of(frame, physics, along * math.cos(angle), slider + along * math.sin(angle))
    assert close_to(image.getpixel(beam), PENDULUM_COLOR)
    # Slider: west of the hinge, where the beam is not.
    assert close_to(image.getpixel(pixel_of(frame, physics, -0.018, slider)), SLIDER_COLOR)
    # Rod: beyond the slider's far side.
    rod_z = -0.1 if slider > 0 else 0.1
    assert close_to(image.getpixel(pixel_of(frame, physics, 0.0, rod_z)), ROD_COLOR)
    # Empty space stays background.
    empty_z = -0.3 if angle >= 0 else 0.25  # on the side the beam does not point to
    assert close_to(image.getpixel(pixel_of(frame, physics, 0.4, empty_z)), BACKGROUND_COLOR)


def test_the_overlay_regions_carry_text():
    model = model_in_episode()
    png, words = render_png(model.snapshot(now=3.5), WIDTH, HEIGHT)
    image = Image.open(io.BytesIO(png)).convert('RGB')
    assert image.size == (WIDTH, HEIGHT)
    frame = layout(PhysicsParams(), WIDTH, HEIGHT)
    banner = image.crop((0, 0, frame.scene_width, frame.banner_height))
    panel = image.crop((frame.scene_width, 0, WIDTH, HEIGHT // 2))
    # Text makes many distinct colours (anti-aliased glyphs) over a flat fill.
    for region in (banner, panel):
        assert len(region.getcolors(maxcolors=100000)) > 20
    assert close_to(banner.getpixel((frame.scene_width - 3, 3)), (24, 110, 60))  # act: green
    document = status_document(model.snapshot(now=3.5), words)
    assert document['episode_label'] == 'Episode 7 of at most 30'
    assert document['state']['step'] == 12 and document['session']['phase'] == 'training'
