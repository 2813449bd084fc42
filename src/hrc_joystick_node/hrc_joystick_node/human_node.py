"""The human node (``human``): joystick device, /joy or the simulated human -> the human's command.

A thin node around :class:`hrc_joystick_node.human_core.HumanCore` (the per-step decisions,
pure and shared with the in-process engine): it converts messages, owns the joystick device,
the /joy subscription, the timers and the QoS.

Subscribes ``/hrc/state`` (TaskState), ``/hrc/session`` (SessionStatus, transient local) and,
when the input may be ``/joy``, ``/joy`` (sensor_msgs/Joy). For every state that is not the last
of its episode it publishes ``/hrc/human/action`` (HumanAction, whose ``source`` says which
input drove it) and ``/hrc/human/cmd_wrench`` (WrenchStamped, only the human's degree of
freedom set, scaled by the sim's ``max_force``/``max_torque``), both carrying the state's
stamp, so the lockstep sim can match them to the step. The sim owns its control period and
limits: the node reads them at start from the sim's parameter service (node ``sim_node``); a
state that arrives before they are known is answered when they come. While the session says
the human is not involved (the robot learns alone) it answers nothing: the sim does not await
the human then. When the session is aborted (phase ``aborted``) it sends a zero command at
once, answering the newest state, and zero for anything after. The joystick device is sampled
(drained without blocking) when each state arrives, so the command is the stick's position at
that moment.

It publishes the input status on ``/hrc/human/input`` (diagnostic_msgs/DiagnosticStatus,
reliable, transient local, depth 1) at every change and every second: ``level`` OK / WARN /
ERROR, ``message`` one readable line ("joystick disconnected (zero held, session should
pause): ..."), and key-values ``state`` (ok, missing, lost), ``active`` (device, joy, sim,
zero), ``pause_requested`` (true when the joystick is missing or lost and ``on_input_lost`` is
``pause``, the default), ``mode``, ``fallback``, ``lost_count`` and the device's and /joy's
status. The session pauses on ``pause_requested`` (see the package README).
"""

import select
import threading
import time

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_common.contract import NS_PER_S, SimLimits
from hrc_common.dof import DOF_INDEX, DOF_NAME, set_wrench_value
from hrc_common.nodes import run_node
from hrc_common.parameter_query import ParameterQuery
from hrc_common.diagnostics import DiagnosticsReporter
from hrc_common.session_end import SessionEndWatch
from hrc_common.params import as_dict, declare_parameters, ParameterError
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from rclpy.node import Node
from sensor_msgs.msg import Joy

from hrc_joystick_node.human_core import (HumanAnswer, HumanCore, HumanParams, InputStatus,
                                          resolve_profile)
from hrc_joystick_node.inputs import DEVICE, JOY, JoyInput, StickReading
from hrc_joystick_node.js_event import JoystickDevice
from hrc_joystick_node.human_profile import default_profiles_path, load_profiles
from hrc_joystick_node.sim_human import StateView

SUMMARY = ('The human side of hrc: reads a Linux joystick device, sensor_msgs/Joy on /joy, or '
           'runs a simulated human, and answers every /hrc/state with /hrc/human/action and '
           '/hrc/human/cmd_wrench on the degree of freedom the session gives the human; '
           'reports its input on /hrc/human/input.')
# The input status topic (diagnostic_msgs/DiagnosticStatus, reliable, transient local, depth 1).
HUMAN_INPUT = topics.HUMAN_INPUT
# The input status is republished at least this often (s) even when nothing changed.
STATUS_HEARTBEAT = 1.0
# While the sim's parameters are not known, say so this often (s).
SIM_WAIT_REPORT_S = 10.0

__all__ = ['HumanNode', 'HumanParams', 'HUMAN_INPUT', 'StateView', 'main', 'state_view',
           'status_message']


def state_view(message: TaskState, control_period: float, human_period: float = 0.0
               ) -> StateView:
    """Return the simulated human's view of a TaskState (time = s since the episode's reset).

    A slice state (``slice`` > 0) lies ``slice`` human periods into its step's period.
    """
    time_s = message.step * control_period + message.slice * human_period
    return StateView(message.step, time_s, message.slider_position,
                     message.slider_velocity, message.pendulum_angle,
                     message.pendulum_angular_velocity, message.ball_position,
                     message.ball_velocity)


def stamp_ns(stamp) -> int:
    """Return a builtin_interfaces/Time as integer nanoseconds."""
    return stamp.sec * NS_PER_S + stamp.nanosec


