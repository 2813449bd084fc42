"""The sim node: runs the slider-pendulum-ball physics and talks the hrc step protocol.

Publishes ``/hrc/state`` (TaskState), ``/joint_states`` with each period's state,
``/robot_description`` (its URDF, latched), ``/clock`` (lockstep), ``/hrc/sim/markers`` and,
when ``camera_rate`` > 0, ``/hrc/sim/image``; consumes ``/hrc/robot/cmd_wrench``,
``/hrc/human/cmd_wrench`` and ``/hrc/session``; serves ``/hrc/sim/reset``.

Step protocol (docs/architecture.md; the pure core ``hrc_sim_node.protocol``, shared with the
in-process engine): a command answers a state by carrying its stamp. ``lockstep`` advances when
every actor in ``expected_actors`` has answered (or at ``lockstep_timeout``: the missing command
counts as zero and is flagged) and, with ``await_recorder``, no further than a window ahead of
the recorder (``hrc_sim_node.recorder_gate``); ``realtime`` steps on a wall timer. A reset may
switch the mode; its response reports the mode, the control period and the sim's limits.

Commands (``hrc_sim_node.commands``): from each actor only its degree of freedom is applied
(``robot_dof`` parameter, the human gets the other, both updated from ``/hrc/session``); other
non-zero components are ignored and reported; a command with a non-finite component is refused
(logged, counted, the step counts it as missing); an out-of-range command is clamped to
``max_force``/``max_torque`` with a throttled warning. Every such event is counted and listed
in the one-line summary logged at each episode end.

Operator abort (``/hrc/session`` with phase ``aborted``): a running episode stops at once, the
sim holds (no more steps or states, nothing applied) until ``/hrc/sim/reset`` is called again.
"""

import sys
import time

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_common.cdr_header import header_stamp
from hrc_common.contract import SimLimits
from hrc_common.dof import DOF_INDEX, DOF_NAME
from hrc_common.nodes import run_node
from hrc_common.diagnostics import DiagnosticsReporter, TimingHealth
from hrc_common.session_end import SessionEndWatch
from hrc_common.params import declare_parameters, ParameterError
from hrc_msgs.msg import SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode
from hrc_sim_node.body_geometry import model_urdf
from hrc_sim_node.commands import HUMAN, ROBOT, unit_of
from hrc_sim_node.physics import physics_params_of, SliderPendulumBall
from hrc_sim_node.protocol import ProtocolSettings, stamp_fields, stamp_ns, StepProtocol
from hrc_sim_node.recorder_wait import EXIT_RECORDER_STALLED, RecorderStalled, RecorderWait
from hrc_sim_node.sim_log import summary_line, WarningThrottle
from hrc_sim_node.sim_messages import (joint_state_message, SimVisuals, stamp_of,
                                       state_message)
from hrc_sim_node.sim_params import CLOCK_MODES, LOCKSTEP, REALTIME, SimParams
from hrc_sim_node.stepper import SimStepper
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import String
from visualization_msgs.msg import MarkerArray

__all__ = ['SimNode', 'SimParams', 'LOCKSTEP', 'REALTIME', 'main']

# Throttle (s) of each kind of warning about commands: a broken sender at 500 Hz would flood.
WARN_THROTTLE_S = 2.0
# /clock: reliable, so best-effort (rclpy's TimeSource) and reliable subscribers both match.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
# The sim's command subscriptions keep this many samples (KEEP_LAST). With depth 1 (the
# contract's), a second publisher flooding the topic (about 40k/s here) or sending 1 MiB
# commands replaced the actor's matching command in the reader's queue before the executor
# took it; the sim also drains the queue in one turn (_on_raw_command). Depth is not part of
# QoS matching, so the publishers keep the contract's QoS. Memory: small commands are ~100 B;
# giant ones arrive slowly (tens per second) and are drained as they come.
COMMAND_SUBSCRIPTION_DEPTH = 1000
COMMAND_SUBSCRIPTION_QOS = QoSProfile(
    history=qos.COMMAND_QOS.history, depth=COMMAND_SUBSCRIPTION_DEPTH,
    reliability=qos.COMMAND_QOS.reliability, durability=qos.COMMAND_QOS.durability,
    deadline=qos.COMMAND_QOS.deadline)
