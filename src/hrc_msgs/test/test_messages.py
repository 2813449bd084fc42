"""hrc_msgs: every message survives serialization and crosses two processes over DDS."""

import math
import pathlib
import subprocess
import sys
import textwrap

import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message

from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode


def sample_messages():
    """Return one filled-in instance of every message, with distinctive values."""
    state = TaskState(episode=3, step=17, slider_position=0.0425, slider_velocity=-0.11,
                      pendulum_angle=-0.3, pendulum_angular_velocity=1.5, ball_position=0.2,
                      ball_velocity=-0.05, applied_force=2.5, applied_torque=-0.4,
                      robot_command_missing=True, truncated=True)
    state.header.stamp.sec = 3
    state.header.stamp.nanosec = 400_000_000
    state.header.frame_id = 'world'
    action = HumanAction(episode=3, step=17, command=-0.75, dof=HumanAction.DOF_ROTATION,
                         source=HumanAction.SOURCE_DEVICE, source_detail='/dev/input/js0',
                         engaged=True)
    session = SessionStatus(session_id='s-001', case_id=4, strategy='level_guided',
                            training_step=1, training_step_count=2,
                            robot_dof=SessionStatus.DOF_ROTATION,
                            human_dof=SessionStatus.DOF_TRANSLATION, human_involved=True,
                            robot_subtasks=['slider', 'pendulum', 'ball'],
                            human_subtasks=['slider'], episode=9, total_episodes=9,
                            human_involved_episodes=9, phase=SessionStatus.PHASE_UPDATING,
                            message='updating the policy')
    summary = EpisodeSummary(session_id='s-001', case_id=4, episode=9, training_step=1,
                             human_involved=True, steps=200, truncated=True,
                             episode_return=123.5, slider_error=0.01, pendulum_error=0.2,
                             ball_error=0.05, total_error=0.26, robot_effort=0.0022,
                             human_effort=0.0021, converged=True)
    step = AgentStep(episode=9, step=5, observation_human_action=0.5, action=-0.25,
                     wrench=-0.125, subtask_ids=['slider', 'pendulum'],
                     reward_components=[3.9, 3.8], reward=7.7, value_estimate=101.0,
                     log_prob=-0.9)
    return [state, action, session, summary, step]


def fields_of(message):
    """Return the message as a nested dict of plain values (for equality checks)."""
    result = {}
    for name in message.get_fields_and_field_types():
        value = getattr(message, name)
        if hasattr(value, 'get_fields_and_field_types'):
            value = fields_of(value)
        elif not isinstance(value, (str, bytes, int, float, bool)):
            value = list(value)
        result[name] = value
    return result


@pytest.mark.parametrize('message', sample_messages(), ids=lambda m: type(m).__name__)
def test_serialization_round_trip(message):
    data = serialize_message(message)
    assert isinstance(data, bytes) and len(data) > 8
    copy = deserialize_message(data, type(message))
    assert fields_of(copy) == fields_of(message)


def test_constants_and_units_documented():
    assert HumanAction.DOF_TRANSLATION == SessionStatus.DOF_TRANSLATION == 0
    assert HumanAction.DOF_ROTATION == SessionStatus.DOF_ROTATION == 1
    from ament_index_python.packages import get_package_share_directory
    share = pathlib.Path(get_package_share_directory('hrc_msgs'))
    state_definition = (share / 'msg' / 'TaskState.msg').read_text()
    for field, unit in [('slider_position', '(m)'), ('pendulum_angle', '(rad)'),
                        ('ball_position', '(m)'), ('applied_torque', '(N*m)')]:
        line = next(line for line in state_definition.splitlines() if line.split()[1:2] == [field])
        assert unit in line, f'{field} has no unit in its comment'


def test_reset_service_types():
    request = ResetEpisode.Request()
    assert request.seed == -1, 'the default seed means: the next of the sim sequence'
    response = ResetEpisode.Response(success=True, message='ok')
    response.state.step = 0
    assert deserialize_message(serialize_message(response), ResetEpisode.Response).success


# Reliable and transient local (as /hrc/session): a subscription that matches late still gets
# each message. Defined here: hrc_msgs is the lowest layer and imports no other hrc package.
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)

PUBLISHER_SCRIPT = textwrap.dedent("""
    import sys, time, pickle, base64
    import rclpy
    from rclpy.duration import Duration
    from rclpy.serialization import deserialize_message
    from hrc_msgs.msg import AgentStep, EpisodeSummary, HumanAction, SessionStatus, TaskState
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    rclpy.init()
    node = rclpy.create_node('message_publisher')
    messages = [deserialize_message(base64.b64decode(data), cls) for data, cls in zip(
        {payloads!r}, [TaskState, HumanAction, SessionStatus, EpisodeSummary, AgentStep])]
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publishers = [node.create_publisher(type(m), '/hrc/test/' + type(m).__name__, qos)
                  for m in messages]
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if all(p.get_subscription_count() > 0 for p in publishers):
            break
        rclpy.spin_once(node, timeout_sec=0.05)
    for publisher, message in zip(publishers, messages):
        publisher.publish(message)
    for publisher in publishers:     # the listener has each message before this process ends
        publisher.wait_for_all_acked(Duration(seconds=60))
    rclpy.shutdown()
""")


def test_every_message_crosses_processes(rclpy_context, ros_env):
    import base64
    import time

    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    messages = sample_messages()
    payloads = [base64.b64encode(serialize_message(m)).decode() for m in messages]
    script = PUBLISHER_SCRIPT.format(payloads=payloads)
    node = rclpy.create_node('message_listener', context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    received = {}
    for message in messages:
        name = type(message).__name__
        node.create_subscription(type(message), '/hrc/test/' + name,
                                 lambda m, name=name: received.setdefault(name, m),
                                 LATCHED_QOS)
    publisher = subprocess.Popen([sys.executable, '-c', script], env=ros_env,
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        # s: the publisher is a new Python process (rclpy's import, discovery) on a machine
        # that may be busy
        deadline = time.monotonic() + 120
        while len(received) < len(messages) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
    finally:
        publisher.kill()
        output = publisher.communicate()[0].decode(errors='replace')
        node.destroy_node()
    assert sorted(received) == sorted(type(m).__name__ for m in messages), output
    for message in messages:
        got = received[type(message).__name__]
        assert fields_of(got) == fields_of(message)
    assert math.isclose(received['TaskState'].slider_position, 0.0425)
