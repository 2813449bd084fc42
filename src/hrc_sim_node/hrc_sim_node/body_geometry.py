"""The bodies of the slider-pendulum-ball system: their URDF model and their poses.

Pure geometry (no PyBullet): :func:`model_urdf` gives the chain rod -> slider -> pendulum ->
ball that :class:`hrc_sim_node.physics.SliderPendulumBall` loads (and the sim publishes on
/robot_description), :func:`joint_values` its joints for a state (/joint_states),
:func:`body_poses` the centre pose of each body for a state (the sim's markers, the display's
scene). The frame and the
quantities are described in :mod:`hrc_sim_node.physics`.
"""

from __future__ import annotations

import math
import typing

from hrc_common.contract import BODY_COLOURS

if typing.TYPE_CHECKING:   # annotations only: physics imports this module
    from hrc_sim_node.physics_params import PhysicsParams, PhysicsState


# Cross sections of the visual bodies (m); they do not enter the dynamics except BEAM_HEIGHT,
# which places the ball's centre on top of the beam.
BEAM_WIDTH = 0.03
BEAM_HEIGHT = 0.01
SLIDER_SIZE = (0.05, 0.05, 0.03)
ROD_RADIUS = 0.006
# The rod and the slider are drawn behind the beam (-x, away from the viewer) so they do not
# hide it; the hinge itself is on the rod's axis.
BODY_DEPTH_OFFSET = -0.03


def _inertial(mass, com, inertia):
    ixx, iyy, izz = inertia
    return (f'<inertial><origin xyz="{com[0]} {com[1]} {com[2]}"/><mass value="{mass}"/>'
            f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'
            f'</inertial>')


def _visual(geometry, xyz, material, body):
    rgba = ' '.join(str(channel) for channel in BODY_COLOURS[body]) + ' 1'
    return (f'<visual><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}"/><geometry>{geometry}</geometry>'
            f'<material name="{material}"><color rgba="{rgba}"/></material></visual>')


def model_urdf(params: PhysicsParams) -> str:
    """Return the URDF text of the rod-slider-pendulum-ball chain for ``params``."""
    half_rod = params.rod_length / 2
    half_beam = params.pendulum_length / 2
    beam_inertia_xz = params.pendulum_mass * params.pendulum_length ** 2 / 12
    # The beam's inertia about its own length hardly matters (it never spins about y).
    beam_inertia_y = params.pendulum_mass * (BEAM_WIDTH ** 2 + BEAM_HEIGHT ** 2) / 12
    slider_inertia = params.slider_mass * (SLIDER_SIZE[0] ** 2) / 6
    # A point mass has no inertia; a tiny one keeps the solver well conditioned.
    ball_inertia = 0.4 * params.ball_mass * params.ball_radius ** 2
    ball_height = BEAM_HEIGHT / 2 + params.ball_radius
    rod = (_inertial(1.0, (0, 0, 0), (1, 1, 1))
           + _visual(f'<cylinder radius="{ROD_RADIUS}" length="{params.rod_length + 0.04}"/>',
                     (BODY_DEPTH_OFFSET, 0, 0), 'grey', 'rod'))
    slider = (_inertial(params.slider_mass, (0, 0, 0), (slider_inertia,) * 3)
              + _visual('<box size="{} {} {}"/>'.format(*SLIDER_SIZE), (BODY_DEPTH_OFFSET, 0, 0),
                        'orange', 'slider'))
    pendulum = (_inertial(params.pendulum_mass, (0, half_beam, 0),
                          (beam_inertia_xz, beam_inertia_y, beam_inertia_xz))
                + _visual(f'<box size="{BEAM_WIDTH} {params.pendulum_length} {BEAM_HEIGHT}"/>',
                          (0, half_beam, 0), 'blue', 'pendulum'))
    ball = (_inertial(params.ball_mass, (0, 0, 0), (ball_inertia,) * 3)
            + _visual(f'<sphere radius="{params.ball_radius}"/>', (0, 0, 0), 'ball_grey',
                      'ball'))
    limit = params.pendulum_limit
    return f"""<?xml version="1.0"?>
<robot name="slider_pendulum_ball">
  <link name="rod">{rod}</link>
  <link name="slider">{slider}</link>
  <link name="pendulum">{pendulum}</link>
  <link name="ball">{ball}</link>
  <joint name="slide" type="prismatic">
    <parent link="rod"/><child link="slider"/><origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="{-half_rod}" upper="{half_rod}" effort="1e6" velocity="1e6"/>
  </joint>
  <joint name="hinge" type="revolute">
    <parent link="slider"/><child link="pendulum"/><origin xyz="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="{-limit}" upper="{limit}" effort="1e6" velocity="1e6"/>
  </joint>
  <joint name="roll" type="prismatic">
    <parent link="pendulum"/><child link="ball"/><origin xyz="0 {half_beam} {ball_height}"/>
    <axis xyz="0 1 0"/>
    <limit lower="{-half_beam}" upper="{half_beam}" effort="1e6" velocity="1e6"/>
  </joint>
</robot>
"""


