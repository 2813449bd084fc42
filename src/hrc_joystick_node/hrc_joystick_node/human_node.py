"""The human node (``human``): joystick device, /joy or the simulated human -> the human's command.

Subscribes ``/hrc/state`` (TaskState), ``/hrc/session`` (SessionStatus, transient local) and,
when the input may be ``/joy``, ``/joy`` (sensor_msgs/Joy). For every state that is not the last
of its episode it publishes ``/hrc/human/action`` (HumanAction) and ``/hrc/human/cmd_wrench``
(WrenchStamped, only the human's degree of freedom set, scaled by ``max_force``/``max_torque``),
both carrying the state's stamp, so the lockstep sim can match them to the step. It answers even
when the human is not involved (zero, ``engaged`` false), so the sim can always wait for both
actors. When the session is aborted (phase ``aborted``) it sends a zero command at once,
answering the newest state, and zero for anything after. Which input drives the command,
and the fallback when it is lost, are in :mod:`hrc_joystick_node.inputs`; the joystick device
is sampled (drained without blocking) when each state arrives, so the command is the stick's
position at that moment.
"""

from dataclasses import dataclass
import time
import typing

from geometry_msgs.msg import WrenchStamped
from hrc_common import qos, topics
from hrc_common.dof import DOF_INDEX, DOF_NAME, DOFS, set_wrench_value, TRANSLATION
from hrc_common.nodes import run_node
from hrc_common.params import as_dict, declare_parameters, param, ParameterError
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from rclpy.node import Node
from sensor_msgs.msg import Joy

from hrc_joystick_node.inputs import (DEVICE, FALLBACKS, INPUT_MODES, InputSelector, JOY,
                                      JoyInput, SIM, stick_command, ZERO)
from hrc_joystick_node.js_event import JoystickDevice
from hrc_joystick_node.sim_human import (BALL, default_profiles_path, load_profiles,
                                         normalize_subtasks, OWN_SUBTASK, SimulatedHuman)

SUMMARY = ('The human side of hrc: reads a Linux joystick device, sensor_msgs/Joy on /joy, or '
           'runs a simulated human, and answers every /hrc/state with /hrc/human/action and '
           '/hrc/human/cmd_wrench on the degree of freedom the session gives the human.')
SOURCE_OF = {DEVICE: HumanAction.SOURCE_DEVICE, JOY: HumanAction.SOURCE_JOY,
             SIM: HumanAction.SOURCE_SIMULATED, ZERO: HumanAction.SOURCE_NONE}


@dataclass
class HumanParams:
    """Parameters of the human node (mirrored in params/human.yaml)."""

    input: str = param('auto', 'where the command comes from: auto = the device if it opens, '
                       'else /joy if a publisher is seen, else the simulated human',
                       choices=INPUT_MODES)
    device: str = param('/dev/input/js0', 'Linux joystick device (or a FIFO/file carrying its '
                        'js_event stream)')
    axis: int = param(1, 'joystick axis that drives the command, same index on the device and '
                      'on /joy (1 = left stick vertical on most gamepads)', low=0, high=63)
    invert: bool = param(False, 'flip the axis: by default stick up/left (the Joy convention, '
                         '+1) commands + (slider up, east end of the beam up)')
    deadzone: float = param(0.05, 'axis magnitudes below this read as 0; the rest is rescaled '
                            'to [0, 1] (normalized units)', low=0.0, high=0.9)
    enable_button: int = param(-1, 'deadman button that must be held for a non-zero command '
                               '(-1 = none)', low=-1, high=255)
    joy_timeout: float = param(1.0, '/joy counts as silent after this long without a message '
                               '(s, wall time); the joy node must publish faster '
                               '(autorepeat_rate)', low=0.05, high=60.0)
    on_input_lost: str = param('sim', 'when the device vanishes or /joy falls silent: hand over '
                               'to the simulated human (sim) or hold zero (zero)',
                               choices=FALLBACKS)
    reopen_period: float = param(1.0, 'interval between attempts to (re)open an absent device '
                                 '(s)', low=0.05, high=60.0)
    input_check_period: float = param(0.1, 'interval of the input check: drain the device, '
                                      'watch the /joy deadline (s)', low=0.01, high=5.0)
    dof: str = param('rotation', 'degree of freedom of the human until /hrc/session says',
                     choices=DOFS)
    involved: bool = param(True, 'whether the human acts, until /hrc/session says')
    hold_ball: bool = param(False, 'whether the human is also asked to hold the ball, until '
                            "/hrc/session lists the human's subtasks")
    max_force: float = param(2.0, 'force (N) of a full command on translation; same value as '
                             "the sim's max_force", low=0.01, high=100.0)
    max_torque: float = param(0.5, 'torque (N*m) of a full command on rotation; same value as '
                              "the sim's max_torque", low=0.001, high=50.0)
    control_period: float = param(0.2, 'control period of the sim (s), for the simulated '
                                  "human's delay and fatigue", low=0.01, high=1.0)
    profile: str = param('paper', 'simulated-human profile (a name in profiles_file)')
    profiles_file: str = param('', 'simulated-human profiles YAML (empty = the installed '
                               'share/hrc_joystick_node/params/sim_human.yaml)')
    seed: int = param(0, 'seed of the simulated human (with the episode index)', low=0,
                      high=2 ** 31 - 1)


