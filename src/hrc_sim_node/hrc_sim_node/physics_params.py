"""The parameters of the slider-pendulum-ball model and the state it reports (no ROS).

The model itself, its dynamics and its episodes: :mod:`hrc_sim_node.physics`. Here: what
each quantity means, its unit and bounds, and why the defaults are what they are.

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

Timing
------
The human's rate: ``human_period`` (default 0.02 s) splits a control period into slices of
``substeps_per_slice`` substeps; ``SliderPendulumBall.advance`` (:mod:`hrc_sim_node.physics`)
holds a wrench for one slice and ``finish_period`` ends the period (``step`` is both, for one
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

"""

from dataclasses import dataclass
import math

from hrc_common.contract import SimLimits
from hrc_common.params import param


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