# The model's movable joints, in /joint_states order: the slider along the rod (m), the beam's
# hinge (rad), the ball along the beam from its middle (m).
JOINT_NAMES = ('slide', 'hinge', 'roll')


def joint_values(state: PhysicsState) -> tuple:
    """Return (positions, velocities) of :data:`JOINT_NAMES` for ``state``."""
    return ((state.slider_position, state.pendulum_angle, state.ball_position),
            (state.slider_velocity, state.pendulum_angular_velocity, state.ball_velocity))


def _rotation_about_x(angle: float) -> tuple:
    """Quaternion (x, y, z, w) of a rotation by ``angle`` (rad) about the world x axis."""
    return (math.sin(angle / 2), 0.0, 0.0, math.cos(angle / 2))


def body_poses(state: PhysicsState, params: PhysicsParams) -> dict:
    """Return the centre pose of each body for ``state`` (pure geometry, no PyBullet).

    {'rod' | 'slider' | 'pendulum' | 'ball': ((x, y, z) m, (qx, qy, qz, qw))} in the world
    frame, matching the model's joints: hinge at the slider's centre, beam reaching east.
    """
    angle = state.pendulum_angle
    cos_angle, sin_angle = math.cos(angle), math.sin(angle)
    hinge_height = state.slider_position
    half_beam = params.pendulum_length / 2
    # The ball's centre: along the beam from the hinge, lifted by the ball's height above it.
    along = half_beam + state.ball_position
    above = BEAM_HEIGHT / 2 + params.ball_radius
    identity = (0.0, 0.0, 0.0, 1.0)
    return {
        'rod': ((BODY_DEPTH_OFFSET, 0.0, 0.0), identity),
        'slider': ((BODY_DEPTH_OFFSET, 0.0, hinge_height), identity),
        'pendulum': ((0.0, half_beam * cos_angle, hinge_height + half_beam * sin_angle),
                     _rotation_about_x(angle)),
        'ball': ((0.0, along * cos_angle - above * sin_angle,
                  hinge_height + along * sin_angle + above * cos_angle),
                 _rotation_about_x(angle)),
    }


def body_shapes(params: PhysicsParams) -> dict:
    """Return {body: (shape, (x, y, z) size in m)} of the viewers' scene (markers, Foxglove).

    ``shape``: 'cylinder' | 'cube' | 'sphere'; the sizes of the model's visuals (the rod drawn
    a little longer than the slider's travel), centred on :func:`body_poses`.
    """
    return {'rod': ('cylinder', (2 * ROD_RADIUS, 2 * ROD_RADIUS, params.rod_length + 0.04)),
            'slider': ('cube', SLIDER_SIZE),
            'pendulum': ('cube', (BEAM_WIDTH, params.pendulum_length, BEAM_HEIGHT)),
            'ball': ('sphere', (2 * params.ball_radius,) * 3)}