class StateView(typing.NamedTuple):
    """The PhysicsState attributes the simulated human reads, taken from a TaskState."""

    step: int
    time: float
    slider_position: float
    slider_velocity: float
    pendulum_angle: float
    pendulum_angular_velocity: float
    ball_position: float
    ball_velocity: float


def state_view(message: TaskState, control_period: float) -> StateView:
    """Return the simulated human's view of a TaskState (time = s since the episode's reset)."""
    return StateView(message.step, message.step * control_period, message.slider_position,
                     message.slider_velocity, message.pendulum_angle,
                     message.pendulum_angular_velocity, message.ball_position,
                     message.ball_velocity)


class HumanNode(Node):
    """Answers every sim state with the human's command (see the module docstring)."""

    def __init__(self):
        super().__init__('human')
        self.params = params = declare_parameters(self, HumanParams)
        profiles_path = params.profiles_file or default_profiles_path()
        try:
            profiles = load_profiles(profiles_path)
        except OSError as error:
            raise ParameterError(f'profiles_file: cannot read {profiles_path}: {error}')
        if params.profile not in profiles:
            raise ParameterError(f'profile: {params.profile!r} is not in {profiles_path} '
                                 f'(known: {sorted(profiles)})')
        self.profile = profiles[params.profile]

        # What the session says (parameters until the first /hrc/session arrives).
        self.dof = params.dof
        self.involved = params.involved
        self.subtasks = self._default_subtasks(self.dof)
        self.session_seen = False
        self.aborted = False
        self.sim_human = self._new_sim_human(self.dof)
        self._sim_episode = None
        self._sim_step = None

        self.selector = InputSelector(params.input, params.on_input_lost)
        self.device = JoystickDevice(params.device) if params.input in ('auto', DEVICE) else None
        self.joy = JoyInput(params.joy_timeout) if params.input in ('auto', JOY) else None
        self._next_open_attempt = 0.0
        self._reported_garbage = 0
        self._joy_was_alive = False
        self._last_answer = None  # (episode, step, HumanAction, WrenchStamped)
        self.answered = 0

        self.action_publisher = self.create_publisher(HumanAction, topics.HUMAN_ACTION,
                                                      qos.HUMAN_ACTION_QOS)
        self.wrench_publisher = self.create_publisher(WrenchStamped, topics.HUMAN_CMD_WRENCH,
                                                      qos.COMMAND_QOS)
        self.create_subscription(TaskState, topics.STATE, self.on_state, qos.STATE_QOS)
        self.create_subscription(SessionStatus, topics.SESSION, self.on_session,
                                 qos.SESSION_QOS)
        self.joy_subscription = None
        if self.joy is not None:
            self.joy_subscription = self.create_subscription(Joy, topics.JOY, self.on_joy,
                                                             qos.JOY_QOS)
        self.create_timer(params.input_check_period, self.check_inputs)
        self.get_logger().info(
            f'human node: input={params.input}, device={params.device}, axis={params.axis}'
            f'{" inverted" if params.invert else ""}, deadzone={params.deadzone}, '
            f'enable_button={params.enable_button}, on_input_lost={params.on_input_lost}, '
            f'profile={params.profile}, dof={self.dof} (until a session arrives), '
            f'subtasks={self.subtasks}; parameters: {as_dict(params)}')
        self.check_inputs()

    # -- helpers ---------------------------------------------------------------------------
    def _default_subtasks(self, dof: str) -> typing.List[str]:
        return [OWN_SUBTASK[dof]] + ([BALL] if self.params.hold_ball else [])

    def _new_sim_human(self, dof: str) -> SimulatedHuman:
        return SimulatedHuman(self.profile, dof, seed=self.params.seed,
                              control_period=self.params.control_period)

    # -- inputs ----------------------------------------------------------------------------
    def check_inputs(self) -> None:
        """Drain the device, reopen it if absent, watch /joy, and pick the active input."""
        now = time.monotonic()
        logger = self.get_logger()
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
            garbage = self.device.parser.garbage_bytes
            if garbage > self._reported_garbage:
                logger.warning(f'joystick stream from {self.params.device}: skipped '
                               f'{garbage - self._reported_garbage} byte(s) that are no '
                               f'js_event (resynchronized; {garbage} in total)')
                self._reported_garbage = garbage
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
        change = self.selector.update(device_present, device_status, joy_alive, joy_status)
        if change is not None:
            logger.info(change)

    def on_joy(self, message: Joy) -> None:
        """Keep the latest /joy axes and buttons."""
        self.joy.on_message(message.axes, message.buttons, time.monotonic())

    # -- session ---------------------------------------------------------------------------
    def on_session(self, message: SessionStatus) -> None:
        """Take the human's degree of freedom, involvement and subtasks from the session."""
        if message.human_dof not in DOF_NAME:
            self.get_logger().error(f'session {message.session_id!r}: human_dof '
                                    f'{message.human_dof} is unknown; session ignored')
            return
        dof = DOF_NAME[message.human_dof]
        subtasks, unknown = normalize_subtasks(message.human_subtasks)
        if unknown:
            self.get_logger().warning(f'session {message.session_id!r}: unknown human '
                                      f'subtask(s) {unknown} ignored')
        changed = (not self.session_seen or dof != self.dof
                   or bool(message.human_involved) != self.involved or subtasks != self.subtasks)
        if dof != self.dof:
            self.sim_human = self._new_sim_human(dof)
            self._sim_episode = None
        self.dof, self.involved, self.subtasks = dof, bool(message.human_involved), subtasks
        self.session_seen = True
        aborted = message.phase == SessionStatus.PHASE_ABORTED
        if aborted and not self.aborted:
            self.get_logger().warning(f'session {message.session_id!r} aborted: sending zero '
                                      f'({message.message})')
            if self._last_answer is not None:
                (episode, step), answered, _ = self._last_answer
                self._publish_zero(episode, step, answered.header.stamp)
        self.aborted = aborted
        if changed:
            self.get_logger().info(
                f'session {message.session_id!r} (case {message.case_id}, '
                f'{message.strategy}, training step {message.training_step}): human drives '
                f'{dof}, {"involved" if self.involved else "not involved"}, '
                f'subtasks {subtasks}')

    # -- the step --------------------------------------------------------------------------
    def on_state(self, message: TaskState) -> None:
        """Answer one sim state with the human's action and wrench (not the last state)."""
        if message.truncated or message.terminated:
            return  # the last state of an episode needs no answer
        key = (message.episode, message.step)
        if self.aborted:
            self._publish_zero(message.episode, message.step, message.header.stamp)
            return
        if self._last_answer is not None and self._last_answer[0] == key:
            # The same state again: repeat the answer, do not advance the simulated human.
            self.action_publisher.publish(self._last_answer[1])
            self.wrench_publisher.publish(self._last_answer[2])
            return
        self.check_inputs()
        command, engaged, source, detail = self._command(message)
        action = HumanAction(episode=message.episode, step=message.step, command=command,
                             dof=DOF_INDEX[self.dof], source=SOURCE_OF[source],
                             source_detail=detail, engaged=engaged)
        action.header.stamp = message.header.stamp
        action.header.frame_id = 'world'
        wrench = WrenchStamped()
        wrench.header = action.header
        scale = self.params.max_force if self.dof == TRANSLATION else self.params.max_torque
        set_wrench_value(wrench.wrench, self.dof, command * scale)
        self.action_publisher.publish(action)
        self.wrench_publisher.publish(wrench)
        self._last_answer = (key, action, wrench)
        self.answered += 1

    def _publish_zero(self, episode: int, step: int, stamp) -> None:
        """Publish a zero, disengaged command answering the state of ``stamp`` (abort)."""
        action = HumanAction(episode=episode, step=step, command=0.0, dof=DOF_INDEX[self.dof],
                             source=HumanAction.SOURCE_NONE,
                             source_detail='session aborted by the operator', engaged=False)
        action.header.stamp = stamp
        action.header.frame_id = 'world'
        wrench = WrenchStamped()
        wrench.header = action.header
        self.action_publisher.publish(action)
        self.wrench_publisher.publish(wrench)
        self._last_answer = ((episode, step), action, wrench)

    def _command(self, message: TaskState) -> tuple:
        """Return (command, engaged, input, source detail) for one state."""
        active = self.selector.active
        if not self.involved:
            return 0.0, False, ZERO, f'not involved in this training step (input: {active})'
        params = self.params
        use_enable = params.enable_button >= 0
        if active == DEVICE:
            command, engaged, why = stick_command(
                self.device.axis(params.axis), self.device.button(params.enable_button),
                use_enable, params.deadzone, params.invert)
            return command, engaged, DEVICE, params.device + (f' ({why})' if why else '')
        if active == JOY:
            command, engaged, why = stick_command(
                self.joy.axis(params.axis), self.joy.button(params.enable_button), use_enable,
                params.deadzone, params.invert)
            topic = self.joy_subscription.topic_name
            return command, engaged, JOY, topic + (f' ({why})' if why else '')
        if active == SIM:
            if (message.episode != self._sim_episode or self._sim_step is None
                    or message.step <= self._sim_step):
                self.sim_human.reset(message.episode)
                self._sim_episode = message.episode
            self._sim_step = message.step
            view = state_view(message, params.control_period)
            detail = params.profile
            if params.input != SIM:  # standing in for a lost or absent joystick: say why
                detail += f' ({self.selector.reason})'
            return self.sim_human.act(view, self.subtasks), True, SIM, detail
        return 0.0, False, ZERO, f'zero held: {self.selector.reason}'

    def close(self) -> None:
        """Release the joystick device."""
        if self.device is not None:
            self.device.close()


def main(args=None):
    """Run the human node (``ros2 run hrc_joystick_node human_node``)."""
    return run_node(HumanNode, 'human_node', SUMMARY, HumanParams, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
