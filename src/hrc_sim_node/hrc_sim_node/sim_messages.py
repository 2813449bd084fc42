"""The sim node's messages: TaskState, markers and stamps from the physics' values.

The ROS side of :mod:`hrc_sim_node.sim_node` (it converts, nothing here decides).
"""

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from hrc_common.contract import BODY_COLOURS
from hrc_msgs.msg import TaskState
from hrc_sim_node.body_geometry import body_poses, body_shapes, JOINT_NAMES, joint_values
from hrc_sim_node.commands import HUMAN, ROBOT
from hrc_sim_node.physics_params import PhysicsParams
from hrc_sim_node.protocol import stamp_fields
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray


def stamp_of(nanoseconds: int) -> Time:
    """Return a builtin_interfaces/Time for a simulation time in nanoseconds."""
    sec, nanosec = stamp_fields(nanoseconds)
    return Time(sec=sec, nanosec=nanosec)


def state_message(state, episode: int, stamp: Time, missing: dict, slice_index: int = 0,
                  human_applied=()) -> TaskState:
    """Convert a PhysicsState into a TaskState message (``slice_index`` > 0: a slice state)."""
    message = TaskState(
        episode=episode, step=state.step,
        slider_position=state.slider_position, slider_velocity=state.slider_velocity,
        pendulum_angle=state.pendulum_angle,
        pendulum_angular_velocity=state.pendulum_angular_velocity,
        ball_position=state.ball_position, ball_velocity=state.ball_velocity,
        applied_force=state.applied_force, applied_torque=state.applied_torque,
        robot_command_missing=bool(missing.get(ROBOT, False)),
        human_command_missing=bool(missing.get(HUMAN, False)),
        slice=int(slice_index), human_applied=[float(value) for value in human_applied],
        terminated=state.terminated, truncated=state.truncated)
    message.header.stamp = stamp
    message.header.frame_id = 'world'
    return message


def joint_state_message(state, stamp: Time) -> JointState:
    """Return the /joint_states message of a period's state (stamped as the state)."""
    positions, velocities = joint_values(state)
    message = JointState(name=list(JOINT_NAMES), position=[float(value) for value in positions],
                         velocity=[float(value) for value in velocities])
    message.header.stamp = stamp
    message.header.frame_id = 'world'
    return message


# Marker looks: id, RViz type, size (m) and colour of each body (the paper's colours).
MARKER_IDS = {'rod': 0, 'slider': 1, 'pendulum': 2, 'ball': 3}
MARKER_TYPES = {'cylinder': Marker.CYLINDER, 'cube': Marker.CUBE, 'sphere': Marker.SPHERE}


def marker_array(state, params: PhysicsParams, stamp: Time) -> MarkerArray:
    """Return the rod, slider, pendulum and ball as RViz/Foxglove markers in frame 'world'."""
    shapes = body_shapes(params)
    markers = MarkerArray()
    for name, (position, orientation) in body_poses(state, params).items():
        shape, size = shapes[name]
        rgb = BODY_COLOURS[name]
        marker = Marker(ns='hrc_sim', id=MARKER_IDS[name], type=MARKER_TYPES[shape],
                        action=Marker.ADD)
        marker.header.stamp = stamp
        marker.header.frame_id = 'world'
        marker.pose = Pose(position=Point(x=position[0], y=position[1], z=position[2]),
                           orientation=Quaternion(x=orientation[0], y=orientation[1],
                                                  z=orientation[2], w=orientation[3]))
        marker.scale = Vector3(x=float(size[0]), y=float(size[1]), z=float(size[2]))
        marker.color = ColorRGBA(r=rgb[0], g=rgb[1], b=rgb[2], a=1.0)
        markers.markers.append(marker)
    return markers


class SimVisuals:
    """The sim node's markers and camera image on their timers (a mixin of SimNode)."""

    def _publish_markers(self):
        if self._state is None:
            return
        self._marker_pub.publish(marker_array(self._state, self.params,
                                              stamp_of(self.protocol.sim_time_ns)))

    def _publish_image(self):
        if self._state is None:
            return
        width, height = self.params.image_width, self.params.image_height
        pixels = self.physics.render(width, height)
        image = Image(height=height, width=width, encoding='rgb8', is_bigendian=0,
                      step=width * 3, data=pixels.tobytes())
        image.header.stamp = stamp_of(self.protocol.sim_time_ns)
        image.header.frame_id = 'world'
        self._image_pub.publish(image)
