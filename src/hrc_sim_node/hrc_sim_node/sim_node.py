"""The sim node: runs the slider-pendulum-ball physics and talks the hrc step protocol.

Publishes ``/hrc/state`` (TaskState), ``/clock`` (lockstep), ``/hrc/sim/markers`` and, when
``camera_rate`` > 0, ``/hrc/sim/image``; consumes ``/hrc/robot/cmd_wrench``,
``/hrc/human/cmd_wrench`` and ``/hrc/session``; serves ``/hrc/sim/reset``.

Step protocol (docs/architecture.md): a command answers a state by carrying the state's stamp.
In ``lockstep`` the sim advances as soon as every actor in ``expected_actors`` has answered the
current state (or after ``lockstep_timeout`` wall seconds: the missing command counts as zero
and the next state's ``*_command_missing`` flag says so); with ``expected_actors`` empty it runs
free, as fast as it can. In ``realtime`` a wall timer steps every ``control_period`` with each
actor's latest command; one older than ``command_timeout`` counts as zero and is reported.

Commands (``hrc_sim_node.commands``): from each actor only its degree of freedom is applied
(``robot_dof`` parameter, the human gets the other, both updated from ``/hrc/session``); other
non-zero components are ignored and reported; a command with a non-finite component is refused
(logged, counted, the step counts it as missing); an out-of-range command is clamped to
``max_force``/``max_torque`` with a throttled warning. Every such event is counted and listed
in the one-line summary logged at each episode end.

Operator abort (``/hrc/session`` with phase ``aborted``): a running episode stops at once, the
sim holds (no more steps or states, nothing applied) until ``/hrc/sim/reset`` is called again.
"""

from collections import Counter
from dataclasses import dataclass
import time

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3, WrenchStamped
from hrc_common import qos, topics
from hrc_common.contract import BODY_COLOURS
from hrc_common.dof import DOF_INDEX, DOF_NAME, DOFS, other_dof, ROTATION, TRANSLATION
from hrc_common.nodes import run_node
from hrc_common.params import declare_parameters, param, ParameterError
from hrc_msgs.msg import SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
from hrc_sim_node.commands import ACTORS, HUMAN, limit_for, read_command, ROBOT, unit_of
from hrc_sim_node.physics import (body_poses, physics_params_of, PhysicsParams,
                                  SliderPendulumBall)
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

LOCKSTEP = 'lockstep'
REALTIME = 'realtime'
# Throttle (s) of each kind of warning about commands: a broken sender at 500 Hz would flood.
WARN_THROTTLE_S = 2.0
# /clock: reliable, so best-effort (rclpy's TimeSource) and reliable subscribers both match.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
NANOSECONDS = 1_000_000_000
# Period (s) of the free-run timer: as short as possible, the timer is re-armed every step.
FREE_RUN_PERIOD_S = 1e-6