def status_message(status: InputStatus, hardware_id: str, extra: dict) -> DiagnosticStatus:
    """Return the DiagnosticStatus of an input status (see the package README)."""
    values = {'mode': status.mode, 'active': status.active, 'state': status.state,
              'fallback': status.fallback,
              'pause_requested': 'true' if status.pause_requested else 'false'}
    values.update({key: str(value) for key, value in extra.items()})
    return DiagnosticStatus(level=bytes([status.level]), name='human input',
                            message=status.reason, hardware_id=hardware_id,
                            values=[KeyValue(key=key, value=value)
                                    for key, value in values.items()])


class HumanNode(Node):
    """Answers every sim state with the human's command (see the module docstring)."""

    def __init__(self):
        super().__init__('human')
        self.params = params = self._declare()
        self.session_end = SessionEndWatch(self, params.exit_after_session)
        self.diagnostics = DiagnosticsReporter(self, self._diagnostics)
        self.core = HumanCore(params, self._profiles, str(self._profiles_path))
        self.profile = self.core.profile

        self.device = JoystickDevice(params.device) if params.input in ('auto', DEVICE) else None
        self.joy = JoyInput(params.joy_timeout) if params.input in ('auto', JOY) else None
        self._next_open_attempt = 0.0
        self._reported_garbage = 0
        self._joy_was_alive = False
        self._last_messages = None  # (answer, HumanAction, WrenchStamped) of the last answer
        self._last_status = None
        self._last_status_time = 0.0
        self._last_status_message = None   # the newest input status, also on /diagnostics

        quiet_pub, quiet_sub = qos.NO_PUBLISHER_EVENTS, qos.NO_SUBSCRIPTION_EVENTS  # wait set
        self.action_publisher = self.create_publisher(HumanAction, topics.HUMAN_ACTION,
                                                      qos.stream_qos(qos.HUMAN_ACTION_QOS),
                                                      event_callbacks=quiet_pub)
        self.wrench_publisher = self.create_publisher(WrenchStamped, topics.HUMAN_CMD_WRENCH,
                                                      qos.stream_qos(qos.COMMAND_QOS),
                                                      event_callbacks=quiet_pub)
        self.status_publisher = self.create_publisher(DiagnosticStatus, HUMAN_INPUT,
                                                      qos.SESSION_QOS)
        # The session first: when an announcement and a state wait together, the executor
        # serves them in creation order, and the state must be answered with the new roles.
        self.create_subscription(SessionStatus, topics.SESSION, self.on_session,
                                 qos.SESSION_QOS, event_callbacks=quiet_sub)
        self.create_subscription(TaskState, topics.STATE, self.on_state, qos.STATE_QOS,
                                 event_callbacks=quiet_sub)
        # The sim's control period and limits, read from the sim's parameters (never repeated
        # here). States are subscribed from the start, so that discovery matches the sim's
        # writer early (a state published to a reader not matched yet is lost); one that comes
        # before the limits waits for them (on_sim_limits answers it).
        self.sim_query = ParameterQuery(self, params.sim_node, SimLimits.NAMES,
                                        self.on_sim_limits, optional=SimLimits.OPTIONAL_NAMES)
        # At the human's rate the sim sends the states within each period here; each is
        # answered with a wrench (lockstep: the sim waits for it), no HumanAction.
        self.create_subscription(TaskState, topics.SLICE_STATE, self.on_state, qos.STATE_QOS,
                                 event_callbacks=quiet_sub)
        self._state_before_limits = None
        self._state_while_out = None     # the newest state not answered while sitting out
        self._waiting_since = time.monotonic()
        self.joy_subscription = None
        if self.joy is not None:
            self.joy_subscription = self.create_subscription(Joy, topics.JOY, self.on_joy,
                                                             qos.JOY_QOS)
        self.create_timer(params.input_check_period, self.check_inputs)
        # A person acts continuously: a stick event is forwarded at once (HumanCore.forward).
        # A thread waits on the device's file descriptor and wakes the executor through a
        # guard condition; the device is read and the answer published in the executor's
        # thread, as everything else.
        self._stick_moved = self.create_guard_condition(self.on_stick_moved)
        self._stick_read = threading.Event()
        self._watching = threading.Event()
        self._watcher = None
        if self.device is not None:
            self._watching.set()
            self._watcher = threading.Thread(target=self._watch_device, daemon=True,
                                             name='stick watcher')
            self._watcher.start()
        person = f' person {params.person}' if params.person >= 0 else ''
        self.get_logger().info(
            f'human node: input={params.input}, device={params.device}, axis={params.axis}'
            f'{" inverted" if params.invert else ""}, deadzone={params.deadzone}, '
            f'enable_button={params.enable_button}, on_input_lost={params.on_input_lost}, '
            f'profile={params.profile}{person}, dof={self.core.dof} (until a session '
            f'arrives), subtasks={self.core.subtasks}; parameters: {as_dict(params)}')
        self.check_inputs()

    def _declare(self) -> HumanParams:
        """Declare the parameters; ParameterError with every reason, the profile's among them.

        The profile is checked against the profiles file also when other values are wrong,
        and a bad profiles file is named as the parameter ``profiles_file``. The profiles read
        are kept (``_profiles``, ``_profiles_path``) for the core.
        """
        try:
            params, reasons = declare_parameters(self, HumanParams), []
        except ParameterError as error:
            params, reasons = None, list(error.reasons)
        values = {name: self.get_parameter(name).value for name in ('profile', 'profiles_file',
                                                                    'person')
                  if self.has_parameter(name)}
        path = self._profiles_path = values.get('profiles_file') or default_profiles_path()
        try:
            profiles = self._profiles = load_profiles(path)
            if params is not None or 'profile' in values:
                resolve_profile(params or HumanParams(**values), profiles, str(path))
        except ParameterError as error:
            named = [reason if reason.startswith(('profile:', 'profiles_file:'))
                     else f'profiles_file: {reason}' for reason in error.reasons]
            reasons += [reason for reason in named if reason not in reasons]
        except (TypeError, ValueError):
            pass                        # a wrong type: declare_parameters said so
        if reasons:
            raise ParameterError('HumanParams rejected: ' + '; '.join(reasons), reasons)
        return params

    @property
    def answered(self) -> int:
        """States answered so far (not counting repeats)."""
        return self.core.answered

    # -- the sim's limits ------------------------------------------------------------------
    def on_sim_limits(self, values: dict) -> None:
        """Take the sim's control period and limits; then answer states."""
        try:
            limits = SimLimits(**values)
            self.core.set_limits(limits)
        except (TypeError, ValueError) as error:
            self.get_logger().error(f'/{self.sim_query.target} parameters unusable: {error}; '
                                    f'no state is answered until they are',
                                    throttle_duration_sec=10.0)
            self.sim_query.restart()   # ask again: a restarted sim may give usable ones
            return
        self.get_logger().info(f'from /{self.sim_query.target}: {limits.describe()}')
        waiting, self._state_before_limits = self._state_before_limits, None
        if waiting is not None:
            self.on_state(waiting)

    def wait_for_sim(self, now: float) -> None:
        """Ask the sim for its limits until it answers; say every 10 s that we wait."""
        if self.sim_query.done:
            return
        self.sim_query.poll()
        if now - self._waiting_since >= SIM_WAIT_REPORT_S:
            self._waiting_since = now
            self.get_logger().warning(
                f"waiting for the sim's control period and limits on {self.sim_query.service} "
                f'(is the sim running, under the node name {self.sim_query.target!r} '
                f'(parameter sim_node), in this ROS domain?)')

    # -- inputs ----------------------------------------------------------------------------
    def check_inputs(self) -> None:
        """Drain the device, reopen it if absent, watch /joy, pick the input, report it."""
        now = time.monotonic()
        logger = self.get_logger()
        self.wait_for_sim(now)
        device_present, device_status = False, 'no device configured'
        if self.device is not None:
            was_present = self.device.present
            if was_present:
                self.device.poll()
            if was_present and not self.device.present:
                logger.warning(f'joystick device {self.device.status}')
            if not self.device.present and now >= self._next_open_attempt:
                self._next_open_attempt = now + self.params.reopen_period
                if self.device.open():
                    verb = 'reappeared' if self.device.opened_count > 1 else 'opened'
                    logger.info(f'joystick device {self.params.device} {verb}')
                elif self.device.rejected:
                    logger.warning(f'joystick device {self.device.status}',
                                   throttle_duration_sec=10.0)
            garbage = self.device.parser.garbage_bytes
            if garbage > self._reported_garbage and not self.device.rejected:
                logger.warning(f'joystick stream from {self.params.device}: skipped '
                               f'{garbage - self._reported_garbage} byte(s) that are no '
                               f'js_event (resynchronized; {garbage} in total)')
            self._reported_garbage = max(self._reported_garbage, garbage)
            device_present, device_status = self.device.present, self.device.status
        joy_alive, joy_status = False, '/joy not used'
        if self.joy is not None:
            self.joy.on_publisher_count(
                self.count_publishers(self.joy_subscription.topic_name), now)
            joy_alive, joy_status = self.joy.alive(now), self.joy.status(now)
            if joy_alive != self._joy_was_alive:
                if joy_alive:
                    logger.info(f'/joy input available: {joy_status}')
                else:
                    logger.warning(f'/joy input lost: {joy_status}')
                self._joy_was_alive = joy_alive
        change = self.core.on_inputs(device_present, device_status, joy_alive, joy_status)
        if change is not None:
            if self.core.input_status.state == 'ok':
                logger.info(change)
            else:
                logger.warning(change)
        self.publish_status(now)

    def _diagnostics(self) -> list:
        """Return the input status as ``human: input`` (none before the first)."""
        message = self._last_status_message
        if message is None:
            return []
        return [DiagnosticStatus(level=message.level, name='human: input',
                                 message=message.message, hardware_id=message.hardware_id,
                                 values=list(message.values))]

    def publish_status(self, now: float) -> None:
        """Publish the input status on a change, and every STATUS_HEARTBEAT s."""
        status = self.core.input_status
        decision = status._replace(reason='')
        if decision == self._last_status and now - self._last_status_time < STATUS_HEARTBEAT:
            return
        self._last_status, self._last_status_time = decision, now
        hardware = {DEVICE: self.params.device, JOY: topics.JOY}.get(status.active, '')
        extra = {'lost_count': self.core.selector.lost_count,
                 'human_involved': self.core.involved}
        if self.device is not None:
            extra['device'] = self.params.device
            extra['device_status'] = self.device.status
            extra['garbage_bytes'] = self.device.parser.garbage_bytes
        if self.joy is not None:
            extra['joy_status'] = self.joy.status(now)
        message = status_message(status, hardware, extra)
        self._last_status_message = message
        self.status_publisher.publish(message)

    def on_joy(self, message: Joy) -> None:
        """Keep the latest /joy axes and buttons; forward a move of the stick at once."""
        self.joy.on_message(message.axes, message.buttons, time.monotonic())
        self._forward()

    def _watch_device(self) -> None:
        """Thread: wake the executor whenever the device has bytes to read (no reading here)."""
        while self._watching.is_set():
            descriptor = self.device.fileno() if self.device is not None else -1
            if descriptor < 0:
                time.sleep(self.params.input_check_period)
                continue
            try:
                readable, _, _ = select.select([descriptor], [], [], 0.1)
            except (OSError, ValueError):   # closed under us: look again
                time.sleep(0.01)
                continue
            if readable:
                self._stick_read.clear()
                self._stick_moved.trigger()
                # Until the executor drained it the descriptor stays readable: wait for that
                # (and at most 1 kHz of wake-ups: a descriptor at end of file stays readable).
                self._stick_read.wait(0.05)
                time.sleep(0.001)

    def on_stick_moved(self) -> None:
        """Drain the device (it has events) and forward the stick's new position."""
        try:
            # The one path that reads the device: a vanished device is logged and reported
            # there (a direct poll here swallowed the 'vanished' warning of an unplug).
            self.check_inputs()
            self._forward()
        finally:
            self._stick_read.set()

    def _forward(self) -> None:
        """Send the stick as it is now, answering the newest state (HumanCore.forward)."""
        if self.core.limits is None:
            return
        answer = self.core.forward(self._sticks())
        if answer is not None:
            self._publish_wrench(answer)

    def _sticks(self) -> dict:
        params, sticks = self.params, {}
        if self.device is not None and self.device.present:
            sticks[DEVICE] = StickReading(self.device.axis(params.axis),
                                          self.device.button(params.enable_button),
                                          params.device)
        if self.joy is not None:
            sticks[JOY] = StickReading(self.joy.axis(params.axis),
                                       self.joy.button(params.enable_button),
                                       self.joy_subscription.topic_name)
        return sticks

    # -- session ---------------------------------------------------------------------------
    def on_session(self, message: SessionStatus) -> None:
        """Take the human's degree of freedom, involvement and subtasks from the session."""
        if message.human_dof not in DOF_NAME:
            self.get_logger().error(f'session {message.session_id!r}: human_dof '
                                    f'{message.human_dof} is unknown; session ignored')
            return
        aborted = message.phase == SessionStatus.PHASE_ABORTED
        was_aborted = self.core.aborted
        changed, unknown = self.core.on_session(DOF_NAME[message.human_dof],
                                                message.human_involved,
                                                list(message.human_subtasks), aborted)
        if unknown:
            self.get_logger().warning(f'session {message.session_id!r}: unknown human '
                                      f'subtask(s) {unknown} ignored')
        if aborted and not was_aborted:
            self.get_logger().warning(f'session {message.session_id!r} aborted: sending zero '
                                      f'({message.message})')
            zero = self.core.abort_answer()
            if zero is not None:
                self._publish(zero)
        if changed:
            core = self.core
            self.get_logger().info(
                f'session {message.session_id!r} (case {message.case_id}, '
                f'{message.strategy}, training step {message.training_step}): human drives '
                f'{core.dof}, {"involved" if core.involved else "not involved"}, '
                f'subtasks {core.subtasks}')
            self._answer_late_first_state(message.episode)

    def _answer_late_first_state(self, episode: int) -> None:
        """Answer the announced episode's first state if it came before the announcement.

        The agent announces an episode and waits (at most ANNOUNCE_ACK_TIMEOUT_S) for the
        readers' acknowledgement before the sim starts it; when that wait timed out, the first
        state can come first, while the human still sat out. The sim awaits the human from its
        own copy of the announcement: answering the state now saves a lockstep timeout (and a
        command counted missing). Only the first state of that very episode: any other kept
        state belongs to the robot alone.
        """
        late, self._state_while_out = self._state_while_out, None
        if (late is not None and self.core.answers_states and late.episode == episode
                and late.step == 0 and late.slice == 0):
            self.get_logger().info(f'episode {episode}: its announcement came after its first '
                                   'state: answering that state now')
            self.on_state(late)

    # -- the step --------------------------------------------------------------------------
    def on_state(self, message: TaskState) -> None:
        """Answer one sim state with the human's action and wrench (not the last state)."""
        if message.truncated or message.terminated:
            self._state_while_out = None
            return  # the last state of an episode needs no answer
        if self.core.limits is None:
            if self.core.involved:
                self._state_before_limits = message   # the newest: answered once the sim says
            else:
                self._state_while_out = message   # kept as below
            return
        if not self.core.answers_states:
            # Sitting out this training step: the sim awaits nothing of the human. Kept in
            # case the announcement of an episode with the human comes after its first state.
            self._state_while_out = message
            return
        if not self.core.aborted:
            self.check_inputs()
        limits = self.core.limits
        answer = self.core.answer(message.episode, message.step,
                                  stamp_ns(message.header.stamp),
                                  state_view(message, limits.control_period,
                                             limits.human_step),
                                  self._sticks(), slice_index=message.slice)
        if answer.repeated and self._last_messages is not None:
            # The same state again: repeat the answer (the simulated human was not advanced).
            if message.slice == 0:
                self.action_publisher.publish(self._last_messages[1])
            self.wrench_publisher.publish(self._last_messages[2])
            return
        self._publish(answer, message.header.stamp)

    def _publish(self, answer: HumanAnswer, stamp=None) -> None:
        """Publish the HumanAction and the WrenchStamped of one answer."""
        action = HumanAction(episode=answer.episode, step=answer.step, command=answer.command,
                             dof=DOF_INDEX[answer.dof], source=answer.source_code,
                             source_detail=answer.detail, engaged=answer.engaged)
        if stamp is None:
            action.header.stamp.sec, action.header.stamp.nanosec = divmod(answer.stamp_ns,
                                                                         NS_PER_S)
        else:
            action.header.stamp = stamp
        action.header.frame_id = 'world'
        wrench = WrenchStamped()
        wrench.header = action.header
        set_wrench_value(wrench.wrench, answer.dof, answer.wrench)
        if answer.slice == 0:   # one HumanAction per control step: a slice sends its wrench
            self.action_publisher.publish(action)
        self.wrench_publisher.publish(wrench)
        self._last_messages = (answer, action, wrench)

    def _publish_wrench(self, answer: HumanAnswer) -> None:
        """Publish only the wrench of a forwarded answer (the stick moved between states)."""
        wrench = WrenchStamped()
        wrench.header.stamp.sec, wrench.header.stamp.nanosec = divmod(answer.stamp_ns, NS_PER_S)
        wrench.header.frame_id = 'world'
        set_wrench_value(wrench.wrench, answer.dof, answer.wrench)
        self.wrench_publisher.publish(wrench)
        if self._last_messages is not None:
            self._last_messages = (answer, self._last_messages[1], wrench)

    def close(self) -> None:
        """Stop the stick watcher; release the joystick device."""
        self._watching.clear()
        if self._watcher is not None:
            self._watcher.join(timeout=1.0)
        if self.device is not None:
            self.device.close()


def main(args=None):
    """Run the human node (``ros2 run hrc_joystick_node human_node``)."""
    return run_node(HumanNode, 'human_node', SUMMARY, HumanParams, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
