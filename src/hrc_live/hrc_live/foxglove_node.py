"""The foxglove node: the running session, live, in Foxglove (the Foxglove WebSocket protocol).

    ros2 run hrc_live foxglove_node            # then Foxglove: Open connection, ws://localhost:8766
    hrc session --foxglove                     # the session runner starts it beside the graph

It serves, with the ``foxglove-sdk`` package, the channels of :mod:`hrc_live.foxglove_view`:
the 3D scene from the state, the subtask errors, the robot's reward and both actors' actions,
and the session's status; ``params/foxglove/hrc_layout.json`` is a Foxglove layout of them.
It only reads the session's topics (best effort to the control loop: its readers keep one
message, and each channel is logged at most ``max_rate`` times a second), so a slow viewer
cannot hold the sim, the agent or the human node.

Offline, Foxglove shows the same system from the bags: ``/robot_description`` (the URDF)
and ``/joint_states`` are recorded in every episode file.
"""

import time

import foxglove
from foxglove.channels import SceneUpdateChannel
from foxglove.messages import (Color, CubePrimitive, CylinderPrimitive, Pose, Quaternion,
                               SceneEntity, SceneUpdate, SpherePrimitive, Timestamp, Vector3)
from hrc_common import qos, topics
from hrc_common.nodes import closing_log, run_node
from hrc_common.parameter_query import ParameterQuery
from hrc_common.params import declare_parameters, ParameterError, with_overrides
from hrc_msgs.msg import AgentStep, SessionStatus, TaskState
from hrc_sim_node.physics_params import PhysicsParams
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from hrc_live.foxglove_view import (AGENT_SCHEMA, agent_record, ERRORS_SCHEMA, errors_record,
                                    FoxgloveParams, RateLimit, scene_bodies, SCENE_FRAME,
                                    SESSION_SCHEMA, session_record)

EXECUTABLE = 'foxglove_node'
SUMMARY = ('Serve the running hrc session to Foxglove over its WebSocket protocol: the 3D '
           'scene, the subtask errors, the reward and both actions, the session status.')
GEOMETRY = ('rod_length', 'pendulum_length', 'ball_radius')
# The viewer's readers: the newest message only, never a backlog that would cost the writers.
VIEW_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                      reliability=ReliabilityPolicy.BEST_EFFORT)
PRIMITIVES = {'cube': ('cubes', CubePrimitive), 'sphere': ('spheres', SpherePrimitive),
              'cylinder': ('cylinders', CylinderPrimitive)}


def scene_update(bodies: list, stamp) -> SceneUpdate:
    """Return a foxglove SceneUpdate of :func:`hrc_live.foxglove_view.scene_bodies`."""
    entities = []
    for body in bodies:
        field, primitive = PRIMITIVES[body['shape']]
        pose = Pose(position=Vector3(x=body['position'][0], y=body['position'][1],
                                     z=body['position'][2]),
                    orientation=Quaternion(x=body['orientation'][0], y=body['orientation'][1],
                                           z=body['orientation'][2], w=body['orientation'][3]))
        red, green, blue, alpha = body['colour']
        shape = primitive(pose=pose, size=Vector3(x=body['size'][0], y=body['size'][1],
                                                  z=body['size'][2]),
                          color=Color(r=red, g=green, b=blue, a=alpha))
        entities.append(SceneEntity(timestamp=Timestamp(sec=stamp.sec, nsec=stamp.nanosec),
                                    frame_id=SCENE_FRAME, id=body['id'], **{field: [shape]}))
    return SceneUpdate(entities=entities)


class FoxgloveNode(Node):

    def __init__(self):
        super().__init__('foxglove')
        self.params = declare_parameters(self, FoxgloveParams)
        self.physics = PhysicsParams()
        self.foxglove = foxglove.Context()
        try:
            self.server = foxglove.start_server(name='hrc', host=self.params.host,
                                                port=self.params.port, context=self.foxglove)
        except Exception as error:  # the SDK's own error type: the port is taken, no address
            raise ParameterError(f'port/host: cannot serve on {self.params.host}:'
                                 f'{self.params.port}: {error}') from error
        self.scene = SceneUpdateChannel('/hrc/scene', context=self.foxglove)
        self.channels = {name: foxglove.Channel(name, schema=schema, message_encoding='json',
                                                context=self.foxglove)
                         for name, schema in (('/hrc/errors', ERRORS_SCHEMA),
                                              ('/hrc/agent', AGENT_SCHEMA),
                                              ('/hrc/session', SESSION_SCHEMA))}
        self.limits = {name: RateLimit(self.params.max_rate)
                       for name in ('/hrc/scene', '/hrc/agent')}
        self.create_subscription(TaskState, topics.STATE, self.on_state, VIEW_QOS)
        self.create_subscription(AgentStep, topics.AGENT_STEP, self.on_step, VIEW_QOS)
        self.create_subscription(SessionStatus, topics.SESSION, self.on_session,
                                 qos.SESSION_QOS)
        self.sim_query = ParameterQuery(self, self.params.sim_node, GEOMETRY, self.on_geometry)
        self.session_record = None      # said again every second: a viewer that connects later
        self.create_timer(1.0, self.every_second)  # sees the session's status within a second
        self.get_logger().info(f'serving Foxglove on ws://{self.params.host}:{self.server.port}'
                               f' (Foxglove: Open connection; layout: '
                               f'params/foxglove/hrc_layout.json)')

    def on_geometry(self, values: dict) -> None:
        """Take the sim's geometry for the scene."""
        try:
            self.physics = with_overrides(PhysicsParams(), **values)
        except (ParameterError, TypeError) as error:
            self.get_logger().warning(f'/{self.params.sim_node} geometry unusable: {error}')

    def on_state(self, state: TaskState) -> None:
        if not self.limits['/hrc/scene'].admit(time.monotonic()):
            return
        self.scene.log(scene_update(scene_bodies(state, self.physics), state.header.stamp))
        self.channels['/hrc/errors'].log(errors_record(state))

    def on_step(self, step: AgentStep) -> None:
        if self.limits['/hrc/agent'].admit(time.monotonic()):
            self.channels['/hrc/agent'].log(agent_record(step))

    def on_session(self, status: SessionStatus) -> None:
        self.session_record = session_record(status)
        self.channels['/hrc/session'].log(self.session_record)

    def every_second(self) -> None:
        self.sim_query.poll()
        if self.session_record is not None:
            self.channels['/hrc/session'].log(self.session_record)

    def close(self) -> None:
        """Stop the server (its clients are told the connection closes)."""
        self.server.stop()
        closing_log(self, 'info', 'Foxglove server stopped')


def main(args=None):
    """Run the foxglove node (``ros2 run hrc_live foxglove_node``)."""
    return run_node(FoxgloveNode, EXECUTABLE, SUMMARY, FoxgloveParams, args)


if __name__ == '__main__':
    raise SystemExit(main())