@dataclass
class SimParams(PhysicsParams):
    """Parameters of the sim node: the physics (PhysicsParams, inherited) plus these."""

    mode: str = param('lockstep', 'lockstep: advance when the commands of the step arrived; '
                      'realtime: advance every control_period of wall time',
                      choices=(LOCKSTEP, REALTIME))
    expected_actors: list = param(
        [ROBOT, HUMAN], 'actors whose command the sim waits for (lockstep) and reports missing;'
        ' [] = run free', choices=ACTORS)
    lockstep_timeout: float = param(
        1.0, 'lockstep: wall seconds to wait for the commands of a step before counting the '
        'missing ones as zero', low=0.001, high=600.0)
    command_timeout: float = param(
        0.5, 'realtime: a command older than this (wall s) counts as zero and is reported',
        low=0.01, high=60.0)
    auto_reset: bool = param(False, 'start the next episode by itself after the last state '
                             '(standalone runs); false = hold until /hrc/sim/reset')
    start_on_launch: bool = param(False, 'start episode 0 at launch instead of waiting for '
                                  '/hrc/sim/reset (standalone runs)')
    robot_dof: str = param(TRANSLATION, 'degree of freedom the robot drives until /hrc/session '
                           'says otherwise; the human drives the other', choices=DOFS)
    seed: int = param(0, 'seed of the initial states when a reset asks for none (-1)',
                      low=0, high=2 ** 31 - 1)
    max_episodes: int = param(0, 'exit (code 0) after this many finished episodes; 0 = never',
                              low=0, high=10 ** 9)
    camera_rate: float = param(0.0, 'rate (Hz, wall time) of the rendered image on '
                               '/hrc/sim/image; 0 = off', low=0.0, high=60.0)
    image_width: int = param(320, 'width of the rendered image (px)', low=16, high=1920)
    image_height: int = param(240, 'height of the rendered image (px)', low=16, high=1080)
    marker_rate: float = param(10.0, 'rate (Hz, wall time) of /hrc/sim/markers; 0 = off',
                               low=0.0, high=60.0)
    gui: bool = param(False, 'open the PyBullet GUI window (needs a display); default: '
                      'headless (DIRECT)')

    def check(self) -> list:
        """Return the reasons why the fields do not fit together (empty if they do)."""
        reasons = list(super().check())
        if len(set(self.expected_actors)) != len(self.expected_actors):
            reasons.append(f'expected_actors {self.expected_actors} lists an actor twice')
        return reasons


