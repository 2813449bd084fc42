"""The experimenter's console data: the current attempt's numbers, colours that mean "act now".

Pure and deterministic (explicit monotonic times).
"""

from hrc_live.display_core import AgentPlan, DisplayModel, HumanView, StateView
from hrc_live.display_documents import console_document
from hrc_testing.display_views import case2_view

PLAN = AgentPlan(max_training_episodes=100, evaluation_episodes=2, episode_break=3.0)


status = case2_view


def test_the_episode_box_holds_the_current_attempt_only():
    model = DisplayModel()
    model.on_session(status(), now=0.0)
    for step in range(60):                  # the first attempt, stopped at step 59
        model.on_state(StateView(9, step, 0.05, 0.0, 0.1, False), now=0.2 * step)
    model.on_session(status(phase='paused'), now=12.0)
    model.on_session(status(), now=20.0)
    for step in range(10):                  # the episode runs again from its start
        model.on_state(StateView(9, step, 0.01, 0.0, 0.02, False), now=23.0 + 0.2 * step)
    episode = console_document(model.snapshot(now=25.0))['episode']
    assert episode['episode'] == 9 and episode['steps'] == 10
    assert abs(episode['slider_error_m'] - 0.01) < 1e-9
    assert abs(episode['ball_error_m'] - 0.02) < 1e-9


def test_no_red_for_what_is_normal_red_for_what_asks_for_action():
    model = DisplayModel()
    model.set_plan(PLAN)
    # the robot learns alone: nothing comes from the person, and that is normal
    model.on_session(status(human_involved=False, human_subtasks=(), training_step=0),
                     now=0.0)
    model.on_state(StateView(9, 5, 0.0, 0.0, 0.0, False), now=0.1)
    assert console_document(model.snapshot(now=5.0))['input']['tone'] == ''
    # the person's round: a fresh command is fine, a stale one asks for action
    model.on_session(status(episode=10, total_episodes=10), now=6.0)
    model.on_state(StateView(10, 1, 0.0, 0.0, 0.0, False), now=6.2)
    model.on_human(HumanView('device', '/dev/input/js0', True, 0.1, received=6.2))
    assert console_document(model.snapshot(now=6.3))['input']['tone'] == 'ok'
    assert console_document(model.snapshot(now=9.0))['input']['tone'] == 'bad'
    # paused by the operator: the command ages, and that is normal
    model.on_session(status(episode=10, total_episodes=10, phase='paused'), now=9.1)
    assert console_document(model.snapshot(now=30.0))['input']['tone'] == ''
    # the joystick is lost: act now
    model.set_input_lost('joystick disconnected: /dev/input/js0 gone')
    assert console_document(model.snapshot(now=31.0))['input']['tone'] == 'bad'


def test_the_console_carries_the_subject_the_condition_the_tlx_and_the_runners_wait():
    model = DisplayModel()
    model.set_runner_waiting("waiting for the person's input (up to 120 s): plug it in")
    document = console_document(model.snapshot(now=0.0),
                                {'subject_id': 'P07', 'condition': 'condition 2 of 6 in the '
                                 'order (case 3)'}, "waiting for the person's answers")
    assert document['study'] == {'subject_id': 'P07',
                                 'condition': 'condition 2 of 6 in the order (case 3)'}
    assert document['runner_waiting'].startswith("waiting for the person's input")
    assert document['tlx'] == "waiting for the person's answers"
    model.set_runner_waiting('')
    assert console_document(model.snapshot(now=1.0))['runner_waiting'] == ''


def test_every_nodes_health_from_diagnostics_with_its_level_and_a_stale_one_said():
    model = DisplayModel()
    model.set_health('sim: timing', 0, 'period jitter p99 2.1 ms', now=10.0)
    model.set_health('recorder: writing', 1, 'disk almost full: 900 MiB free', now=10.0)
    model.set_health('human: input', 2, 'joystick lost', now=10.0)
    model.set_health('sim: timing', 0, 'period jitter p99 2.4 ms', now=11.0)   # the newest kept
    rows = console_document(model.snapshot(now=11.5))['health']
    assert rows == [
        {'name': 'human: input', 'status': 'ERROR: joystick lost', 'tone': 'bad'},
        {'name': 'recorder: writing', 'status': 'WARN: disk almost full: 900 MiB free',
         'tone': 'wait'},
        {'name': 'sim: timing', 'status': 'OK: period jitter p99 2.4 ms', 'tone': 'ok'}]
    # a node that has not spoken for over 3 s (they speak once a second): stale, not "OK"
    stale = console_document(model.snapshot(now=14.5))['health'][2]
    assert stale == {'name': 'sim: timing', 'tone': 'wait',
                     'status': 'no word for 4 s (last: OK: period jitter p99 2.4 ms)'}
