"""The ``graph`` fixture of the page tests (see page_graph.py)."""

import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from browser import open_browser  # noqa: E402
from page_graph import FakeAgent, PENDULUM_LENGTH, served_port, session_status, status  # noqa: E402
from hrc_testing.nodes import wait_for  # noqa: E402


@pytest.fixture
def graph(start_node, rclpy_context, tmp_path):
    start_node('hrc_sim_node', 'sim_node', parameters={
        'pendulum_length': PENDULUM_LENGTH, 'marker_rate': 0.0})
    display = start_node('hrc_live', 'display_node', parameters={
        'port': 0, 'tlx_file': str(tmp_path / 'tlx.yaml'), 'tlx_title': 'the part you played'})
    agent = FakeAgent(rclpy_context)
    port = served_port(display)
    agent.session.publish(session_status())
    assert wait_for(lambda: (status(port)['geometry_from_sim'] and status(port)['plan']
                             and status(port)['session']), 60, 0.2), display.output
    browser = open_browser(1920, 1080)
    yield agent, port, browser, display
    browser.quit()
    agent.close()
