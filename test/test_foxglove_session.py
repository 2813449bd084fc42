"""``hrc session --foxglove``: the running session, read live by a Foxglove WebSocket client.

A short lockstep session with the option on; a client of the Foxglove WebSocket protocol
(``websockets``) connects while it runs, subscribes to every channel and decodes what comes
(src/hrc_live/test/test_foxglove_node.py checks the records' values against known messages).
"""

import asyncio
import base64
import json
import socket
import struct
import subprocess
import threading

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from hrc_common.executables import executable_path
import pytest
import websockets

pytestmark = pytest.mark.slow


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def scene_class(channel: dict):
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel['schema']))
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel['schemaName']))


async def watch(port: int, stop: threading.Event, seen: dict) -> None:
    """Connect (retrying while the server starts), subscribe to all, keep the last of each."""
    while not stop.is_set():
        try:
            async with websockets.connect(f'ws://127.0.0.1:{port}',
                                          subprotocols=['foxglove.sdk.v1']) as client:
                channels = {}
                while not stop.is_set():
                    try:
                        frame = await asyncio.wait_for(client.recv(), 0.5)
                    except asyncio.TimeoutError:
                        continue
                    if isinstance(frame, str):
                        message = json.loads(frame)
                        if message.get('op') == 'advertise':
                            channels.update({c['id']: c for c in message['channels']})
                            await client.send(json.dumps({'op': 'subscribe', 'subscriptions': [
                                {'id': c['id'], 'channelId': c['id']}
                                for c in message['channels']]}))
                        continue
                    (subscription,) = struct.unpack_from('<I', frame, 1)
                    channel = channels[subscription]
                    payload = frame[13:]
                    seen[channel['topic']] = (json.loads(payload) if channel['encoding'] == 'json'
                                              else scene_class(channel).FromString(payload))
        except (OSError, websockets.exceptions.WebSocketException):
            await asyncio.sleep(0.2)


def test_hrc_session_foxglove_serves_the_running_session(tmp_path, ros_domain_id):
    port = free_port()
    stop, seen = threading.Event(), {}
    viewer = threading.Thread(target=lambda: asyncio.run(watch(port, stop, seen)), daemon=True)
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
