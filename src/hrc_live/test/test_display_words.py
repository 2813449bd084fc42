"""The person's words: a participant's vocabulary, what their action does, steady banners.

Pure and deterministic (the model is fed with explicit monotonic times).
"""

from dataclasses import replace
import re

from hrc_live.display_core import AgentPlan, DisplayModel, ResultView, StateView
from hrc_live.display_words import (ALONE_BANNER, BANNER_HOLD_S, overlay, REPLAY_BANNER,
                                    SteadyBanner)
from hrc_testing.display_views import case2_view

PLAN = AgentPlan(max_training_episodes=100, evaluation_episodes=2, episode_break=3.0)
PERIOD = 0.2    # s between two pushes of the words (the display's words_rate 5 Hz)


case2 = case2_view


def test_the_person_on_the_slider_is_told_how_their_moves_reach_the_ball():
    model = DisplayModel()
    model.set_plan(PLAN)
    model.on_session(case2(), now=0.0)
    model.on_state(StateView(9, 3, 0.0, 0.0, 0.0, False), now=1.0)
    lines = overlay(model.snapshot(now=1.0)).lines
    assert 'Your task: keep the ball in the middle of the pendulum.' in lines
    assert ('Your moves tilt the beam: a quick move up dips its right end, a quick move down '
            'lifts it. The ball rolls toward the lower end.') in lines


def test_the_person_on_the_beam_is_told_what_tilting_does_to_the_ball():
    model = DisplayModel()
    model.on_session(case2(human_dof='rotation', human_subtasks=('pendulum', 'ball')), now=0.0)
    lines = overlay(model.snapshot(now=0.0)).lines
    assert ('The ball rolls toward the lower end of the beam: lift the end it is rolling '
            'to.') in lines


def words_in_every_situation() -> list:
    """Return the overlays of a session from the start to the end (with a pause and a result)."""
    model, seen = DisplayModel(), []
    seen.append(overlay(model.snapshot(now=0.0)))
    model.set_plan(PLAN)
    model.on_session(case2(human_involved=False, human_subtasks=(), training_step=0,
                           episode=0, total_episodes=0), now=0.0)
    model.on_state(StateView(0, 5, 0.0, 0.0, 0.0, False), now=0.1)
    seen.append(overlay(model.snapshot(now=0.2)))
    model.on_session(case2(), now=10.0)
    seen.append(overlay(model.snapshot(now=10.5)))          # the countdown
    model.on_state(StateView(9, 0, 0.0, 0.0, 0.0, False), now=13.0)
    model.on_state(StateView(9, 40, 0.0, 0.0, 0.0, False), now=21.0)
    seen.append(overlay(model.snapshot(now=21.0)))          # the person's round
    model.on_state(StateView(9, 200, 0.0, 0.0, 0.0, True), now=53.0)
    model.on_result(ResultView(9, False, True, 0.01, 0.05, 0.02, 0.08, False), now=53.0)
    model.on_session(case2(episode=10, total_episodes=10, human_involved_episodes=1,
                           phase='updating'), now=53.1)
    seen.append(overlay(model.snapshot(now=53.2)))
    model.on_session(case2(episode=10, total_episodes=10, human_involved_episodes=1,
                           phase='paused'), now=54.0)
    seen.append(overlay(model.snapshot(now=54.1)))
    model.on_session(case2(episode=10, total_episodes=10, human_involved_episodes=1,
                           phase='evaluation'), now=60.0)
    seen.append(overlay(model.snapshot(now=60.1)))
    model.on_session(case2(episode=12, total_episodes=10, human_involved_episodes=1,
                           phase='done'), now=90.0)
    seen.append(overlay(model.snapshot(now=90.1)))
    return seen


def test_the_page_speaks_to_a_participant_not_to_an_rl_engineer():
    seen = words_in_every_situation()
    texts = [text for words in seen
             for text in (words.banner, words.notice, *words.lines, *words.result)]
    jargon = [text for text in texts
              if re.search(r'\bepisodes?\b|training step|evaluation|converge', text, re.I)]
    assert not jargon, jargon
    labels = [words.episode_label for words in seen]
    assert 'Round 10 of at most 100' in labels and 'Test round 1 of 2' in labels, labels


def test_a_resume_in_the_middle_of_the_first_round_does_not_say_first_again():
    model = DisplayModel()
    model.set_plan(PLAN)
    model.on_state(StateView(8, 200, 0.0, 0.0, 0.0, True), now=0.0)   # the robot's last round
    model.on_session(case2(), now=0.0)
    assert overlay(model.snapshot(now=0.5)).banner == 'Get ready: your first round starts in 3 s'
    model.on_state(StateView(9, 0, 0.0, 0.0, 0.0, False), now=3.0)
    model.on_state(StateView(9, 60, 0.0, 0.0, 0.0, False), now=15.0)
    model.on_session(case2(phase='paused'), now=15.1)       # paused in the middle
    model.on_session(case2(), now=30.0)                     # resumed: the round runs again
    assert overlay(model.snapshot(now=30.5)).banner == 'Get ready: the next round starts in 3 s'


def test_a_replay_is_marked_as_one():
    model = DisplayModel()
    model.on_session(case2(), now=0.0)
    model.on_state(StateView(9, 3, 0.0, 0.0, 0.0, False), now=1.0)
    assert overlay(model.snapshot(now=1.0)).banner.startswith('Your turn')
    model.set_replay('bags/case2-seed0 at rate 1.0')
    words = overlay(model.snapshot(now=1.0))
    assert words.banner == REPLAY_BANNER and words.tone == 'info'
    assert words.lines[1] == 'Replay: bags/case2-seed0 at rate 1.0'
    model.set_replay('')
    assert overlay(model.snapshot(now=1.0)).banner.startswith('Your turn')


def test_the_banner_does_not_flicker_while_the_robot_practises_alone():
    """138 s of lonely rounds, each a fraction of a second, seen at the words' rate."""
    model, steady = DisplayModel(), SteadyBanner()
    model.set_plan(PLAN)
    shown, now, episode = [], 0.0, 0
    while now < 138.0:
        # a lonely round of 0.5 s: its first state, a state within it, its final state
        alone = case2(human_involved=False, human_subtasks=(), training_step=0,
                      episode=episode, total_episodes=episode)
        model.on_session(alone, now=now)
        for step, offset, final in ((0, 0.0, False), (100, 0.2, False), (200, 0.4, True)):
            model.on_state(StateView(episode, step, 0.0, 0.0, 0.0, final), now=now + offset)
            shown.append(steady.shown(overlay(model.snapshot(now=now + offset)),
                                      now + offset).banner)
        now += 0.5
        episode += 1
    assert set(shown) == {ALONE_BANNER}, set(shown)


def test_a_steady_banner_holds_a_text_unless_the_situation_changes():
    steady = SteadyBanner()
    model = DisplayModel()
    model.on_session(case2(), now=0.0)
    model.on_state(StateView(9, 3, 0.0, 0.0, 0.0, False), now=0.0)
    act = overlay(model.snapshot(now=0.0))
    assert steady.shown(act, 0.0).banner == act.banner
    other = replace(act, banner='Your turn: another text')
    assert steady.shown(other, 0.3).banner == act.banner              # held
    assert steady.shown(other, BANNER_HOLD_S + 0.01).banner == other.banner
    stop = replace(act, banner='Stopped by the operator.', tone='stop')
    assert steady.shown(stop, BANNER_HOLD_S + 0.02).banner == stop.banner  # at once
