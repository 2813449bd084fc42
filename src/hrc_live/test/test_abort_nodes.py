"""An operator abort as the sim and the human node see it (each node in its own process).

The test publishes ``/hrc/session`` with phase ``aborted`` as the agent does: the realtime sim
must stop stepping at once and hold, the human node must send zero at once and keep to zero.
"""

from hrc_common import qos, topics
from hrc_common.contract import SimLimits
from hrc_testing.nodes import serve_sim_parameters, wait_for
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
from hrc_sim_node.physics import PhysicsParams
import pytest


class Peer:
    """The test's node: publishes the session and states, collects what the nodes send."""

    def __init__(self, context):
        import rclpy
        from geometry_msgs.msg import WrenchStamped
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node('test_live_abort', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.states, self.actions, self.wrenches = [], [], []
        self.node.create_subscription(TaskState, topics.STATE, self.states.append,
                                      qos.STATE_QOS)
        self.node.create_subscription(HumanAction, topics.HUMAN_ACTION, self.actions.append,
                                      qos.HUMAN_ACTION_QOS)
        self.node.create_subscription(WrenchStamped, topics.HUMAN_CMD_WRENCH,
                                      self.wrenches.append, qos.COMMAND_QOS)
        self.session = self.node.create_publisher(SessionStatus, topics.SESSION,
                                                  qos.SESSION_QOS)
        self.state = self.node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
        self.reset = self.node.create_client(ResetEpisode, topics.RESET_SERVICE)
        self.context = context
        self.sim_parameters = None

    def serve_sim_parameters(self):
        """Stand in for the sim's parameter service (a human node reads its limits there)."""
        self.sim_parameters = serve_sim_parameters(self.context,
                                                   SimLimits.of(PhysicsParams()))
        self.executor.add_node(self.sim_parameters)

    def spin(self, seconds: float = 0.05):
        self.executor.spin_once(timeout_sec=seconds)

    def wait(self, condition, timeout=60.0):
        return wait_for(condition, timeout, spin=self.spin)

    def publish_session(self, phase, message=''):
        self.session.publish(SessionStatus(
            session_id='abort-test', case_id=5, strategy='learn_together',
            robot_dof=SessionStatus.DOF_TRANSLATION, human_dof=SessionStatus.DOF_ROTATION,
            human_involved=True, human_subtasks=['pendulum'], phase=phase, message=message))

    def close(self):
        self.executor.shutdown()
        if self.sim_parameters is not None:
            self.sim_parameters.destroy_node()
        self.node.destroy_node()


@pytest.fixture
def peer(rclpy_context):
    peer = Peer(rclpy_context)
    yield peer
    peer.close()


def test_the_realtime_sim_holds_at_once_on_an_abort(start_node, peer):
    sim = start_node('hrc_sim_node', 'sim_node', parameters={
        'mode': 'realtime', 'expected_actors': [], 'start_on_launch': True,
        'marker_rate': 0.0})
    assert peer.wait(lambda: len(peer.states) >= 3), sim.output
    peer.publish_session(SessionStatus.PHASE_ABORTED, 'by the operator in episode 0')
    assert wait_for(lambda: 'aborted' in sim.output, timeout=60), sim.output
    assert 'holding, nothing applied' in sim.output
    # A sim that did not hold would publish five states a second.
    held_at = len(peer.states)
    peer.wait(lambda: False, timeout=1.5)
    assert len(peer.states) == held_at, [state.step for state in peer.states[held_at:]]
    assert not any(state.truncated for state in peer.states)
    # An explicit reset (a new episode) is still served.
    future = peer.reset.call_async(ResetEpisode.Request(seed=1, episode=1))
    assert peer.wait(future.done) and future.result().success
    assert peer.wait(lambda: any(state.episode == 1 for state in peer.states))


def test_the_human_node_sends_zero_at_once_on_an_abort(start_node, peer):
    peer.serve_sim_parameters()
    human = start_node('hrc_joystick_node', 'human_node', parameters={'input': 'sim'})
    peer.publish_session(SessionStatus.PHASE_TRAINING)
    step = [0]

    def answered_by_the_simulated_human():
        step[0] += 1
        state = TaskState(episode=0, step=step[0], pendulum_angle=0.3, ball_position=0.1)
        state.header.stamp.sec = step[0]
        peer.state.publish(state)
        peer.spin(0.2)
        return any(action.source == HumanAction.SOURCE_SIMULATED for action in peer.actions)

    assert wait_for(answered_by_the_simulated_human, timeout=60), human.output
    answered = max(action.step for action in peer.actions)
    # Everything sent for the states so far has arrived: the abort comes after.
    assert peer.wait(lambda: max(action.step for action in peer.actions) == step[0])
    before = len(peer.actions)
    peer.publish_session(SessionStatus.PHASE_ABORTED, 'by the operator')
    assert peer.wait(lambda: len(peer.actions) > before), human.output
    zero = peer.actions[before]
    assert (zero.command, zero.engaged, zero.source) == (0.0, False, HumanAction.SOURCE_NONE)
    assert zero.step == step[0] and zero.header.stamp.sec == step[0] >= answered
    assert 'aborted' in zero.source_detail
    assert peer.wait(lambda: any(w.header.stamp.sec == step[0] and w.wrench.torque.x == 0.0
                                 for w in peer.wrenches[-2:]))
    # A later state (a sim that has not seen the abort yet) is answered with zero too.
    state = TaskState(episode=0, step=step[0] + 1, pendulum_angle=0.3, ball_position=0.1)
    state.header.stamp.sec = step[0] + 1
    peer.state.publish(state)
    assert peer.wait(lambda: peer.actions[-1].step == step[0] + 1)
    assert (peer.actions[-1].command, peer.actions[-1].engaged) == (0.0, False)
    assert 'session' in human.output and 'aborted: sending zero' in human.output
