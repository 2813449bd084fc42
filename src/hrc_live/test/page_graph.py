"""The display node's test graph: a real sim, the display node, a stand-in agent, a browser.

Shared by the page tests (the ``graph`` fixture of this folder's conftest.py): the stand-in
agent publishes the agent's topics and serves its parameters and operator services; the sim
runs with a non-default pendulum length so that the page must take the sim's geometry.
"""

import json
import re
import threading
import urllib.request

from hrc_common import qos, topics
from hrc_msgs.msg import EpisodeSummary, HumanAction, SessionStatus, TaskState
from hrc_sim_node.physics import PhysicsParams
from hrc_testing.nodes import wait_for
from std_srvs.srv import Trigger

PENDULUM_LENGTH = 0.4  # not the default 0.5: the display must take it from the sim
PHYSICS = PhysicsParams(pendulum_length=PENDULUM_LENGTH)

def served_port(process) -> int:
    found = []

    def logged():
        match = re.search(r'serving the display on http://127\.0\.0\.1:(\d+)/', process.output)
        if match:
            found.append(int(match.group(1)))
        return bool(found)

    assert wait_for(logged, timeout=60), process.output
    return found[0]


def fetch(port, path):
    with urllib.request.urlopen(f'http://127.0.0.1:{port}{path}', timeout=10) as answer:
        return answer.status, answer.read()


def status(port) -> dict:
    return json.loads(fetch(port, '/status.json')[1])


def task_state(episode, step, slider, angle, ball, final=False):
    message = TaskState(episode=episode, step=step, slider_position=slider, pendulum_angle=angle,
                        ball_position=ball, truncated=final)
    message.header.stamp.sec = step
    return message


def session_status(**values):
    message = SessionStatus(session_id='display-test', case_id=2,
                            strategy='responsibility_guided', training_step=1,
                            training_step_count=2, robot_dof=SessionStatus.DOF_ROTATION,
                            human_dof=SessionStatus.DOF_TRANSLATION, human_involved=True,
                            human_subtasks=['slider', 'ball'], episode=3, total_episodes=3,
                            human_involved_episodes=1, phase=SessionStatus.PHASE_TRAINING)
    for name, value in values.items():
        setattr(message, name, value)
    return message


def close_to(pixel, color, tolerance=14):
    return all(abs(int(a) - int(b)) <= tolerance for a, b in zip(pixel, color))


class FakeAgent:
    """The agent's side of the display: parameters, topics, operator services; spun in a thread."""

    def __init__(self, context):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node('agent', context=context)
        for name, value in (('max_training_episodes', 30), ('evaluation_episodes', 2),
                            ('episode_break', 4.0), ('mode', 'realtime')):
            self.node.declare_parameter(name, value)
        self.session = self.node.create_publisher(SessionStatus, topics.SESSION,
                                                  qos.SESSION_QOS)
        self.state = self.node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
        self.slice_state = self.node.create_publisher(TaskState, topics.SLICE_STATE,
                                                      qos.STATE_QOS)
        self.episode = self.node.create_publisher(EpisodeSummary, topics.EPISODE,
                                                  qos.EPISODE_QOS)
        self.human = self.node.create_publisher(HumanAction, topics.HUMAN_ACTION,
                                                qos.HUMAN_ACTION_QOS)
        self.calls = []

        def serve(name):
            def answer(request, response):
                self.calls.append(name)
                response.success, response.message = True, f'{name} requested (test agent)'
                return response
            return answer

        for name in ('pause', 'resume', 'abort'):
            self.node.create_service(Trigger, f'/hrc/agent/{name}', serve(name))
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.spin, daemon=True)
        self.running = True
        self.thread.start()

    def spin(self):
        while self.running:
            self.executor.spin_once(timeout_sec=0.05)

    def close(self):
        self.running = False
        self.thread.join(5)
        self.executor.shutdown()
        self.node.destroy_node()