def stamp_of(nanoseconds: int) -> Time:
    """Return a builtin_interfaces/Time for a simulation time in nanoseconds."""
    return Time(sec=nanoseconds // NANOSECONDS, nanosec=nanoseconds % NANOSECONDS)


def summary_line(episode: int, state, counters: Counter, params: SimParams) -> str:
    """Return the one-line summary of a finished episode (where each body ended, events)."""
    end = 'truncated' if state.truncated else 'terminated' if state.terminated else 'stopped'
    parts = [f'episode {episode} {end} after {state.step} steps ({state.time:.1f} s sim):',
             f'slider S_x={state.slider_position:+.4f} m,',
             f'pendulum P_z={state.pendulum_angle:+.4f} rad,',
             f'ball B_y={state.ball_position:+.4f} m;',
             'missing commands ' + ', '.join(
                 f'{actor} {counters[actor + "_missing"]}' for actor in ACTORS) + ';']
    events = [f'{name} {count}' for name, count in sorted(counters.items())
              if count and not name.endswith('_missing')]
    parts.append(', '.join(events) if events else 'no refused/clamped/off-axis/stale commands')
    parts.append(f'({params.mode})')
    return ' '.join(parts)


class SimNode(Node):
    """Thin ROS wrapper of :class:`SliderPendulumBall` (see the module docstring)."""

    def __init__(self):
        super().__init__('sim')
        self.params = params = declare_parameters(self, SimParams)
        try:
            self.physics = SliderPendulumBall(physics_params_of(params), gui=params.gui)
        except RuntimeError as error:
            raise ParameterError(f'SimParams rejected: gui: {error}') from error
        self.dof_of = {ROBOT: params.robot_dof, HUMAN: other_dof(params.robot_dof)}
        self.human_involved = True
        self._period_ns = int(round(params.control_period * NANOSECONDS))
        self._sim_time_ns = None        # stamp of the last published state (ns), None = none yet
        self._state = None              # last PhysicsState
        self.episode = 0
        self._active = False            # an episode is running (false while holding)
        self._seeded = False
        self._finished_episodes = 0
        self._counters = Counter()
        self._awaited = None            # (sec, nanosec) of the state the commands must answer
        self._answers = {}              # actor -> Command answering the awaited state
        self._latest = {}               # realtime: actor -> (Command, monotonic receipt time)
        self._exiting = False
        self._warned = {}               # kind -> (monotonic time of the last warning, suppressed)

        self._state_pub = self.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
        self._clock_pub = (self.create_publisher(Clock, topics.CLOCK, CLOCK_QOS)
                           if params.mode == LOCKSTEP else None)
        self._marker_pub = self.create_publisher(MarkerArray, topics.MARKERS, qos.VISUAL_QOS)
        self._image_pub = (self.create_publisher(Image, topics.CAMERA_IMAGE, qos.VISUAL_QOS)
                           if params.camera_rate > 0 else None)
        for actor, topic in ((ROBOT, topics.ROBOT_CMD_WRENCH), (HUMAN, topics.HUMAN_CMD_WRENCH)):
            events = SubscriptionEventCallbacks(
                deadline=lambda event, actor=actor: self._on_deadline_missed(actor, event))
            self.create_subscription(WrenchStamped, topic,
                                     lambda msg, actor=actor: self._on_command(actor, msg),
                                     qos.COMMAND_QOS, event_callbacks=events)
        self.create_subscription(SessionStatus, topics.SESSION, self._on_session,
                                 qos.SESSION_QOS)
        self.create_service(ResetEpisode, topics.RESET_SERVICE, self._on_reset)

        if params.mode == LOCKSTEP:
            self._timeout_timer = self.create_timer(params.lockstep_timeout,
                                                    self._on_lockstep_timeout)
            self._timeout_timer.cancel()
            # Free run: a timer that is due at once, re-armed after each state, makes one step
            # per turn of the executor, so services and other timers are served in between.
            # (A timer, not a guard condition: rclpy's EventsExecutor has no guard conditions.)
            self._free_run = self.create_timer(FREE_RUN_PERIOD_S, self._on_free_run)
            self._free_run.cancel()
        else:
            self._step_timer = self.create_timer(params.control_period, self._on_realtime_tick)
        if params.marker_rate > 0:
            self.create_timer(1.0 / params.marker_rate, self._publish_markers)
        if params.camera_rate > 0:
            self.create_timer(1.0 / params.camera_rate, self._publish_image)

        actors = ', '.join(params.expected_actors) or 'none (free run)'
        self.get_logger().info(
            f'{params.mode} sim: control period {params.control_period} s, '
            f'{params.steps_per_episode} steps per episode, max_force {params.max_force} N, '
            f'max_torque {params.max_torque} N*m, robot drives {self.dof_of[ROBOT]}, human '
            f'drives {self.dof_of[HUMAN]}, expected actors: {actors}')
        if params.start_on_launch:
            self.start_episode(0, seed=-1)
        else:
            self.get_logger().info(f'waiting for {topics.RESET_SERVICE} to start an episode')

    def _warn(self, kind: str, message: str):
        """Log a warning, at most once per WARN_THROTTLE_S for each kind (actor and event)."""
        now = time.monotonic()
        last, suppressed = self._warned.get(kind, (None, 0))
        if last is not None and now - last < WARN_THROTTLE_S:
            self._warned[kind] = (last, suppressed + 1)
            return
        if suppressed:
            message += f' ({suppressed} more like this in the last {now - last:.1f} s)'
        self.get_logger().warning(message)
        self._warned[kind] = (now, 0)

    # -- parameters ----------------------------------------------------------------------------
    # -- episodes ------------------------------------------------------------------------------
    def start_episode(self, episode: int, seed: int = -1) -> TaskState:
        """Reset the physics, publish the state of step 0 and wait for its commands."""
        if self._active:
            self.get_logger().warning(
                f'episode {self.episode} abandoned at step {self._state.step}: reset requested')
        if seed >= 0:
            state = self.physics.reset(seed=seed)
            origin = f'seed {seed}'
        elif not self._seeded:
            state = self.physics.reset(seed=self.params.seed)
            origin = f'seed {self.params.seed} (parameter seed)'
        else:
            state = self.physics.reset()  # next from the seeded sequence
            origin = 'next initial state of the seeded sequence'
        self._seeded = True
        self.episode = episode
        self._active = True
        self._counters = Counter()
        self._answers = {}
        self._latest = {}
        message = self._publish(state, missing={})
        self.get_logger().info(
            f'episode {episode} started ({origin}): '
            f'S_x={state.slider_position:+.4f} m, P_z={state.pendulum_angle:+.4f} rad, '
            f'B_y={state.ball_position:+.4f} m')
        if self.params.mode == REALTIME:
            self._step_timer.reset()  # step 1 comes one full period after step 0
        return message

    def _end_episode(self):
        self._active = False
        self._awaited = None
        self._finished_episodes += 1
        self.get_logger().info(summary_line(self.episode, self._state, self._counters,
                                            self.params))
        if self.params.max_episodes and self._finished_episodes >= self.params.max_episodes:
            self.get_logger().info(f'{self._finished_episodes} episode(s) finished '
                                   f'(max_episodes): exiting')
            self._exiting = True
            self.context.try_shutdown()
        elif self.params.auto_reset:
            self.start_episode(self.episode + 1, seed=-1)
        else:
            self.get_logger().info(f'holding until {topics.RESET_SERVICE} is called')

    def _on_reset(self, request, response):
        if self._exiting:
            response.success = False
            response.message = 'the sim is exiting (max_episodes reached)'
            return response
        response.state = self.start_episode(int(request.episode), seed=int(request.seed))
        response.success = True
        response.message = f'episode {request.episode} started'
        return response

    # -- stepping ------------------------------------------------------------------------------
    def _advance(self, commands: dict, missing: dict):
        """Apply one control period with ``commands`` (actor -> Command) and publish."""
        wrench = {TRANSLATION: 0.0, ROTATION: 0.0}
        for actor, command in commands.items():
            if command is None or not command.accepted:
                continue
            if actor == HUMAN and not self.human_involved:
                if command.value != 0.0:
                    self._counters['human_not_involved'] += 1
                    self._warn('human_not_involved', f'human command {command.value:+.3g} '
                               f'ignored: the session says the human is not involved now')
                continue
            wrench[self.dof_of[actor]] += command.value
        for actor, is_missing in missing.items():
            if is_missing:
                self._counters[actor + '_missing'] += 1
        state = self.physics.step(wrench[TRANSLATION], wrench[ROTATION])
        self._publish(state, missing)
        if state.truncated or state.terminated:
            self._end_episode()

    def _publish(self, state, missing: dict) -> TaskState:
        """Publish /clock (lockstep) and the state; arm the wait for its commands."""
        self._state = state
        self._sim_time_ns = 0 if self._sim_time_ns is None else \
            self._sim_time_ns + self._period_ns
        stamp = stamp_of(self._sim_time_ns)
        if self._clock_pub is not None:
            self._clock_pub.publish(Clock(clock=stamp))
        message = state_message(state, self.episode, stamp, missing)
        self._answers = {}
        last = state.truncated or state.terminated
        self._awaited = None if last else (stamp.sec, stamp.nanosec)
        self._state_pub.publish(message)
        if self.params.mode == LOCKSTEP and not last:
            if self.params.expected_actors:
                self._timeout_timer.reset()
            else:
                self._free_run.reset()
        return message

    def _on_free_run(self):
        self._free_run.cancel()
        if self._active and self._awaited is not None and not self.params.expected_actors:
            self._advance(self._answers, missing={})

    def _on_lockstep_timeout(self):
        self._timeout_timer.cancel()
        if not self._active or self._awaited is None:
            return
        missing = {actor: actor not in self._answers for actor in self.params.expected_actors}
        absent = [actor for actor, is_missing in missing.items() if is_missing]
        self._warn('lockstep_timeout', f'step {self._state.step}: no command from '
                   f'{", ".join(absent)} within lockstep_timeout '
                   f'{self.params.lockstep_timeout} s: counted as zero')
        self._advance(self._answers, missing)

    def _on_realtime_tick(self):
        if not self._active or self._awaited is None:
            return
        now = time.monotonic()
        commands, missing = {}, {}
        for actor in ACTORS:
            command, received = self._latest.get(actor, (None, None))
            fresh = command is not None and now - received <= self.params.command_timeout
            if fresh and command.accepted:
                commands[actor] = command
            if actor in self.params.expected_actors:
                missing[actor] = not (fresh and command.accepted)
        absent = [actor for actor, is_missing in missing.items() if is_missing]
        if absent:
            self._warn('command_timeout', f'step {self._state.step}: no fresh command from '
                       f'{", ".join(absent)} (command_timeout '
                       f'{self.params.command_timeout} s): counted as zero')
        self._advance(commands, missing)

    # -- inputs --------------------------------------------------------------------------------
    def _on_command(self, actor: str, message: WrenchStamped):
        if not self._active:
            self._counters[actor + '_between_episodes'] += 1
            return
        lockstep = self.params.mode == LOCKSTEP
        stamp = (message.header.stamp.sec, message.header.stamp.nanosec)
        if lockstep and stamp != self._awaited:
            self._counters[actor + '_stale'] += 1
            self.get_logger().debug(f'{actor} command stamped {stamp} does not answer the '
                                    f'current state {self._awaited}: ignored')
            return
        dof = self.dof_of[actor]
        limit = limit_for(dof, self.params.max_force, self.params.max_torque)
        command = read_command(message.wrench, dof, limit)
        step = self._state.step
        if not command.accepted:
            self._counters[actor + '_refused'] += 1
            self._warn(actor + '_refused', f'refused {actor} command at step {step}: '
                       f'{command.refused}; the step counts it as missing (zero)')
        else:
            if command.clamped:
                self._counters[actor + '_clamped'] += 1
                self._warn(actor + '_clamped', f'clamped {actor} {dof} command '
                           f'{command.requested:+.4g} to {command.value:+.4g} {unit_of(dof)} '
                           f'(limit {limit:g})')
            if command.off_axis:
                self._counters[actor + '_off_axis'] += 1
                components = ', '.join(f'{name}={value:+.4g}'
                                       for name, value in sorted(command.off_axis.items()))
                self._warn(actor + '_off_axis', f'ignored off-axis components of the {actor} '
                           f'command ({actor} drives {dof} only): {components}')
        if not lockstep:
            self._latest[actor] = (command, time.monotonic())
            return
        self._answers[actor] = command
        if all(expected in self._answers for expected in self.params.expected_actors):
            self._timeout_timer.cancel()
            missing = {expected: not self._answers[expected].accepted
                       for expected in self.params.expected_actors}
            self._advance(self._answers, missing)

    def _on_deadline_missed(self, actor: str, event):
        if self._active and self.params.mode == REALTIME:
            self._warn(actor + '_deadline', f'{actor} commands stopped for over '
                       f'{qos.COMMAND_DEADLINE_S} s ({event.total_count} deadline misses)')

    def _on_session(self, message: SessionStatus):
        if message.phase == SessionStatus.PHASE_ABORTED and self._active:
            self._hold_after_abort(message)
        robot, human = DOF_NAME.get(message.robot_dof), DOF_NAME.get(message.human_dof)
        if robot is None or human is None or robot == human:
            self.get_logger().error(
                f'session {message.session_id!r} assigns robot_dof={message.robot_dof}, '
                f'human_dof={message.human_dof}: not one of each of {DOF_INDEX}; ignored, '
                f'keeping robot {self.dof_of[ROBOT]}, human {self.dof_of[HUMAN]}')
            return
        changed = (robot != self.dof_of[ROBOT] or message.human_involved != self.human_involved)
        self.dof_of = {ROBOT: robot, HUMAN: human}
        self.human_involved = bool(message.human_involved)
        if changed:
            self.get_logger().info(f'session {message.session_id!r}: robot drives {robot}, '
                                   f'human drives {human}, human involved: '
                                   f'{self.human_involved}')

    def _hold_after_abort(self, message: SessionStatus):
        """Stop the running episode at once: no more steps, nothing applied, hold."""
        self._active = False
        self._awaited = None
        self._answers = {}
        self._latest = {}
        if self.params.mode == LOCKSTEP:
            self._timeout_timer.cancel()
            self._free_run.cancel()
        self.get_logger().warning(
            f'session {message.session_id!r} aborted ({message.message}): episode '
            f'{self.episode} stopped at step {self._state.step}; holding, nothing applied, '
            f'until {topics.RESET_SERVICE} is called')

    # -- visualization -------------------------------------------------------------------------
    def _publish_markers(self):
        if self._state is None:
            return
        self._marker_pub.publish(marker_array(self._state, self.params,
                                              stamp_of(self._sim_time_ns)))

    def _publish_image(self):
        if self._state is None:
            return
        width, height = self.params.image_width, self.params.image_height
        pixels = self.physics.render(width, height)
        image = Image(height=height, width=width, encoding='rgb8', is_bigendian=0,
                      step=width * 3, data=pixels.tobytes())
        image.header.stamp = stamp_of(self._sim_time_ns)
        image.header.frame_id = 'world'
        self._image_pub.publish(image)

    def close(self):
        """Release PyBullet."""
        self.physics.close()


def state_message(state, episode: int, stamp: Time, missing: dict) -> TaskState:
    """Convert a PhysicsState into a TaskState message."""
    message = TaskState(
        episode=episode, step=state.step,
        slider_position=state.slider_position, slider_velocity=state.slider_velocity,
        pendulum_angle=state.pendulum_angle,
        pendulum_angular_velocity=state.pendulum_angular_velocity,
        ball_position=state.ball_position, ball_velocity=state.ball_velocity,
        applied_force=state.applied_force, applied_torque=state.applied_torque,
        robot_command_missing=bool(missing.get(ROBOT, False)),
        human_command_missing=bool(missing.get(HUMAN, False)),
        terminated=state.terminated, truncated=state.truncated)
    message.header.stamp = stamp
    message.header.frame_id = 'world'
    return message


# Marker looks: id, RViz type, size (m) and colour of each body (the paper's colours).
MARKER_STYLE = {
    'rod': (0, Marker.CYLINDER, None, BODY_COLOURS['rod']),
    'slider': (1, Marker.CUBE, (0.05, 0.05, 0.03), BODY_COLOURS['slider']),
    'pendulum': (2, Marker.CUBE, None, BODY_COLOURS['pendulum']),
    'ball': (3, Marker.SPHERE, None, BODY_COLOURS['ball']),
}


def marker_array(state, params: PhysicsParams, stamp: Time) -> MarkerArray:
    """Return the rod, slider, pendulum and ball as RViz/Foxglove markers in frame 'world'."""
    sizes = {'rod': (0.012, 0.012, params.rod_length + 0.04),
             'slider': MARKER_STYLE['slider'][2],
             'pendulum': (0.03, params.pendulum_length, 0.01),
             'ball': (2 * params.ball_radius,) * 3}
    markers = MarkerArray()
    for name, (position, orientation) in body_poses(state, params).items():
        marker_id, marker_type, _, rgb = MARKER_STYLE[name]
        marker = Marker(ns='hrc_sim', id=marker_id, type=marker_type, action=Marker.ADD)
        marker.header.stamp = stamp
        marker.header.frame_id = 'world'
        marker.pose = Pose(position=Point(x=position[0], y=position[1], z=position[2]),
                           orientation=Quaternion(x=orientation[0], y=orientation[1],
                                                  z=orientation[2], w=orientation[3]))
        marker.scale = Vector3(x=float(sizes[name][0]), y=float(sizes[name][1]),
                               z=float(sizes[name][2]))
        marker.color = ColorRGBA(r=rgb[0], g=rgb[1], b=rgb[2], a=1.0)
        markers.markers.append(marker)
    return markers


def main(args=None):
    """Run the sim node (``ros2 run hrc_sim_node sim_node``)."""
    return run_node(SimNode, 'sim_node', __doc__, SimParams, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
