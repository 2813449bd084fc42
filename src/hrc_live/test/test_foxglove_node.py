"""The Foxglove live view: a real foxglove node over DDS, read by a Foxglove WebSocket client.

The test publishes a state, an agent step and a session status from its own process; a client
of the Foxglove WebSocket protocol (``websockets``, subprotocol ``foxglove.sdk.v1``: the SDK's
name of ws-protocol v1) subscribes to every channel the node advertises and decodes what comes:
the JSON records and the scene (protobuf, decoded with the schema the server advertised).
"""

import asyncio
import re
import threading
import time

from hrc_common import qos, topics
from hrc_msgs.msg import AgentStep, SessionStatus, TaskState
from hrc_sim_node.body_geometry import body_poses
from hrc_sim_node.physics_params import PhysicsParams
import pytest
import rclpy

from hrc_testing.foxglove_client import follow
from hrc_testing.nodes import wait_for

pytestmark = pytest.mark.dds

CHANNELS = ('/hrc/scene', '/hrc/errors', '/hrc/agent', '/hrc/session')


def the_state() -> TaskState:
    state = TaskState(episode=3, step=17, slider_position=-0.04, pendulum_angle=0.12,
                      ball_position=0.05)
    state.header.stamp.sec, state.header.stamp.nanosec = 12, 400_000_000
    return state


def first_messages(url: str, timeout: float) -> tuple:
    """Subscribe to every advertised channel; return (channels, {topic: first message})."""
    received = {}
    loop_deadline = time.monotonic() + timeout

    def done():
        return set(received) == set(CHANNELS) or time.monotonic() > loop_deadline
    channels = asyncio.run(follow(
        url, lambda topic, message, _: received.setdefault(topic, message), done))
    return channels, received


def test_a_foxglove_client_sees_the_scene_the_errors_the_actions_and_the_session(
        start_node, rclpy_context):
    viewer = start_node('hrc_live', 'foxglove_node', parameters={'port': 0, 'max_rate': 50.0})
    assert wait_for(lambda: 'serving Foxglove on ws://' in viewer.output, 60), viewer.output
    url = re.search(r'serving Foxglove on (ws://\S+)', viewer.output).group(1)

    node = rclpy.create_node('foxglove_test_source', context=rclpy_context)
    executor = rclpy.executors.SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    states = node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
    steps = node.create_publisher(AgentStep, topics.AGENT_STEP, qos.AGENT_STEP_QOS)
    sessions = node.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
    status = SessionStatus(session_id='fox', case_id=2, episode=3,
                           phase=SessionStatus.PHASE_EVALUATION, human_involved=True,
                           message='evaluating')
    step = AgentStep(episode=3, step=17, action=0.25, observation_human_action=-0.5, reward=0.75)

    def publish():         # until the client has what it needs: a server keeps no history
        states.publish(the_state())
        steps.publish(step)
        sessions.publish(status)
    node.create_timer(0.05, publish)
    spinning = threading.Event()

    def spin():
        while not spinning.is_set():
            executor.spin_once(timeout_sec=0.05)
    spinner = threading.Thread(target=spin)
    spinner.start()
    try:
        channels, received = first_messages(url, timeout=60.0)
    finally:
        spinning.set()
        spinner.join()
        node.destroy_node()

    assert set(channels) == set(CHANNELS), channels
    assert channels['/hrc/scene']['schemaName'] == 'foxglove.SceneUpdate'
    assert received['/hrc/errors'] == {'episode': 3, 'step': 17, 'slider_m': 0.04,
                                       'pendulum_rad': 0.12, 'ball_m': 0.05}
    assert received['/hrc/agent'] == {'episode': 3, 'step': 17, 'reward': 0.75,
                                      'robot_action': 0.25, 'human_action': -0.5,
                                      'deterministic': False}
    assert received['/hrc/session']['phase'] == 'evaluation'
    assert received['/hrc/session']['session_id'] == 'fox'
    entities = {entity.id: entity for entity in received['/hrc/scene'].entities}
    assert set(entities) == {'rod', 'slider', 'pendulum', 'ball'}
    ball = entities['ball']
    assert ball.frame_id == 'world' and (ball.timestamp.seconds, ball.timestamp.nanos) == (
        12, 400_000_000)
    expected = body_poses(the_state(), PhysicsParams())['ball'][0]
    position = ball.spheres[0].pose.position
    assert (position.x, position.y, position.z) == pytest.approx(expected)
