"""The person's page in a real headless Chromium, through every state of a session.

A stand-in agent (page_graph.FakeAgent) drives the display node over DDS through the states a
person meets: the robot practising alone (many short rounds), the countdown, their turn, a
pause, a lost joystick, a replay, the end and the questionnaire, the thank-you. At each, at
1280x720 and at 1920x1080, a screenshot is saved (``HRC_SCREENSHOTS`` names a folder to keep
them) and checked: the words a participant reads (no RL vocabulary), the scene's share of the
viewport (at least 60 %) and that the scene never moves. Over the lonely phase the banner's
changes are recorded in the page itself (a MutationObserver): no text may flicker.
"""

import os
import pathlib
import re
import sys

from hrc_common import qos, topics
from hrc_live.input_check import INPUT_LOST_TOPIC
from hrc_msgs.msg import SessionStatus
from hrc_testing.nodes import wait_for
from std_msgs.msg import String

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from browser import screenshot, set_viewport  # noqa: E402
from page_graph import session_status, task_state  # noqa: E402

SIZES = ((1280, 720), (1920, 1080))
MIN_SCENE_SHARE = 0.60
JARGON = re.compile(r'\bepisodes?\b|training step|evaluation|converge|reward', re.I)
# Records every change of the banner's text with the page's clock (ms).
WATCH_BANNER = """
window.bannerChanges = [];
const target = document.getElementById('banner-text');
new MutationObserver(() => window.bannerChanges.push([performance.now(), target.textContent]))
  .observe(target, {childList: true, characterData: true, subtree: true});
"""


def page_text(browser, element):
    return browser.find_element('id', element).text


def scene_box(browser):
    return browser.execute_script(
        "const r = document.getElementById('scene').getBoundingClientRect();"
        'return [r.left, r.top, r.width, r.height, window.innerWidth, window.innerHeight];')


def check_page(browser, folder, name, banner_start, boxes):
    """Screenshot the page at both sizes; check the words and the scene's place and share."""
    for width, height in SIZES:
        set_viewport(browser, width, height)
        assert wait_for(lambda: scene_box(browser)[4:] == [width, height], 20, 0.1)
        assert wait_for(lambda: page_text(browser, 'banner').startswith(banner_start), 30,
                        0.1), (name, page_text(browser, 'banner'))
        screenshot(browser).save(folder / f'person-{name}-{width}x{height}.png')
        left, top, scene_width, scene_height, _, _ = scene_box(browser)
        share = scene_width * scene_height / (width * height)
        assert share >= MIN_SCENE_SHARE, (name, width, height, round(share, 3))
        boxes.setdefault((width, height), set()).add((left, top, scene_width, scene_height))
        words = [page_text(browser, element) for element in ('banner', 'label', 'lines',
                                                             'result', 'notice')]
        assert not any(JARGON.search(text) for text in words), (name, words)


def lonely_rounds(agent, first, count):
    """Publish ``count`` rounds of the robot practising alone (a few states each, at once)."""
    for episode in range(first, first + count):
        agent.session.publish(session_status(
            human_involved=False, human_subtasks=[], training_step=0, episode=episode,
            total_episodes=episode, human_involved_episodes=0))
        for step, final in ((0, False), (100, False), (200, True)):
            agent.state.publish(task_state(episode, step, 0.01, 0.02, 0.03, final))


def test_every_state_of_the_page_for_a_person(graph, tmp_path):
    agent, port, browser, display = graph
    folder = pathlib.Path(os.environ.get('HRC_SCREENSHOTS', tmp_path))
    folder.mkdir(parents=True, exist_ok=True)
    boxes = {}
    lost = agent.node.create_publisher(String, INPUT_LOST_TOPIC, qos.SESSION_QOS)
    replay = agent.node.create_publisher(String, topics.REPLAY, qos.SESSION_QOS)
    browser.get(f'http://127.0.0.1:{port}/')

    # The robot practises alone for 20 rounds: one text, no flicker.
    lonely_rounds(agent, 0, 1)
    assert wait_for(lambda: page_text(browser, 'banner').startswith(
        'The robot is practising alone'), 30, 0.1), page_text(browser, 'banner')
    browser.execute_script(WATCH_BANNER)
    for first in range(1, 20, 4):
        lonely_rounds(agent, first, 4)
        assert wait_for(lambda: f'{first + 3} rounds' in page_text(browser, 'lines'), 30, 0.1)
    changes = browser.execute_script('return window.bannerChanges')
    assert changes == [], changes
    check_page(browser, folder, 'robot-alone', 'The robot is practising alone', boxes)

    # The person joins: the countdown, then their turn with what their action does.
    lonely_rounds(agent, 20, 1)     # its last round ends: the break before the person's starts
    agent.session.publish(session_status(episode=21, total_episodes=21,
                                         human_involved_episodes=0))
    check_page(browser, folder, 'countdown', 'Get ready: your first round starts in', boxes)
    for step in range(0, 12):
        agent.state.publish(task_state(21, step, 0.02, 0.05, 0.04))
    check_page(browser, folder, 'your-turn', 'Your turn: keep the slider', boxes)
    lines = page_text(browser, 'lines')
    assert 'Your moves tilt the beam' in lines and 'You move the slider up and down' in lines

    agent.session.publish(session_status(episode=21, total_episodes=21,
                                         phase=SessionStatus.PHASE_PAUSED))
    check_page(browser, folder, 'paused', 'Paused by the operator', boxes)
    lost.publish(String(data='/dev/input/js0 unplugged'))
    check_page(browser, folder, 'joystick-lost', 'The joystick is disconnected', boxes)
    assert 'js0' not in page_text(browser, 'notice')        # the detail is the console's
    lost.publish(String(data=''))

    replay.publish(String(data='bags/case2-seed0 at rate 1.0'))
    agent.session.publish(session_status(episode=22, total_episodes=22))
    agent.state.publish(task_state(22, 3, 0.0, 0.0, 0.0))
    check_page(browser, folder, 'replay', 'Replay of a recorded session', boxes)
    assert 'Replay: bags/case2-seed0' in page_text(browser, 'lines')
    replay.publish(String(data=''))

    # The end: the questionnaire covers the page (the scene does not show through), then thanks.
    agent.session.publish(session_status(episode=24, total_episodes=22,
                                         phase=SessionStatus.PHASE_DONE))
    form = browser.find_element('id', 'tlx')
    assert wait_for(form.is_displayed, 30, 0.2)
    assert browser.execute_script(
        "return getComputedStyle(document.getElementById('tlx')).backgroundColor") == \
        'rgb(20, 24, 30)'
    screenshot(browser).save(folder / 'person-questionnaire.png')
    for name in ('mental', 'physical', 'temporal', 'performance', 'effort', 'frustration'):
        browser.find_element('css selector', f'input[name="{name}"][value="50"]').click()
    browser.find_element('id', 'tlx-send').click()
    check_page(browser, folder, 'thank-you', 'Thank you, your answers are saved', boxes)

    # The scene stayed in one place at each size, whatever the banner said.
    assert all(len(places) == 1 for places in boxes.values()), boxes
