"""The slider-pendulum-ball system of the paper, simulated with PyBullet (no ROS in here).

Description
-----------
A vertical rod (``rod_length`` = 0.2 m) carries a slider that moves along it. A pendulum, a
beam of ``pendulum_length`` = 0.5 m, hangs on a hinge on the slider; the hinge holds the beam at
its *west end*, so the beam reaches east from the rod. A ball sits on the beam and moves along
it between two end stops at the beam's ends. Two actors share the system: one pushes the slider
along the rod (a force), the other turns the pendulum about its hinge (a torque).

Frame (``hrc_common.dof``): x toward the viewer (the hinge axis), y east, z up.

State: :class:`~hrc_sim_node.physics_params.PhysicsState` (quantities, units, bounds);
parameters: :class:`~hrc_sim_node.physics_params.PhysicsParams` (with the reasons for the
defaults: the human's rate, the integration, the force and torque limits).

Actions
-------
``step(force, torque)``: ``force`` (N, + up) on the slider along the rod and ``torque``
(N*m, + raises the east end) on the pendulum about its hinge, held constant over one control
period (``control_period`` = 0.2 s, ``substeps`` physics steps). Each is clamped to
``[-max_force, max_force]`` and ``[-max_torque, max_torque]``; a non-finite value raises
ValueError. ``step_normalized(translation, rotation)`` takes commands in [-1, 1] (clamped) and
scales them by the limits.

Dynamics
--------
PyBullet (Featherstone multibody, DIRECT mode by default) integrates a chain of three joints:

* ``slide``: prismatic along world z, rod -> slider, hard limits at the rod's ends;
* ``hinge``: revolute about world x, slider -> pendulum, hard limits at +-``pendulum_limit``
  (the beam cannot swing through the rod it hangs on);
* ``roll``: prismatic along the beam, pendulum -> ball, hard limits at the beam's ends (the
  end stops that keep the ball on the pendulum, so no restart is ever needed).

PyBullet's joint limits pass an impact's impulse on to the other bodies; a body that still
went past its stop within a substep is put back on it with its outward velocity dropped, so
every reported position lies within its bounds exactly (the stops are inelastic).

The ball is a point mass on a prismatic joint (sliding, not spinning) with viscous rolling
resistance. A real rolling sphere (contacts and friction) would add the 2/7 share of spin
inertia but makes contact solving part of every step, slower and sensitive to solver details;
the prismatic ball is exact, deterministic and fast. Its centre sits ``ball_radius`` above the
beam's axis, as a ball resting on top of the beam.

Viscous damping (``slider_damping``, ``pendulum_damping``, ``ball_damping``) acts on each
joint, applied explicitly at every substep (``params.check`` refuses values that would make
that unstable). With the damping the slider and the pendulum respond to a held command by
settling to a speed (force / damping) within about 0.1-0.2 s, which a person at a joystick and
an agent sampling every 0.2 s can both follow.

Couplings (both actions affect both level-2 subtasks, as in the paper):

* translation -> rotation: the pendulum's centre of mass lies ``pendulum_length/2`` east of the
  hinge, so accelerating the slider up presses the east end down (and down lifts it): a torque
  ``-m_p * d * a_slider * cos(P_z)`` on the hinge;
* rotation -> translation: turning the pendulum accelerates its centre of mass up or down, and
  the reaction ``-m_p * d * (P_z'' cos P_z - P_z'^2 sin P_z)`` pushes the slider the other way;
* level 2 -> level 1: along the beam the ball feels ``-(g + a_slider) * sin(P_z)`` (gravity
  and the slider's acceleration tilted into the beam) plus the centrifugal term; hence the ball
  is far more sensitive to the pendulum angle than to the slider (at P_z = 0 the slider does
  not move the ball at all);
* level 1 -> level 2: the ball off the middle puts ``m_b * g * B_y * cos(P_z)`` of torque on
  the hinge (east of the middle presses the east end down).

Gravity
-------
``gravity`` acts on every body. With ``gravity_compensation`` on (default), the model includes
what a counterweight would do (a static compensation, computed at every substep):

* a constant force ``(m_slider + m_pendulum + m_ball) * g`` up on the slider, so the slider
  with its load floats where it is;
* a torque ``g * (m_p * d * cos P_z + m_b * (L/2 * cos P_z - r_b * sin P_z))`` on the hinge,
  which balances the beam's weight and the weight of the ball *when the ball is in the middle*.

The ball's displacement from the middle is never compensated: its motion and its torque on the
beam are the task. Hence a released joystick (zero command) leaves the slider and the
pendulum where they are (damped); only the ball rolls downhill and, once off the middle, slowly
tips the beam toward its side (at most ``m_b * g * L/2`` = 0.12 N*m, a quarter of
``max_torque``), so every state stays recoverable and the task is never made impossible by
letting go. Without compensation the slider would drop to the bottom stop within half a second
and the beam would swing down, which a 5 Hz joystick loop cannot catch.

Reward
------
None here: the agent owns the reward (the task tree).

Episode start
-------------
``reset(seed)``: slider, pendulum and ball start at rest at positions drawn uniformly from
``[-initial_*_spread, initial_*_spread]`` with a numpy Generator seeded by ``seed``; with
``seed=None`` the generator of the previous reset continues (seeded from the OS entropy if
never seeded), as in Gymnasium.

Episode end
-----------
Truncation after ``episode_duration`` = 40 s (``steps_per_episode`` = 200 control steps): the
state of step 200 has ``truncated`` set. Nothing terminates the episode (``terminated`` is
always false): the end stops keep every body on the model. ``step()`` after the last step
raises RuntimeError; call ``reset()``.
"""

