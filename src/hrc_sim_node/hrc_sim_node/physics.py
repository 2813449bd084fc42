"""The slider-pendulum-ball system of the paper, simulated with PyBullet (no ROS in here).

Description
-----------
A vertical rod (``rod_length`` = 0.2 m) carries a slider that moves along it. A pendulum, a
beam of ``pendulum_length`` = 0.5 m, hangs on a hinge on the slider; the hinge holds the beam at
its *west end*, so the beam reaches east from the rod. A ball sits on the beam and moves along
it between two end stops at the beam's ends. Two actors share the system: one pushes the slider
along the rod (a force), the other turns the pendulum about its hinge (a torque).

Frame (``hrc_common.dof``): x toward the viewer (the hinge axis), y east, z up.

State (:class:`PhysicsState`)
-----------------------------
====  =============================  ======  ================================================
      quantity                       unit    bounds
====  =============================  ======  ================================================
S_x   ``slider_position``            m       [-rod_length/2, rod_length/2] = [-0.1, 0.1]
      ``slider_velocity``            m/s     (damped, a few 0.1 m/s at most)
P_z   ``pendulum_angle``             rad     [-pendulum_limit, pendulum_limit] = [-pi/2, pi/2]
      ``pendulum_angular_velocity``  rad/s
B_y   ``ball_position``              m       [-pendulum_length/2, pendulum_length/2]
      ``ball_velocity``              m/s
====  =============================  ======  ================================================

S_x = 0 is the middle of the rod (+ up); P_z = 0 is the horizontal beam pointing east, + raises
the east end; B_y = 0 is the middle of the beam, + toward the east end.

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

The human's rate: ``human_period`` (default 0.02 s) splits a control period into slices of
``substeps_per_slice`` substeps; :meth:`SliderPendulumBall.advance` holds a wrench for one
slice and :meth:`SliderPendulumBall.finish_period` ends the period (``step`` is both, for one
wrench held all period). Why 0.02 s (a modelling choice): a person acts continuously, a
joystick streams its position at 100+ Hz and the ``joy`` node at 20-50 Hz (facts); a 20 ms
sample-and-hold adds 10 ms of lag on average, a tenth or less of a human operator's effective
delay of 0.1-0.3 s (McRuer's crossover model), where the robot's 0.2 s period added up to
200 ms and made the rotation role nearly impossible (the ball's offset doubles every ~0.45 s
with no torque); 0.02 s is the joy node's highest usual rate and divides the 10 ms substep
grid. ``human_period = control_period`` is the behaviour before the human had its own rate.

Integration: ``substeps`` = 20 steps of 10 ms per control period. Against a 400-substep
reference, a 12 s closed-loop run deviates by at most 2 mm (slider), 0.012 rad (pendulum) and
3 mm (ball) with 20 substeps, twice that with 10, half with 40 (first order); 20 keeps the
core at several thousand control steps per second on one core.

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

Force and torque limits
-----------------------
The lower bound of each limit is what the actor must overcome; above it, the limit sets how
hard a full command (a fully deflected joystick, a saturated policy) pushes in 0.2 s.

* ``max_torque`` = 0.5 N*m: four times the largest torque of the ball (0.12 N*m at an end
  stop), so the rotation actor can always bring the ball back; full command turns the beam at
  up to 1 rad/s against ``pendulum_damping`` = 0.5 N*m*s/rad (0.2 rad per control period), a
  rate a person can follow on the screen.
* ``max_force`` = 2 N: above the largest reaction the turning pendulum puts on the slider
  (about 1.5 N at full torque, for less than 0.1 s); full command moves the slider at up to
  0.2 m/s against ``slider_damping`` = 10 N*s/m (the whole rod in 1 s, 0.04 m per period).

Measured (test/test_physics.py and the package README): a cascaded PD controller sampled
every 0.2 s holds the ball within a few mm on average, and still within about 1 cm when it
reacts a whole control period late, as a person does; with zero input the ball hits an end
stop within a few seconds. The same controller does as well with ``max_torque`` anywhere from
0.15 to 1 N*m: a team that stays near the middle rarely needs the full torque, so the limit is
chosen for recovery and for the feel of the joystick, not for holding.

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

from dataclasses import dataclass, fields
import math
import os
import tempfile

import numpy

from hrc_common.contract import SimLimits
from hrc_common.params import checked, param
from hrc_sim_node.body_geometry import BEAM_HEIGHT, model_urdf

# PyBullet joint indices of the chain rod -> slider -> pendulum -> ball.
SLIDE_JOINT, HINGE_JOINT, ROLL_JOINT = 0, 1, 2
JOINTS = (SLIDE_JOINT, HINGE_JOINT, ROLL_JOINT)


@dataclass
class PhysicsParams:
    """Physical and timing parameters of :class:`SliderPendulumBall` (SI units)."""

    control_period: float = param(
        0.2, "control period (s): one action is held this long; the paper's sample time",
        low=0.01, high=1.0)
    substeps: int = param(
        20, 'physics substeps per control period (step = control_period / substeps)',
        low=1, high=1000)
    human_period: float = param(
        0.02, "period (s) at which the human's command is applied within a control period "
        '(the robot acts every control_period); control_period/human_period and '
        'substeps/(control_period/human_period) must be whole numbers; = control_period: '
        'the human acts once per period and the command is held (the behaviour before it '
        'existed)', low=0.001, high=1.0)
    episode_duration: float = param(
        40.0, 'episode length (s); a multiple of control_period; the episode is truncated then',
        low=0.2, high=3600.0)
    max_force: float = param(
        2.0, 'limit of |force| on the slider (N); normalized command 1 = this force',
        low=0.01, high=100.0)
    max_torque: float = param(
        0.5, 'limit of |torque| on the pendulum (N*m); normalized command 1 = this torque',
        low=0.001, high=50.0)
    gravity: float = param(9.81, 'gravitational acceleration (m/s^2), acting along -z',
                           low=0.0, high=20.0)
    gravity_compensation: bool = param(
        True, 'static counterweight: slider and pendulum (with the ball in the middle) float; '
        "the ball's offset is never compensated")
    rod_length: float = param(0.2, 'length of the vertical rod (m); slider stops at +-half',
                              low=0.02, high=2.0)
    pendulum_length: float = param(0.5, 'length of the pendulum beam (m), hinged at its west '
                                   'end; ball stops at +-half', low=0.05, high=5.0)
    pendulum_limit: float = param(math.pi / 2, 'hinge stops at +-this angle (rad)',
                                  low=0.1, high=math.pi / 2)
    slider_mass: float = param(1.0, 'mass of the slider (kg)', low=0.01, high=100.0)
    pendulum_mass: float = param(0.5, 'mass of the pendulum beam (kg), uniform',
                                 low=0.01, high=100.0)
    ball_mass: float = param(0.05, 'mass of the ball (kg)', low=0.001, high=10.0)
    ball_radius: float = param(0.02, 'radius of the ball (m): its centre sits this far above '
                               'the beam', low=0.001, high=0.2)
    slider_damping: float = param(10.0, 'viscous damping of the slider on the rod (N*s/m)',
                                  low=0.0, high=1000.0)
    pendulum_damping: float = param(0.5, 'viscous damping of the hinge (N*m*s/rad)',
                                    low=0.0, high=100.0)
    ball_damping: float = param(0.1, 'viscous rolling resistance of the ball (N*s/m)',
                                low=0.0, high=100.0)
    initial_slider_spread: float = param(0.03, 'initial S_x drawn from [-this, this] (m)',
                                         low=0.0, high=1.0)
    initial_angle_spread: float = param(0.1, 'initial P_z drawn from [-this, this] (rad)',
                                        low=0.0, high=math.pi / 2)
    initial_ball_spread: float = param(0.05, 'initial B_y drawn from [-this, this] (m)',
                                       low=0.0, high=2.5)

    @property
    def steps_per_episode(self) -> int:
        """Control steps in one episode (200 for 40 s at 0.2 s)."""
        return int(round(self.episode_duration / self.control_period))

    @property
    def time_step(self) -> float:
        """Physics substep (s)."""
        return self.control_period / self.substeps

    @property
    def human_slices(self) -> int:
        """Slices of a control period in which the human's command is applied anew (>= 1).

        The one rule is ``SimLimits.human_slices`` (hrc_common.contract).
        """
        return SimLimits.of(self).human_slices

    @property
    def substeps_per_slice(self) -> int:
        """Physics substeps in one human slice."""
        return max(1, self.substeps // self.human_slices)

    @property
    def pendulum_com_distance(self) -> float:
        """Distance from the hinge to the beam's centre of mass (m)."""
        return self.pendulum_length / 2

    @property
    def hinge_inertia(self) -> float:
        """Moment of inertia about the hinge of the beam and the ball in the middle (kg*m^2)."""
        half = self.pendulum_length / 2
        beam = self.pendulum_mass * self.pendulum_length ** 2 / 3
        return beam + self.ball_mass * (half ** 2 + self.ball_radius ** 2)

    def check(self) -> list:
        """Return the reasons why the fields do not fit together (empty if they do)."""
        reasons = []
        ratio = self.episode_duration / self.control_period
        if abs(ratio - round(ratio)) > 1e-6:
            reasons.append(f'episode_duration {self.episode_duration} s is not a multiple of '
                           f'control_period {self.control_period} s')
        slices = self.control_period / self.human_period
        if self.human_period > self.control_period + 1e-12:
            reasons.append(f'human_period {self.human_period} s exceeds control_period '
                           f'{self.control_period} s (the human acts at least once a period)')
        elif abs(slices - round(slices)) > 1e-6:
            reasons.append(f'control_period {self.control_period} s is not a whole multiple of '
                           f'human_period {self.human_period} s')
        elif self.substeps % max(1, round(slices)):
            reasons.append(f'substeps {self.substeps} cannot be split into '
                           f'{round(slices)} equal human slices (control_period / human_period)'
                           f': choose substeps a multiple of {round(slices)}')
        if self.initial_slider_spread > self.rod_length / 2:
            reasons.append(f'initial_slider_spread {self.initial_slider_spread} m exceeds the '
                           f"rod's half length {self.rod_length / 2} m")
        if self.initial_angle_spread > self.pendulum_limit:
            reasons.append(f'initial_angle_spread {self.initial_angle_spread} rad exceeds '
                           f'pendulum_limit {self.pendulum_limit} rad')
        if self.initial_ball_spread > self.pendulum_length / 2:
            reasons.append(f'initial_ball_spread {self.initial_ball_spread} m exceeds the '
                           f"beam's half length {self.pendulum_length / 2} m")
        # Explicit damping is stable while damping * dt / inertia < 2; keep a margin of 2.
        carried_mass = self.slider_mass + self.pendulum_mass + self.ball_mass
        for name, damping, inertia in (
                ('slider_damping', self.slider_damping, carried_mass),
                ('pendulum_damping', self.pendulum_damping, self.hinge_inertia),
                ('ball_damping', self.ball_damping, self.ball_mass)):
            if damping * self.time_step / inertia > 1.0:
                reasons.append(f'{name} {damping} with a substep of {self.time_step:.4g} s '
                               f'would make the explicit damping unstable (needs '
                               f'damping * dt / {inertia:.4g} <= 1): lower it or raise substeps')
        return reasons


@dataclass(frozen=True)
class PhysicsState:
    """The system after a control step (or a reset); SI units, see the module docstring."""

    step: int                          # control step within the episode, 0 after reset
    time: float                        # s since reset (step * control_period)
    slider_position: float             # S_x (m), 0 = middle of the rod, + up
    slider_velocity: float             # m/s
    pendulum_angle: float              # P_z (rad), 0 = horizontal east, + = east end up
    pendulum_angular_velocity: float   # rad/s
    ball_position: float               # B_y (m), 0 = middle of the beam, + = east
    ball_velocity: float               # m/s
    applied_force: float               # N: the actors' force held during the last period
    applied_torque: float              # N*m: the actors' torque held during the last period
    terminated: bool                   # always false (nothing ends an episode early)
    truncated: bool                    # time limit reached: the last state of the episode


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


