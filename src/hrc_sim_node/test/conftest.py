"""A test-side client of the sim node: publishes commands, records what the sim publishes."""

import time

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_testing.nodes import wait_for
from hrc_msgs.msg import SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image
from visualization_msgs.msg import MarkerArray


class SimClient:
    """Talk to a sim node in another process over DDS (the test's own rclpy context)."""

    def __init__(self, context):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node('sim_test_client', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.states, self.clocks, self.images, self.markers = [], [], [], []
        self.state_times = []  # monotonic receipt time of each state
        node = self.node
        self.publishers = {
            'robot': node.create_publisher(WrenchStamped, topics.ROBOT_CMD_WRENCH,
                                           qos.COMMAND_QOS),
            'human': node.create_publisher(WrenchStamped, topics.HUMAN_CMD_WRENCH,
                                           qos.COMMAND_QOS)}
        self.session = node.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
        self.state_subscription = node.create_subscription(TaskState, topics.STATE,
                                                           self._on_state, qos.STATE_QOS)
        self.slice_states = []
        self.slice_subscription = node.create_subscription(
            TaskState, topics.SLICE_STATE, self.slice_states.append, qos.STATE_QOS)
        node.create_subscription(Clock, topics.CLOCK, self.clocks.append,
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        node.create_subscription(Image, topics.CAMERA_IMAGE, self.images.append,
                                 qos.VISUAL_QOS)
        node.create_subscription(MarkerArray, topics.MARKERS, self.markers.append,
                                 qos.VISUAL_QOS)
        self.reset_client = node.create_client(ResetEpisode, topics.RESET_SERVICE)

    def _on_state(self, state):
        self.states.append(state)
        self.state_times.append(time.monotonic())

    def spin_once(self):
        """Handle what arrived (waits at most 10 ms)."""
        self.executor.spin_once(timeout_sec=0.01)

    def spin(self, seconds: float):
        """Handle everything that arrives during ``seconds``."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.spin_once()

    def wait(self, condition, timeout: float = 10.0) -> bool:
        """Spin until ``condition()`` holds; return whether it did."""
        return wait_for(condition, timeout, spin=self.spin_once)

    def connect(self, timeout: float = 30.0):
        """Wait until the sim's service and subscriptions see this client."""
        ready = self.wait(lambda: self.reset_client.service_is_ready()
                          and all(publisher.get_subscription_count() > 0
                                  for publisher in self.publishers.values())
                          and self.state_subscription.get_publisher_count() > 0, timeout)
        assert ready, 'the sim node did not come up'
        # service_is_ready() means our request writer matched the server; its response writer
        # may match our reader a little later, and a response sent before is lost. Give
        # discovery a moment to finish both ways.
        self.spin(0.5)

    def reset(self, seed: int = -1, episode: int = 0, clock_mode: str = '',
              state_readers: int = 0):
        """Call /hrc/sim/reset and return the response."""
        future = self.reset_client.call_async(ResetEpisode.Request(
            seed=seed, episode=episode, clock_mode=clock_mode, state_readers=state_readers))
        assert self.wait(future.done, 10.0), 'no answer from /hrc/sim/reset'
        return future.result()

    def answer(self, actor: str, state, stamp=None, **components):
        """Publish ``actor``'s command answering ``state``; components: force_z=..., ..."""
        command = WrenchStamped()
        command.header.stamp = state.header.stamp if stamp is None else stamp
        command.header.frame_id = 'world'
        for name, value in components.items():
            part, axis = name.split('_')
            setattr(getattr(command.wrench, part), axis, float(value))
        self.publishers[actor].publish(command)

    def next_state(self, count_before: int, timeout: float = 10.0):
        """Wait for a state beyond the first ``count_before`` ones and return it."""
        assert self.wait(lambda: len(self.states) > count_before, timeout), \
            f'no new state after {count_before}'
        return self.states[count_before]

    def close(self):
        """Destroy the client node."""
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.fixture
def sim_client(rclpy_context):
    """Give a SimClient on the test's domain."""
    client = SimClient(rclpy_context)
    yield client
    client.close()

