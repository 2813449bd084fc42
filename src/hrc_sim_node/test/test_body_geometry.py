"""The joints the sim publishes on /joint_states move the URDF as the scene's bodies move.

Two geometry paths: the URDF (what PyBullet loads and /robot_description carries) with the
joint values of :func:`joint_values`, and :func:`body_poses` (the markers, the page). The ball's
centre found by walking the URDF's joints must be where body_poses puts it.
"""

import math
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

from hrc_sim_node.body_geometry import body_poses, JOINT_NAMES, joint_values, model_urdf
from hrc_sim_node.physics_params import PhysicsParams, PhysicsState


def rotation_about(axis, angle):
    """Rotation matrix about a unit ``axis`` by ``angle`` (Rodrigues)."""
    x, y, z = axis
    cross = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def ball_from_the_urdf(urdf: str, values: dict) -> np.ndarray:
    """Walk rod -> slider -> pendulum -> ball through the URDF's joints; the ball's origin."""
    position, rotation = np.zeros(3), np.eye(3)
    for joint in ElementTree.fromstring(urdf).iter('joint'):
        origin = np.array([float(v) for v in joint.find('origin').get('xyz').split()])
        axis = np.array([float(v) for v in joint.find('axis').get('xyz').split()])
        position = position + rotation @ origin
        value = values[joint.get('name')]
        if joint.get('type') == 'prismatic':
            position = position + rotation @ (axis * value)
        else:
            rotation = rotation @ rotation_about(axis, value)
    return position


def state(slider, angle, ball):
    return PhysicsState(step=3, time=0.6, slider_position=slider, slider_velocity=0.1,
                        pendulum_angle=angle, pendulum_angular_velocity=-0.2,
                        ball_position=ball, ball_velocity=0.3, applied_force=0.0,
                        applied_torque=0.0, terminated=False, truncated=False)


@pytest.mark.parametrize('slider, angle, ball', [
    (0.0, 0.0, 0.0), (0.12, 0.3, -0.2), (-0.3, -0.5, 0.25), (0.05, 0.9, 0.4)])
def test_the_published_joints_place_the_ball_where_the_scene_draws_it(slider, angle, ball):
    params = PhysicsParams()
    urdf = model_urdf(params)
    movable = [joint.get('name') for joint in ElementTree.fromstring(urdf).iter('joint')]
    assert tuple(movable) == JOINT_NAMES
    positions, velocities = joint_values(state(slider, angle, ball))
    assert velocities == (0.1, -0.2, 0.3)
    walked = ball_from_the_urdf(urdf, dict(zip(JOINT_NAMES, positions)))
    drawn = np.array(body_poses(state(slider, angle, ball), params)['ball'][0])
    assert walked[1:] == pytest.approx(drawn[1:], abs=1e-12)   # y, z: the plane of motion
    assert walked[0] == pytest.approx(0.0)