# No QoS event handlers (qos.NO_*_EVENTS: each costs every turn of the executor); a silent
# actor is reported by the lockstep timeout or the realtime command_timeout.
NO_PUBLISHER_EVENTS, NO_SUBSCRIPTION_EVENTS = qos.NO_PUBLISHER_EVENTS, qos.NO_SUBSCRIPTION_EVENTS
COMMAND_DRAIN_LIMIT = 10000   # commands read from a queue in one turn at most (fairness)
FREE_RUN_PERIOD_S = 1e-6      # s: the free-run timer is re-armed every step
# A status with one of these phases stops a running episode at once (an operator's abort, the
# agent held for a lost input mid-episode; an operator's pause comes between episodes).
HOLDING_PHASES = (SessionStatus.PHASE_ABORTED, SessionStatus.PHASE_PAUSED)


class SimNode(RecorderWait, SimVisuals, Node):
    """Thin ROS wrapper of :class:`SliderPendulumBall` and :class:`StepProtocol`."""

    def __init__(self):
        super().__init__('sim')
        self.params = params = declare_parameters(self, SimParams)
        self.session_end = SessionEndWatch(self, params.exit_after_session)
        # /diagnostics: the period jitter and the running episode's missing or stale commands
        self.health = TimingHealth(params.control_period)
        self.diagnostics = DiagnosticsReporter(self, lambda: [self.health.status(
            self.protocol.mode != LOCKSTEP, self.protocol.mode, self.episode)])
        try:
            self.physics = SliderPendulumBall(physics_params_of(params), gui=params.gui)
        except RuntimeError as error:
            raise ParameterError(f'SimParams rejected: gui: {error}') from error
        self.protocol = StepProtocol(ProtocolSettings.of(params))
        self.stepper = SimStepper(self.physics, self.protocol)
        self._setup_recorder_wait(params, self.protocol.slices)
        self._state = None              # last PhysicsState
        self._seeded = False
        self._exiting = False
        self._throttle = WarningThrottle(WARN_THROTTLE_S)

        self._state_pub = self.create_publisher(TaskState, topics.STATE,
                                                qos.stream_qos(qos.STATE_QOS),
                                                event_callbacks=NO_PUBLISHER_EVENTS)
        # States within a period at the human's rate (the human node, the person's page).
        self._slice_pub = self.create_publisher(TaskState, topics.SLICE_STATE, qos.STATE_QOS,
                                                event_callbacks=NO_PUBLISHER_EVENTS)
        # /clock is published in lockstep only; the publisher exists in both modes because a
        # reset may switch the mode.
        self._clock_pub = self.create_publisher(Clock, topics.CLOCK, CLOCK_QOS,
                                                event_callbacks=NO_PUBLISHER_EVENTS)
        self._joint_pub = self.create_publisher(
            JointState, topics.JOINT_STATES, qos.stream_qos(qos.OF_TOPIC[topics.JOINT_STATES]),
            event_callbacks=NO_PUBLISHER_EVENTS)
        self.create_publisher(String, topics.ROBOT_DESCRIPTION,
                              qos.OF_TOPIC[topics.ROBOT_DESCRIPTION]).publish(
            String(data=model_urdf(self.physics.params)))
        self._marker_pub = self.create_publisher(MarkerArray, topics.MARKERS, qos.VISUAL_QOS,
                                                 event_callbacks=NO_PUBLISHER_EVENTS)
        self._image_pub = (self.create_publisher(Image, topics.CAMERA_IMAGE, qos.VISUAL_QOS,
                                                 event_callbacks=NO_PUBLISHER_EVENTS)
                           if params.camera_rate > 0 else None)
        self._command_topics = {}
        self._command_subscriptions = {}
        for actor, topic in ((ROBOT, topics.ROBOT_CMD_WRENCH), (HUMAN, topics.HUMAN_CMD_WRENCH)):
            subscription = self.create_subscription(
                WrenchStamped, topic, lambda data, actor=actor: self._on_raw_command(actor, data),
                COMMAND_SUBSCRIPTION_QOS, event_callbacks=NO_SUBSCRIPTION_EVENTS, raw=True)
            self._command_subscriptions[actor] = subscription
            self._command_topics[actor] = subscription.topic_name
        self.create_subscription(SessionStatus, topics.SESSION, self._on_session,
                                 qos.SESSION_QOS, event_callbacks=NO_SUBSCRIPTION_EVENTS)
        self.create_service(ResetEpisode, topics.RESET_SERVICE, self._on_reset)

        # Timers of both clock modes, cancelled while not in use (a reset may switch the mode).
        self._timeout_timer = self.create_timer(params.lockstep_timeout,
                                                self._on_lockstep_timeout)
        self._timeout_timer.cancel()
        # Free run: a timer that is due at once, re-armed after each state, makes one step
        # per turn of the executor, so services and other timers are served in between.
        self._free_run = self.create_timer(FREE_RUN_PERIOD_S, self._on_free_run)
        self._free_run.cancel()
        # Realtime: one tick per human slice (human_period), so the physics advances with
        # wall time at the human's rate and each slice takes the newest human command.
        self._step_timer = self.create_timer(params.control_period / self.protocol.slices,
                                             self._on_realtime_tick)
        self._step_timer.cancel()
        if params.marker_rate > 0:
            self.create_timer(1.0 / params.marker_rate, self._publish_markers)
        if params.camera_rate > 0:
            self.create_timer(1.0 / params.camera_rate, self._publish_image)

        actors = ', '.join(params.expected_actors) or 'none (free run)'
        dof_of = self.protocol.dof_of
        self.get_logger().info(
            f'{params.mode} sim: control period {params.control_period} s, human period '
            f'{params.control_period / self.protocol.slices:g} s, '
            f'{params.steps_per_episode} steps per episode, max_force {params.max_force} N, '
            f'max_torque {params.max_torque} N*m, robot drives {dof_of[ROBOT]}, human '
            f'drives {dof_of[HUMAN]}, expected actors: {actors}')
        if params.start_on_launch:
            self.start_episode(0, seed=-1)
        else:
            self.get_logger().info(f'waiting for {topics.RESET_SERVICE} to start an episode')

    @property
    def episode(self) -> int:
        """Return the index of the current (or last) episode."""
        return self.protocol.episode

    def _warn(self, kind: str, message: str):
        """Log a warning, at most once per WARN_THROTTLE_S for each kind (actor and event)."""
        suffix = self._throttle.admit(kind, time.monotonic())
        if suffix is not None:
            self.get_logger().warning(message + suffix)

    # -- episodes ------------------------------------------------------------------------------
    def start_episode(self, episode: int, seed: int = -1) -> TaskState:
        """Reset the physics, publish the state of step 0 and wait for its commands."""
        if self.protocol.active:
            abandoned = self.protocol.counters
            self.get_logger().warning(
                'reset requested: ' + summary_line(self.episode, self._state, abandoned,
                                                   self.protocol.mode, end='abandoned'))
        if seed >= 0:
            origin = f'seed {seed}'
        elif not self._seeded:
            seed = self.params.seed
            origin = f'seed {self.params.seed} (parameter seed)'
        else:
            seed = None  # next from the seeded sequence
            origin = 'next initial state of the seeded sequence'
        self._seeded = True
        self.recorder_gate.drop()           # a step held for the recorder ends with its episode
        first = self.stepper.start_episode(episode, seed)
        state = first.state
        message = self._publish(first)
        self.get_logger().info(
            f'episode {episode} started ({origin}, {self.protocol.mode}): '
            f'S_x={state.slider_position:+.4f} m, P_z={state.pendulum_angle:+.4f} rad, '
            f'B_y={state.ball_position:+.4f} m')
        if self.protocol.mode == REALTIME:
            self._step_timer.reset()  # step 1 comes one full period after step 0
        return message

    def _end_episode(self):
        protocol = self.protocol
        self.get_logger().info(summary_line(self.episode, self._state, protocol.counters,
                                            protocol.mode))
        if self.params.max_episodes and protocol.finished_episodes >= self.params.max_episodes:
            self.get_logger().info(f'{protocol.finished_episodes} episode(s) finished '
                                   f'(max_episodes): exiting')
            self._exiting = True
            self.context.try_shutdown()
        elif self.params.auto_reset:
            following = protocol.next_episode()
            if following is None:
                self.get_logger().error(f'episode {self.episode} is the last index a uint32 '
                                        f'holds: holding instead of starting another')
                return
            self.start_episode(following, seed=-1)
        else:
            self.get_logger().info(f'holding until {topics.RESET_SERVICE} is called')

    def _set_clock_mode(self, mode: str) -> None:
        """Switch lockstep <-> realtime between episodes (the timers of the old mode stop)."""
        if self.protocol.active:
            self.protocol.hold()  # the reset abandons the running episode anyway
            self._cancel_timers()
        if self.protocol.set_mode(mode):
            self._cancel_timers()
            self.get_logger().info(f'clock mode switched to {mode} by a reset request')

    def _cancel_timers(self):
        """Stop stepping: the timers of both modes, and a step held for the recorder."""
        for timer in (self._timeout_timer, self._free_run, self._step_timer):
            timer.cancel()
        self.recorder_gate.drop()

    def _on_reset(self, request, response):
        response.clock_mode = self.protocol.mode
        # The actors scale and observe commands with these (hrc_common.contract.SimLimits).
        limits = SimLimits.of(self.params)
        response.control_period = limits.control_period
        response.max_force = limits.max_force
        response.max_torque = limits.max_torque
        if self._exiting:
            response.success = False
            response.message = 'the sim is exiting (max_episodes reached)'
            return response
        reasons = []
        if request.clock_mode and request.clock_mode not in CLOCK_MODES:
            reasons.append(f'clock_mode {request.clock_mode!r} is not one of {CLOCK_MODES} '
                           f'(or empty to keep {self.protocol.mode})')
        if reasons:
            response.success = False
            response.message = 'reset refused: ' + '; '.join(reasons)
            self.get_logger().error(response.message)
            return response
        # A reader that the agent's graph shows but this writer has not matched yet (a recorder
        # discovered late) would miss the episode's states: lockstep episodes alone can run in
        # well under a second. The agent asks for its first episode to wait until they match.
        response.state_readers_matched = self._state_pub.get_subscription_count()
        if response.state_readers_matched < request.state_readers:
            response.success, response.retry = False, True
            response.message = (f'not started: {response.state_readers_matched} of '
                                 f'{request.state_readers} readers of {topics.STATE} matched')
            return response
        if request.clock_mode:
            abandoned = self.protocol.active
            if abandoned:
                self.get_logger().warning(
                    'reset requested: ' + summary_line(self.episode, self._state,
                                                       self.protocol.counters,
                                                       self.protocol.mode, end='abandoned'))
            self._set_clock_mode(request.clock_mode)
        response.state = self.start_episode(int(request.episode), seed=int(request.seed))
        response.clock_mode = self.protocol.mode
        response.success = True
        response.message = f'episode {request.episode} started ({self.protocol.mode})'
        return response

    # -- stepping ------------------------------------------------------------------------------
    def _advance(self, order):
        """Apply one control period or human slice as ``order`` (a StepOrder) says; publish."""
        if self._recorder_holds(order):
            return
        for actor, value in order.ignored:
            self._warn('human_not_involved', f'{actor} command {value:+.3g} ignored: the '
                       f'session says the human is not involved now')
        advanced = self.stepper.apply(order)
        self._publish(advanced)
        if advanced.episode_over:
            self._end_episode()

    def _publish(self, advanced) -> TaskState:
        """Publish /clock (lockstep) and the (slice) state; arm the wait for its commands."""
        state = advanced.state
        last = advanced.episode_over
        stamp = stamp_of(advanced.stamp)
        lockstep = self.protocol.mode == LOCKSTEP
        if lockstep:
            self._clock_pub.publish(Clock(clock=stamp))
        message = state_message(state, self.episode, stamp, advanced.missing,
                                advanced.slice, advanced.human_applied)
        if advanced.period_end:
            self._state = state
            self._state_pub.publish(message)
            self.recorder_gate.on_published(advanced.stamp)
            self._joint_pub.publish(joint_state_message(state, stamp))   # after: actors first
            self.health.on_state(state.step, advanced.missing, time.monotonic())
        else:
            self._slice_pub.publish(message)
        if lockstep and not last:
            if self.protocol.awaited_actors():
                self._timeout_timer.reset()
            else:
                self._free_run.reset()
        return message

    def _on_free_run(self):
        self._free_run.cancel()
        order = self.protocol.free_run()
        if order is not None:
            self._advance(order)

    def _on_lockstep_timeout(self):
        self._timeout_timer.cancel()
        order = self.protocol.on_timeout()
        if order is None:
            return
        flood = sum(self.protocol.stale_while_waiting[actor] for actor in order.absent)
        self._warn('lockstep_timeout', f'step {self._state.step}: no command from '
                   f'{", ".join(order.absent)} within lockstep_timeout '
                   f'{self.params.lockstep_timeout} s: counted as zero' + (
                       f'; {flood} commands of no state came meanwhile: a flood from another '
                       f'publisher may have pushed the matching one out of the '
                       f'{COMMAND_SUBSCRIPTION_DEPTH}-deep queue' if flood else ''))
        self._advance(order)

    def _on_realtime_tick(self):
        order = self.protocol.on_tick(time.monotonic())
        if order is None:
            return
        if order.absent:
            self._warn('command_timeout', f'step {self._state.step}: no fresh command from '
                       f'{", ".join(order.absent)} (command_timeout '
                       f'{self.params.command_timeout} s): counted as zero')
        self._advance(order)

    # -- inputs --------------------------------------------------------------------------------
    def _on_raw_command(self, actor: str, data: bytes):
        """Read a command, then drain the commands queued behind it in the same turn.

        One message per turn of the executor is far slower than a second publisher can flood
        the topic (about 2k vs 40k/s here), so the reader's queue stayed full and the actor's
        matching command was pushed out of it. Draining, with the stamp read from the CDR
        bytes before anything is decoded, keeps up with such a flood.
        """
        self._read_command(actor, data)
        # Then the other actor's queue too: in lockstep both answers usually wait by now, and
        # reading them in this turn saves a whole turn of the executor per step.
        for each, subscription in sorted(self._command_subscriptions.items(),
                                         key=lambda item: item[0] != actor):
            with subscription.handle:
                for _ in range(COMMAND_DRAIN_LIMIT):
                    taken = subscription.handle.take_message(WrenchStamped, True)
                    if taken is None:
                        break
                    self._read_command(each, taken[0])

    def _read_command(self, actor: str, data: bytes):
        sec, nanosec = header_stamp(data)
        stamp = stamp_ns(sec, nanosec)
        wrench = None
        if self.protocol.is_answer(stamp):
            wrench = deserialize_message(data, WrenchStamped).wrench
        result = self.protocol.on_command(actor, stamp, wrench, time.monotonic())
        if result.kind == 'stale':
            self._warn_stale(actor, (sec, nanosec), result.awaited)
        elif result.kind == 'refused':
            self._warn(actor + '_refused', f'refused {actor} command at step '
                       f'{self.protocol.step}: {result.command.refused}; the step counts it '
                       f'as missing (zero)')
        elif result.kind == 'accepted':
            command, dof = result.command, result.dof
            if command.clamped:
                self._warn(actor + '_clamped', f'clamped {actor} {dof} command '
                           f'{command.requested:+.4g} to {command.value:+.4g} {unit_of(dof)} '
                           f"(limit {result.limit:g}, the sim's max_"
                           f'{"force" if unit_of(dof) == "N" else "torque"})')
            if command.off_axis:
                components = ', '.join(f'{name}={value:+.4g}'
                                       for name, value in sorted(command.off_axis.items()))
                self._warn(actor + '_off_axis', f'ignored off-axis components of the {actor} '
                           f'command ({actor} drives {dof} only): {components}')
        if result.order is not None:
            self._timeout_timer.cancel()
            self._advance(result.order)

    def _warn_stale(self, actor: str, stamp: tuple, awaited) -> None:
        """Report a command that answers no state the sim waits for, with its publishers."""
        self.health.on_stale()
        kind = actor + '_stale'
        suffix = self._throttle.admit(kind, time.monotonic())
        if suffix is None:
            return
        topic = self._command_topics[actor]
        publishers = self.get_publishers_info_by_topic(topic)
        names = ', '.join(f'{info.node_namespace.rstrip("/")}/{info.node_name} (gid '
                          f'{bytes(info.endpoint_gid).hex()[:24]})' for info in publishers)
        expected = ('none (no state is awaited)' if awaited is None
                    else f'{stamp_fields(awaited)}')
        self.get_logger().warning(
            f'{actor} command stamped {stamp} answers no state of the running episode '
            f'(awaited {expected}): ignored as stale; {len(publishers)} publisher(s) on '
            f'{topic}: {names}' + suffix)

    def _on_session(self, message: SessionStatus):
        if message.phase in HOLDING_PHASES and self.protocol.active:
            self._hold_after_abort(message)
        robot, human = DOF_NAME.get(message.robot_dof), DOF_NAME.get(message.human_dof)
        dof_of = self.protocol.dof_of
        if robot is None or human is None or robot == human:
            self.get_logger().error(
                f'session {message.session_id!r} assigns robot_dof={message.robot_dof}, '
                f'human_dof={message.human_dof}: not one of each of {DOF_INDEX}; ignored, '
                f'keeping robot {dof_of[ROBOT]}, human {dof_of[HUMAN]}')
            return
        if self.protocol.set_roles(robot, message.human_involved):
            self.get_logger().info(f'session {message.session_id!r}: robot drives {robot}, '
                                   f'human drives {human}, human involved: '
                                   f'{self.protocol.human_involved}')
            self._rearm_lockstep_wait()

    def _rearm_lockstep_wait(self):
        """After a role change during a lockstep wait: step if due, else wait as now needed.

        Roles change between episodes; an announcement that comes late (after the state it
        concerns) changes who is awaited: without this the sim could wait for nobody's
        command with no timer armed, or on a free-run timer for an actor it now awaits.
        """
        if self.protocol.mode != LOCKSTEP or not self.protocol.waiting:
            return
        order = self.protocol.on_roles_changed()
        if order is not None:
            self._timeout_timer.cancel()
            self._free_run.cancel()
            self._advance(order)
        elif self.protocol.awaited_actors():
            self._free_run.cancel()
            if self._timeout_timer.is_canceled():
                self._timeout_timer.reset()
        else:
            self._timeout_timer.cancel()
            self._free_run.reset()

    def _hold_after_abort(self, message: SessionStatus):
        """Stop the running episode at once: no more steps, nothing applied, hold."""
        self.protocol.hold()
        self._cancel_timers()
        phase = 'paused' if message.phase == SessionStatus.PHASE_PAUSED else 'aborted'
        self.get_logger().warning(
            f'session {message.session_id!r} {phase} ({message.message}): episode '
            f'{self.episode} stopped at step {self._state.step}; holding, nothing applied, '
            f'until {topics.RESET_SERVICE} is called')

    def close(self):
        """Release PyBullet."""
        self.physics.close()


def main(args=None):
    """Run the sim node (``ros2 run hrc_sim_node sim_node``)."""
    try:
        return run_node(SimNode, 'sim_node', __doc__, SimParams, args=args)
    except RecorderStalled as error:
        print(f'[ERROR] [sim]: {error}', file=sys.stderr, flush=True)
        return EXIT_RECORDER_STALLED


if __name__ == '__main__':
    raise SystemExit(main())
