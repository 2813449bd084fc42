"""The person's gamepad through the browser: the page's readings become /joy (real Chromium).

The display node runs in its own process with ``gamepad: true``; the page runs in headless
Chromium with a virtual gamepad in place of ``navigator.getGamepads`` (the browser's Gamepad
API, standard mapping); the test reads ``/joy`` over DDS as the human node would.
"""

import json
import pathlib
import sys

from hrc_common import qos, topics
from hrc_live.gamepad import gamepad_body, joy_values
from hrc_testing.nodes import wait_for
import pytest
import rclpy
from sensor_msgs.msg import Joy

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from browser import open_browser  # noqa: E402
from page_graph import served_port  # noqa: E402

VIRTUAL_PAD = """
window.virtualPad = {index: 0, id: 'virtual gamepad (standard)', connected: true,
  mapping: 'standard', axes: [0, 0, 0, 0], buttons: [{pressed: false}, {pressed: false}]};
navigator.getGamepads = () => [window.virtualPad];
"""


def test_a_reading_is_checked_and_turned_into_the_joy_convention():
    record, problem = gamepad_body(json.dumps({'axis': -0.25, 'button': True, 'axis_index': 1,
                                               'id': 'pad'}).encode())
    assert problem == '' and joy_values(record) == ([0.25], [1])     # stick up: + on /joy
    assert gamepad_body(b'[1]')[1].startswith('not a JSON object')
    assert gamepad_body(b'{"axis": 1')[1] == 'not JSON'
    _, problem = gamepad_body(json.dumps({'axis': 2, 'button': 'yes', 'axis_index': -1,
                                          'id': 'x' * 300}).encode())
    assert problem.count(';') == 3, problem                         # every reason at once
    assert gamepad_body(b'{"axis": NaN}')[1].startswith('axis must be a number')
    assert gamepad_body(b'[' * 100_000)[1] == 'not JSON'            # nesting: refused, bounded


@pytest.mark.dds
def test_the_pages_gamepad_drives_joy_and_a_lost_one_withdraws_it(start_node, rclpy_context):
    display = start_node('hrc_live', 'display_node', parameters={'port': 0, 'gamepad': True})
    port = served_port(display)
    node = rclpy.create_node('gamepad_test', context=rclpy_context)
    executor = rclpy.executors.SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    readings = []
    node.create_subscription(Joy, topics.JOY, readings.append, qos.JOY_QOS)

    def spin():
        executor.spin_once(timeout_sec=0.05)

    browser = open_browser(1280, 720)
    try:
        browser.get(f'http://127.0.0.1:{port}/')
        browser.execute_script(VIRTUAL_PAD)
        gamepad_line = lambda: browser.find_element('id', 'gamepad').text   # noqa: E731
        # connected, no stick moved yet: nothing is sent, so nobody writes /joy
        assert wait_for(lambda: 'move the stick' in gamepad_line(), 30, 0.1), gamepad_line()
        assert node.count_publishers(topics.JOY) == 0 and not readings
        # the person moves the stick they want: the page chooses it, /joy follows it
        browser.execute_script('window.virtualPad.axes[1] = -0.8')
        assert wait_for(lambda: 'stick 1 chosen' in gamepad_line(), 30, 0.1), gamepad_line()
        assert wait_for(lambda: readings and list(readings[-1].axes) == [pytest.approx(0.8)],
                        30, spin=spin)
        browser.execute_script('window.virtualPad.axes[1] = 0.3; '
                               'window.virtualPad.buttons[0].pressed = true')
        assert wait_for(lambda: list(readings[-1].axes) == [pytest.approx(-0.3)]
                        and list(readings[-1].buttons) == [1], 30, spin=spin)
        assert "the person's gamepad (virtual gamepad (standard), axis 1) drives /joy" in \
            display.output
        # unplugged: the page stops sending and the display withdraws its /joy writer
        browser.execute_script('window.virtualPad.connected = false')
        assert wait_for(lambda: 'Gamepad disconnected' in gamepad_line(), 30, 0.1)
        assert wait_for(lambda: node.count_publishers(topics.JOY) == 0, 30, spin=spin)
        assert "the person's gamepad is silent: /joy withdrawn" in display.output
        # plugged in again: the same stick drives /joy again
        count = len(readings)
        browser.execute_script('window.virtualPad.connected = true; '
                               'window.virtualPad.axes[1] = -0.9')
        assert wait_for(lambda: len(readings) > count
                        and list(readings[-1].axes) == [pytest.approx(0.9)], 30, spin=spin)
    finally:
        browser.quit()
        node.destroy_node()
