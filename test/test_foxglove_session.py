"""``hrc session --foxglove``: the running session, read live by a Foxglove WebSocket client.

A short lockstep session with the option on; a client of the Foxglove WebSocket protocol
(``websockets``) connects while it runs, subscribes to every channel and decodes what comes
(src/hrc_live/test/test_foxglove_node.py checks the records' values against known messages).
"""

import asyncio
import socket
import subprocess
import threading

from hrc_common.executables import executable_path
from hrc_testing.foxglove_client import follow
import pytest

pytestmark = pytest.mark.slow


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def test_hrc_session_foxglove_serves_the_running_session(tmp_path, ros_domain_id):
    port = free_port()
    stop, seen = threading.Event(), {}
    viewer = threading.Thread(target=lambda: asyncio.run(follow(
        f'ws://127.0.0.1:{port}', lambda topic, message, _: seen.__setitem__(topic, message),
        stop.is_set)), daemon=True)
    viewer.start()
    try:
        result = subprocess.run(
            [str(executable_path('hrc_bringup', 'hrc')), 'session', '--domain-id',
             str(ros_domain_id), '--session-id', 'fox', '--bags-dir', 'bags', '--runs-dir',
             'runs', '--episodes', '6', '--eval-episodes', '1', '--no-report', '--foxglove',
             '--foxglove-port', str(port)],
            cwd=tmp_path, capture_output=True, text=True, timeout=300,
            start_new_session=True)
    finally:
        stop.set()
        viewer.join(10)
    assert result.returncode == 0, result.stdout + result.stderr
    assert set(seen) == {'/hrc/scene', '/hrc/errors', '/hrc/agent', '/hrc/session'}, seen.keys()
    assert {entity.id for entity in seen['/hrc/scene'].entities} == {
        'rod', 'slider', 'pendulum', 'ball'}
    assert set(seen['/hrc/errors']) == {'episode', 'step', 'slider_m', 'pendulum_rad', 'ball_m'}
    assert seen['/hrc/session']['session_id'] == 'fox'
    log = (tmp_path / 'runs' / 'fox' / 'logs' / 'foxglove.log').read_text()
    assert f'serving Foxglove on ws://127.0.0.1:{port}' in log, log
