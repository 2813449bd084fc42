"""A realtime session played with a gamepad through the person's page (real Chromium, real DDS).

``hrc session --human gamepad`` serves the page; the page reads a virtual gamepad (in place of
the browser's ``navigator.getGamepads``), the display publishes it on ``/joy`` and the human
node takes it as the person's input. The runner waits for it, the person joins, the gamepad is
unplugged mid-episode (the session pauses, no stand-in), plugged in again, the operator
resumes; the bags file the gamepad's readings as the person's input.
"""

import collections
import os
import pathlib
import re
import signal
import subprocess
import sys

from hrc_common.executables import executable_path
from hrc_live.display_words import INPUT_LOST_BANNER
from hrc_msgs.msg import HumanAction
from hrc_testing.live import loose_task_tree, operator
from hrc_testing.nodes import wait_for
import pytest

sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / 'src' / 'hrc_live' / 'test'))
from browser import open_browser  # noqa: E402

pytestmark = pytest.mark.slow

VIRTUAL_PAD = """
window.virtualPad = {index: 0, id: 'virtual gamepad (standard)', connected: true,
  mapping: 'standard', axes: [0, 0, 0, 0], buttons: [{pressed: false}]};
navigator.getGamepads = () => [window.virtualPad];
"""
STICK = -0.7            # the browser's value (stick up is -1): +0.7 on /joy


def test_a_case2_session_with_a_gamepad_through_the_page(tmp_path, ros_domain_id, read_rosbag):
    log = open(tmp_path / 'runner.log', 'w+')
    runner = subprocess.Popen([
        str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id', str(ros_domain_id),
        '--bags-dir', str(tmp_path / 'bags'), '--runs-dir', str(tmp_path / 'runs'),
        '--session-id', 'pad', '--case', '2', '--mode', 'realtime', '--human', 'gamepad',
        '--display-port', '0', '--episodes', '8', '--eval-episodes', '0', '--no-report',
        '--input-wait', '120', '--set', 'sim.episode_duration=3.0', '--set',
        'agent.horizon=64', '--set', 'agent.episode_break=0.5', '--set',
        'agent.convergence_window=1', '--set',
        f'agent.task_tree_file={loose_task_tree(tmp_path)}'],
        stdout=log, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    sim_log = tmp_path / 'runs' / 'pad' / 'logs' / 'sim.log'

    def output():
        log.seek(0)
        return log.read()

    browser = open_browser(1280, 720)
    try:
        assert wait_for(lambda: 'waiting for the person' in output(), 120), output()
        assert 'no gamepad sends' in output()
        page = re.search(r"the person's page: (http://127\.0\.0\.1:\d+/)", output()).group(1)
        browser.get(page)
        browser.execute_script(VIRTUAL_PAD)
        browser.execute_script(f'window.virtualPad.axes[1] = {STICK}')   # chosen by moving it
        assert wait_for(lambda: 'the input is there now' in output(), 60), output()
        # the person joins (realtime); the gamepad is unplugged in their first episode
        assert wait_for(lambda: sim_log.exists() and re.search(
            r'episode \d+ started \(.*realtime\)', sim_log.read_text()), 180), output()
        browser.execute_script('window.virtualPad.connected = false')
        assert wait_for(lambda: 'joystick disconnected' in output(), 60), output()
        # the person's page says the pause (the words of a lost joystick), no stand-in
        assert wait_for(lambda: browser.find_element('id', 'banner-text').text
                        == INPUT_LOST_BANNER, 30, 0.2), browser.find_element('id', 'banner').text
        code, said = operator(ros_domain_id, 'resume')
        assert code == 1 and 'still disconnected' in said, said
        browser.execute_script(f'window.virtualPad.connected = true; '
                               f'window.virtualPad.axes[1] = {STICK}')
        assert wait_for(lambda: 'connected again' in operator(ros_domain_id, 'status')[1],
                        60, interval=0.5), output()
        code, said = operator(ros_domain_id, 'resume')
        assert code == 0 and 'resumed' in said, said
        assert runner.wait(timeout=300) == 0, output()
    finally:
        browser.quit()
        if runner.poll() is None:
            os.killpg(runner.pid, signal.SIGTERM)
            runner.wait(timeout=60)
    text = output()
    assert 'the human side is driven by: joy' in text, text
    bag = read_rosbag(tmp_path / 'bags' / 'pad')
    sources = collections.Counter((a.source, a.engaged) for a in bag['/hrc/human/action'])
    assert HumanAction.SOURCE_SIMULATED not in {source for source, _ in sources}, sources
    driven = [a.command for a in bag['/hrc/human/action']
              if a.source == HumanAction.SOURCE_JOY and a.engaged]
    # the stick held at 0.7 of its range, past the 0.05 deadzone: (0.7 - 0.05) / 0.95
    assert len(driven) >= 10 and all(value == pytest.approx(0.65 / 0.95) for value in driven)