from dataclasses import fields
import math
import os
import tempfile

import numpy

from hrc_common.params import checked
from hrc_sim_node.body_geometry import BEAM_HEIGHT, model_urdf
from hrc_sim_node.physics_params import PhysicsParams, PhysicsState

# PyBullet joint indices of the chain rod -> slider -> pendulum -> ball.
SLIDE_JOINT, HINGE_JOINT, ROLL_JOINT = 0, 1, 2
JOINTS = (SLIDE_JOINT, HINGE_JOINT, ROLL_JOINT)




def _finite(name: str, value) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f'{name} must be finite, got {value!r}')
    return value


def _clamp(value: float, bound: float) -> float:
    return max(-bound, min(bound, value))


def _period_mean(values: list, weights: list) -> float:
    """Return the time-weighted mean of a period's slices; a value held throughout exactly."""
    if all(value == values[0] for value in values):
        return values[0]
    return sum(value * weight for value, weight in zip(values, weights))


class SliderPendulumBall:
    """The slider-pendulum-ball system (see the module docstring: state, actions, dynamics).

    Each instance owns a private PyBullet physics client (DIRECT by default, GUI on request),
    so several instances can live in one process. Call :meth:`reset` before :meth:`step`.
    """

    def __init__(self, params: PhysicsParams = None, gui: bool = False):
        import pybullet  # lazy: PyBullet, PhysicsParams serves modules that never simulate

        self._client = None

        self.params = checked(params if params is not None else PhysicsParams())
        if gui and not os.environ.get('DISPLAY'):
            # PyBullet would end the whole process ("cannot connect to X server").
            raise RuntimeError('the PyBullet GUI needs a display and DISPLAY is not set')
        self._bullet = pybullet
        self._client = pybullet.connect(pybullet.GUI if gui else pybullet.DIRECT)
        if self._client < 0:
            raise RuntimeError('PyBullet could not connect (GUI needs a display)')
        self._rng = None
        self._state = None
        self._clear_period()
        self._build()

    def _clear_period(self) -> None:
        """Forget the running control period's slices (at a reset and at each period's end)."""
        self._joint_cache = None         # joint states after the last slice of this period
        self._period_applied = []        # (force N, torque N*m, share of the period) per slice
        self._period_substeps = 0

    # -- model -----------------------------------------------------------------------------
    def _build(self):
        bullet, client, params = self._bullet, self._client, self.params
        bullet.resetSimulation(physicsClientId=client)
        bullet.setGravity(0, 0, -params.gravity, physicsClientId=client)
        bullet.setPhysicsEngineParameter(fixedTimeStep=params.time_step, numSubSteps=0,
                                         physicsClientId=client)
        with tempfile.NamedTemporaryFile('w', suffix='.urdf', delete=False) as urdf:
            urdf.write(model_urdf(params))
        try:
            self._body = bullet.loadURDF(urdf.name, useFixedBase=True,
                                         flags=bullet.URDF_USE_INERTIA_FROM_FILE,
                                         physicsClientId=client)
        finally:
            os.unlink(urdf.name)
        for joint in JOINTS:
            # PyBullet adds a little damping of its own by default; the model has its own.
            bullet.changeDynamics(self._body, joint, linearDamping=0.0, angularDamping=0.0,
                                  jointDamping=0.0, physicsClientId=client)
        # Joints default to a velocity motor holding them still: switch it off.
        bullet.setJointMotorControlArray(self._body, JOINTS, bullet.VELOCITY_CONTROL,
                                         forces=[0.0, 0.0, 0.0], physicsClientId=client)
        carried_mass = params.slider_mass + params.pendulum_mass + params.ball_mass
        self._slider_compensation = carried_mass * params.gravity
        self._ball_height = BEAM_HEIGHT / 2 + params.ball_radius
        self._stops = (params.rod_length / 2, params.pendulum_limit, params.pendulum_length / 2)

    def _joint_states(self):
        states = self._bullet.getJointStates(self._body, JOINTS, physicsClientId=self._client)
        return [(position, velocity) for position, velocity, _, _ in states]

    def _hold_at_stops(self, joint_states):
        """Put a joint that went past its stop back on it and drop its outward velocity.

        PyBullet's joint limits pass the impact's impulse on to the other bodies but let a
        fast body sink up to about v * dt (mm) past the stop for a substep; this projection
        keeps every reported position within its documented bounds.
        """
        held = []
        for joint, (position, velocity), bound in zip(JOINTS, joint_states, self._stops):
            if abs(position) > bound:
                position = math.copysign(bound, position)
                if velocity * position > 0:  # still moving outward
                    velocity = 0.0
                self._bullet.resetJointState(self._body, joint, position, velocity,
                                             physicsClientId=self._client)
            held.append((position, velocity))
        return held

    def _compensation_torque(self, angle: float) -> float:
        """Counterweight torque on the hinge: beam and ball-in-the-middle weights (N*m)."""
        params = self.params
        cos_angle, sin_angle = math.cos(angle), math.sin(angle)
        beam = params.pendulum_mass * params.pendulum_com_distance * cos_angle
        ball = params.ball_mass * (params.pendulum_length / 2 * cos_angle
                                   - self._ball_height * sin_angle)
        return params.gravity * (beam + ball)

    # -- episode -----------------------------------------------------------------------------
    def reset(self, seed: int = None) -> PhysicsState:
        """Start an episode at rest from a seeded random configuration; return step 0."""
        if seed is not None:
            self._rng = numpy.random.default_rng(seed)
        elif self._rng is None:
            self._rng = numpy.random.default_rng()
        params = self.params
        slider = self._rng.uniform(-params.initial_slider_spread, params.initial_slider_spread)
        angle = self._rng.uniform(-params.initial_angle_spread, params.initial_angle_spread)
        ball = self._rng.uniform(-params.initial_ball_spread, params.initial_ball_spread)
        # Rebuilding the world (a few ms) rather than moving the joints makes every episode
        # independent of the previous one: no solver warm start carries over.
        self._build()
        self._clear_period()
        for joint, position in zip(JOINTS, (slider, angle, ball)):
            self._bullet.resetJointState(self._body, joint, float(position), 0.0,
                                         physicsClientId=self._client)
        self._state = self._read_state(0, 0.0, 0.0)
        return self._state

    def step(self, force: float, torque: float) -> PhysicsState:
        """Hold ``force`` (N) and ``torque`` (N*m) for one control period; return the state.

        Values beyond the limits are clamped to ``max_force``/``max_torque``; non-finite
        values raise ValueError (nothing is applied then).
        """
        self.advance(force, torque, self.params.substeps - self._period_substeps)
        return self.finish_period()

    def advance(self, force: float, torque: float, substeps: int) -> PhysicsState:
        """Hold ``force`` (N) and ``torque`` (N*m) for ``substeps`` physics substeps.

        A part of the control period (a human slice, ``substeps_per_slice``): the period's
        step index does not change; :meth:`finish_period` ends the period. Returns the state
        now, mid-period (what a person sees at that moment; ``time`` includes the slice),
        whose ``applied_*`` are this slice's. Clamping and refusals as :meth:`step`.
        """
        force = _clamp(_finite('force', force), self.params.max_force)
        torque = _clamp(_finite('torque', torque), self.params.max_torque)
        if self._state is None:
            raise RuntimeError('call reset() before step()')
        if self._state.truncated or self._state.terminated:
            raise RuntimeError(f'the episode ended at step {self._state.step}: call reset()')
        substeps = int(substeps)
        if not 0 < substeps <= self.params.substeps - self._period_substeps:
            raise ValueError(f'{substeps} substeps do not fit in the control period '
                             f'({self._period_substeps} of {self.params.substeps} done)')
        bullet, client, body, params = self._bullet, self._client, self._body, self.params
        compensate = params.gravity_compensation
        torque_control = bullet.TORQUE_CONTROL
        joint_states = self._joint_cache or self._joint_states()
        for _ in range(substeps):
            (_, slider_velocity), (angle, angular_velocity), (_, ball_velocity) = joint_states
            slider_force = force - params.slider_damping * slider_velocity
            hinge_torque = torque - params.pendulum_damping * angular_velocity
            if compensate:
                slider_force += self._slider_compensation
                hinge_torque += self._compensation_torque(angle)
            ball_force = -params.ball_damping * ball_velocity
            # PyBullet applies a torque-control command for the next substep only.
            bullet.setJointMotorControlArray(body, JOINTS, torque_control,
                                             forces=[slider_force, hinge_torque, ball_force],
                                             physicsClientId=client)
            bullet.stepSimulation(physicsClientId=client)
            joint_states = self._hold_at_stops(self._joint_states())
        self._joint_cache = joint_states
        # The period's applied wrench is the time-weighted mean of its slices; a whole period
        # held at one value gives that value exactly (weight 1.0).
        weight = substeps / params.substeps
        self._period_applied.append((force, torque, weight))
        self._period_substeps += substeps
        return self._read_state(self._state.step, force, torque,
                                elapsed=self._period_substeps * params.time_step)

    def finish_period(self) -> PhysicsState:
        """End the control period (every substep must be done); return the new step's state.

        Its ``applied_force``/``applied_torque`` are the period's time-weighted means.
        """
        if self._period_substeps != self.params.substeps:
            raise RuntimeError(f'the control period is not complete: {self._period_substeps} '
                               f'of {self.params.substeps} substeps done')
        force = _period_mean([value for value, _, _ in self._period_applied],
                             [weight for _, _, weight in self._period_applied])
        torque = _period_mean([value for _, value, _ in self._period_applied],
                              [weight for _, _, weight in self._period_applied])
        self._clear_period()
        step = self._state.step + 1
        self._state = self._read_state(step, force, torque)
        return self._state

    @property
    def period_substeps(self) -> int:
        """Substeps done in the running control period (0 at its start)."""
        return self._period_substeps

    def step_normalized(self, translation: float, rotation: float) -> PhysicsState:
        """Step with commands in [-1, 1] (clamped) scaled by ``max_force``/``max_torque``."""
        translation = _clamp(_finite('translation', translation), 1.0)
        rotation = _clamp(_finite('rotation', rotation), 1.0)
        return self.step(translation * self.params.max_force,
                         rotation * self.params.max_torque)

    def _read_state(self, step: int, force: float, torque: float,
                    elapsed: float = 0.0) -> PhysicsState:
        (slider, slider_velocity), (angle, angular_velocity), (ball, ball_velocity) = \
            self._joint_states()
        time = step * self.params.control_period
        if elapsed:
            time += elapsed
        return PhysicsState(
            step=step, time=time,
            slider_position=slider, slider_velocity=slider_velocity,
            pendulum_angle=angle, pendulum_angular_velocity=angular_velocity,
            ball_position=ball, ball_velocity=ball_velocity,
            applied_force=force, applied_torque=torque,
            terminated=False, truncated=step >= self.params.steps_per_episode)

    @property
    def state(self) -> PhysicsState:
        """The state after the last reset or step."""
        if self._state is None:
            raise RuntimeError('call reset() first')
        return self._state

    # -- output ------------------------------------------------------------------------------
    def render(self, width: int = 320, height: int = 240) -> numpy.ndarray:
        """Return an RGB image (uint8, shape (height, width, 3)) seen from the viewer (+x)."""
        bullet, client = self._bullet, self._client
        target = (0.0, self.params.pendulum_length * 0.35, 0.0)
        view = bullet.computeViewMatrix(cameraEyePosition=(1.3, target[1], 0.05),
                                        cameraTargetPosition=target, cameraUpVector=(0, 0, 1),
                                        physicsClientId=client)
        projection = bullet.computeProjectionMatrixFOV(fov=45.0, aspect=width / height,
                                                       nearVal=0.1, farVal=5.0,
                                                       physicsClientId=client)
        _, _, rgba, _, _ = bullet.getCameraImage(width, height, view, projection,
                                                 renderer=bullet.ER_TINY_RENDERER,
                                                 physicsClientId=client)
        image = numpy.asarray(rgba, dtype=numpy.uint8).reshape(height, width, 4)
        return numpy.ascontiguousarray(image[:, :, :3])

    def close(self):
        """Disconnect the physics client (idempotent)."""
        client = getattr(self, '_client', None)
        if client is not None and client >= 0:
            try:
                self._bullet.disconnect(physicsClientId=client)
            except Exception:  # already gone (interpreter shutdown)
                pass
        self._client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    def __del__(self):
        self.close()


def physics_params_of(params) -> PhysicsParams:
    """Return the PhysicsParams part of any object carrying those fields (e.g. SimParams)."""
    return PhysicsParams(**{dataclass_field.name: getattr(params, dataclass_field.name)
                            for dataclass_field in fields(PhysicsParams)})
