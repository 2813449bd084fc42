"""The human node in its own process over DDS: lockstep answers, session, /joy, device, auto."""

import os
import time
import uuid

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
import numpy
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Joy

from hrc_common.paths import params_dir
from hrc_common import qos, topics
from hrc_common.contract import SimLimits
from hrc_testing.nodes import serve_sim_parameters
from hrc_joystick_node.human_node import HUMAN_INPUT
from hrc_joystick_node.js_event import JS_EVENT_AXIS, JS_EVENT_BUTTON, JS_EVENT_INIT, pack_event
from hrc_joystick_node.human_profile import load_profile
from hrc_joystick_node.sim_human import SimulatedHuman
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState
from hrc_msgs.srv import ResetEpisode

CONTROL_PERIOD = 0.2   # s: the sim's control period (params/sim.yaml), the people's call period
WAIT = 30.0  # s: generous bound for anything over DDS (node start-up too) on a busy machine
SIM_LIMITS = SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5)  # the sim's defaults
PARAMS = params_dir()


class Harness:
    """The test's side of the graph: a fake sim (states), a session, /joy, and listeners.

    Every topic is remapped under a prefix unique to the test, on both sides: concurrent test
    runs on this machine may share a ROS domain id, and their sims, agents and benches must not
    talk to this test's human node (it also shows the node's topics are remappable).
    """

    def __init__(self, context):
        import rclpy

        self.prefix = '/test_' + uuid.uuid4().hex[:12]
        self.context = context
        self.sim_parameters = None
        self.node = rclpy.create_node('human_node_test', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.states = self.node.create_publisher(TaskState, self.topic(topics.STATE),
                                                 qos.STATE_QOS)
        self.session = self.node.create_publisher(SessionStatus, self.topic(topics.SESSION),
                                                  qos.SESSION_QOS)
        self.joy = None  # created by publish_joy(): in auto mode a publisher alone counts
        self.actions, self.wrenches = {}, {}
        self.action_log = []
        # Deeper than the node's history: a burst of answers must not be dropped here.
        self.action_subscription = self.node.create_subscription(
            HumanAction, self.topic(topics.HUMAN_ACTION), self._on_action,
            QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        self.wrench_subscription = self.node.create_subscription(
            WrenchStamped, self.topic(topics.HUMAN_CMD_WRENCH), self._on_wrench,
            qos.COMMAND_QOS)
        self.statuses = []
        self.node.create_subscription(DiagnosticStatus, self.topic(HUMAN_INPUT),
                                      self.statuses.append, qos.SESSION_QOS)
        self.joy_message = None
        self._joy_timer = None

    def topic(self, name):
        """Return the test's name of topic ``name``."""
        return self.prefix + name

    def start(self, start_node, parameters=None, sim_node=None, limits=SIM_LIMITS, **kwargs):
        """Start the human node with every topic remapped under the test's prefix.

        The node reads the sim's period and limits from node ``sim_node``; by default from a
        stand-in node of this test that declares ``limits`` as the sim does.
        """
        if sim_node is None:
            sim_node = self.serve_sim_parameters(limits)
        remaps = []
        for name in (topics.STATE, topics.SESSION, topics.JOY, topics.HUMAN_ACTION,
                     topics.HUMAN_CMD_WRENCH, HUMAN_INPUT):
            remaps += ['-r', f'{name}:={self.topic(name)}']
        return start_node('hrc_joystick_node', 'human_node', ros_args=remaps,
                          parameters=dict(parameters or {}, sim_node=sim_node), **kwargs)

    def serve_sim_parameters(self, limits) -> str:
        """Serve ``limits`` as parameters of a node with a unique name; return the name."""
        name = 'sim_' + self.prefix[len('/test_'):]
        self.sim_parameters = serve_sim_parameters(self.context, limits, name)
        self.executor.add_node(self.sim_parameters)
        return name

    def _on_action(self, message):
        self.action_log.append(message)
        self.actions[stamp_key(message.header.stamp)] = message

    def _on_wrench(self, message):
        self.wrenches[stamp_key(message.header.stamp)] = message

    def spin_until(self, condition, timeout=WAIT) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def wait_for_human_node(self, process):
        # Matched endpoints, both ways, not the graph's node counts: the graph can list the
        # node's answer writers before they matched this test's readers, and an answer
        # published in between is lost (volatile), which failed a CI run with "no answer to
        # step 0".
        connected = self.spin_until(
            lambda: (self.states.get_subscription_count() > 0
                     and self.action_subscription.get_publisher_count() > 0
                     and self.wrench_subscription.get_publisher_count() > 0))
        assert connected, f'the human node did not come up:\n{process.output}'

    def step(self, state, process, timeout=WAIT):
        """Publish a state and return (HumanAction, WrenchStamped) answering it."""
        key = stamp_key(state.header.stamp)
        self.states.publish(state)
        answered = self.spin_until(lambda: key in self.actions and key in self.wrenches,
                                   timeout)
        assert answered, f'no answer to step {state.step}:\n{process.output}'
        return self.actions[key], self.wrenches[key]

    def publish_joy(self, axes, buttons, rate=20.0):
        """Publish /joy continuously (as a joy node with autorepeat) until stop_joy()."""
        self.joy_message = Joy(axes=[float(a) for a in axes], buttons=list(buttons))
        if self.joy is None:
            self.joy = self.node.create_publisher(Joy, self.topic(topics.JOY), qos.JOY_QOS)
        if self._joy_timer is None:
            self._joy_timer = self.node.create_timer(1.0 / rate,
                                                     lambda: self.joy.publish(self.joy_message))

    def stop_joy(self):
        """Stop publishing; the publisher stays (a joy node that fell silent)."""
        if self._joy_timer is not None:
            self.node.destroy_timer(self._joy_timer)
            self._joy_timer = None

    def close(self):
        if self.sim_parameters is not None:
            self.sim_parameters.destroy_node()
        self.node.destroy_node()


def stamp_key(stamp):
    return (stamp.sec, stamp.nanosec)


def task_state(episode, step, physics_state=None, truncated=False, **values):
    """Return a TaskState stamped with a unique simulation time for (episode, step)."""
    message = TaskState(episode=episode, step=step, truncated=truncated)
    if physics_state is not None:
        for name in ('slider_position', 'slider_velocity', 'pendulum_angle',
                     'pendulum_angular_velocity', 'ball_position', 'ball_velocity'):
            setattr(message, name, float(getattr(physics_state, name)))
    for name, value in values.items():
        setattr(message, name, value)
    nanoseconds = (episode * 100_000 + step * 200) * 1_000_000
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(nanoseconds, 10 ** 9)
    message.header.frame_id = 'world'
    return message


@pytest.fixture
def harness(rclpy_context):
    harness = Harness(rclpy_context)
    yield harness
    harness.close()


def make_session(human_dof, involved, subtasks, training_step=0, episode=0):
    return SessionStatus(session_id='test', case_id=4, strategy='level_guided',
                         training_step=training_step, training_step_count=2,
                         human_dof=human_dof, robot_dof=1 - human_dof,
                         human_involved=involved, human_subtasks=subtasks, episode=episode)


def test_answers_every_lockstep_step_exactly_as_the_pure_simulated_human(start_node, harness):
    from hrc_sim_node.physics import SliderPendulumBall

    process = harness.start(start_node, parameters={'input': 'sim', 'profile': 'paper',
                                                    'seed': 3})
    harness.wait_for_human_node(process)
    reference = SimulatedHuman(load_profile('paper'), 'rotation', seed=3,
                               control_period=CONTROL_PERIOD)
    reference.reset(0)
    with SliderPendulumBall() as physics:
        physics_state = physics.reset(seed=11)
        for step in range(25):  # lockstep: the next state only after the answer
            state = task_state(0, step, physics_state)
            action, wrench = harness.step(state, process)
            # The node's clock for the person is the state's stamp (simulation time).
            expected = reference.act(physics_state, ['pendulum'],
                                     now=state.header.stamp.sec + state.header.stamp.nanosec
                                     * 1e-9)
            assert (action.episode, action.step) == (0, step)
            assert action.header.stamp == state.header.stamp == wrench.header.stamp
            assert action.command == expected, 'the node is the pure simulated human'
            assert action.dof == HumanAction.DOF_ROTATION
            assert action.source == HumanAction.SOURCE_SIMULATED
            assert action.source_detail == 'paper' and action.engaged
            assert wrench.wrench.torque.x == pytest.approx(0.5 * expected)  # max_torque 0.5
            assert (wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z,
                    wrench.wrench.torque.y, wrench.wrench.torque.z) == (0, 0, 0, 0, 0)
            physics_state = physics.step_normalized(0.0, action.command)

    # The same state again (a republished sample) gets the same answer, the model untouched.
    repeated = len(harness.action_log)
    harness.states.publish(state)
    assert harness.spin_until(lambda: len(harness.action_log) > repeated)
    first_answer = harness.actions[stamp_key(state.header.stamp)]
    assert harness.action_log[-1].command == first_answer.command

    # The last state of an episode needs no answer; the next episode's first state does.
    # Answers come in order from one publisher, so an answer to the last state would show up
    # before the answer to the next one.
    before = len(harness.action_log)
    harness.states.publish(task_state(0, 25, truncated=True))
    action, _ = harness.step(task_state(1, 0, pendulum_angle=0.1), process)
    assert [(a.episode, a.step) for a in harness.action_log[before:]] == [(1, 0)]
    assert len({(a.episode, a.step) for a in harness.action_log}) == 25 + 1


def test_follows_the_session_roles_and_sends_nothing_when_not_involved(start_node, harness):
    # A sim with a 4 N slider: the human's wrench follows the sim's limit, read at run time.
    process = harness.start(start_node, params_file=PARAMS / 'human.yaml',
                            parameters={'input': 'sim', 'profile': 'skilled', 'seed': 1},
                            limits=SimLimits(control_period=0.2, max_force=4.0,
                                             max_torque=0.5))
    harness.wait_for_human_node(process)
    assert harness.spin_until(
        lambda: 'control period 0.2 s, max_force 4 N, max_torque 0.5 N*m' in process.output)
    # Until a session arrives: the parameters (rotation, involved).
    action, wrench = harness.step(task_state(0, 0, pendulum_angle=0.3), process)
    assert action.dof == HumanAction.DOF_ROTATION and action.engaged
    assert action.command < 0 and wrench.wrench.torque.x < 0, 'pushes the raised beam down'

    harness.session.publish(make_session(SessionStatus.DOF_TRANSLATION, True, ['T2_1']))
    assert harness.spin_until(lambda: 'human drives translation' in process.output), \
        process.output
    action, wrench = harness.step(task_state(0, 1, slider_position=0.05), process)
    assert action.dof == HumanAction.DOF_TRANSLATION and action.engaged
    assert action.command < 0, 'pushes the high slider down'
    assert wrench.wrench.force.z == pytest.approx(4.0 * action.command)
    assert wrench.wrench.torque.x == 0.0

    harness.session.publish(make_session(SessionStatus.DOF_TRANSLATION, False, [], 1))
    assert harness.spin_until(lambda: 'not involved' in process.output), process.output
    # Sitting out: no answer at all (the sim awaits the robot only then).
    silent = [task_state(0, step, slider_position=0.05) for step in range(2, 5)]
    for state in silent:
        harness.states.publish(state)
    harness.spin_until(lambda: False, 1.0)
    keys = {stamp_key(state.header.stamp) for state in silent}
    assert not keys & (set(harness.actions) | set(harness.wrenches)), process.output
    # Involved again: the next state is answered (the node was there all along).
    harness.session.publish(make_session(SessionStatus.DOF_TRANSLATION, True, ['T2_1'], 2))
    assert harness.spin_until(
        lambda: process.output.count('human drives translation, involved') == 2), process.output
    action, wrench = harness.step(task_state(0, 5, slider_position=0.05), process)
    assert action.engaged and action.command < 0
    # The kept state of a step in the middle of an episode is never answered late (above:
    # step 4 had no answer after the node joined again). An announcement that comes after
    # its episode's first state (the agent's wait for its acknowledgement timed out): that
    # state is answered once the node knows it is involved, not only at the sim's timeout.
    harness.session.publish(make_session(SessionStatus.DOF_TRANSLATION, False, [], 3, 1))
    assert harness.spin_until(
        lambda: process.output.count('not involved') == 2), process.output
    first = task_state(1, 0, slider_position=0.05)
    harness.states.publish(first)
    harness.spin_until(lambda: False, 0.5)
    assert stamp_key(first.header.stamp) not in harness.actions
    assert stamp_key(task_state(0, 4).header.stamp) not in harness.actions
    harness.session.publish(make_session(SessionStatus.DOF_TRANSLATION, True, ['T2_1'], 4, 1))
    key = stamp_key(first.header.stamp)
    assert harness.spin_until(lambda: key in harness.actions and key in harness.wrenches), \
        process.output
    assert harness.actions[key].engaged and 'its announcement came after' in process.output


def test_joy_input_over_dds_with_deadman_deadline_and_return(start_node, harness):
    process = harness.start(start_node, parameters={
        'input': 'joy', 'on_input_lost': 'zero', 'joy_timeout': 0.5, 'axis': 1,
        'deadzone': 0.1, 'invert': True, 'enable_button': 2, 'input_check_period': 0.05})
    harness.wait_for_human_node(process)
    harness.publish_joy([0.3, 0.55], [0, 0, 1])
    step = 0

    def answer():
        nonlocal step
        action, wrench = harness.step(task_state(0, step), process)
        step += 1
        return action, wrench

    def answer_until(condition):
        deadline = time.monotonic() + WAIT
        while time.monotonic() < deadline:
            action, wrench = answer()
            if condition(action):
                return action, wrench
            harness.spin_until(lambda: False, timeout=0.05)
        raise AssertionError(f'condition not met; last {action}:\n{process.output}')

    action, wrench = answer_until(lambda a: a.source == HumanAction.SOURCE_JOY and a.engaged
                                  and a.command != 0.0)
    # axis 1 = 0.55 -> deadzone 0.1 rescaled: 0.5 -> inverted: -0.5; rotation: torque.x
    assert action.command == pytest.approx(-0.5)
    assert wrench.wrench.torque.x == pytest.approx(-0.25)
    assert action.source_detail == harness.topic('/joy')

    harness.publish_joy([0.3, 0.55], [0, 0, 0])  # deadman released
    action, _ = answer_until(lambda a: not a.engaged)
    assert action.command == 0.0 and action.source == HumanAction.SOURCE_JOY
    assert 'enable button released' in action.source_detail

    harness.stop_joy()  # the joy node falls silent: past the deadline, zero is held
    action, _ = answer_until(lambda a: a.source == HumanAction.SOURCE_NONE)
    assert (action.command, action.engaged) == (0.0, False)
    assert 'silent' in action.source_detail
    assert '/joy input lost' in process.output

    harness.publish_joy([0.0, -1.0], [0, 0, 1])  # back
    action, _ = answer_until(lambda a: a.source == HumanAction.SOURCE_JOY and a.engaged)
    assert action.command == pytest.approx(1.0)


def js(event_type, number, value, init=False):
    return pack_event(0, value, event_type | (JS_EVENT_INIT if init else 0), number)


def test_device_through_a_fifo_with_garbage_deadman_and_hot_plug(start_node, harness,
                                                                  tmp_path):
    fifo = str(tmp_path / 'js0')
    os.mkfifo(fifo)
    writer = os.open(fifo, os.O_RDWR)  # the joystick "plugged in" (O_RDWR never blocks)
    os.write(writer, js(JS_EVENT_AXIS, 0, 0, init=True) + js(JS_EVENT_AXIS, 1, 0, init=True)
             + js(JS_EVENT_BUTTON, 0, 1, init=True))
    process = harness.start(start_node, parameters={
        'input': 'device', 'device': fifo, 'on_input_lost': 'sim', 'reopen_period': 0.2,
        'enable_button': 0, 'deadzone': 0.0, 'profile': 'skilled', 'dof': 'translation',
        'input_check_period': 0.05})
    try:
        harness.wait_for_human_node(process)
        step = 0

        def answer(**values):
            nonlocal step
            action, _ = harness.step(task_state(0, step, **values), process)
            step += 1
            return action

        action = answer()
        assert action.source == HumanAction.SOURCE_DEVICE, process.output
        assert action.source_detail == fifo and action.command == 0.0 and action.engaged

        # Stick pushed up (kernel: negative), sent in two pieces with garbage in between:
        # sampled when the state arrives, so the next answer has it.
        record = js(JS_EVENT_AXIS, 1, -16384)
        os.write(writer, b'\xff\xff\xff' + record[:5])
        os.write(writer, record[5:])
        action = answer()
        assert action.command == pytest.approx(16384 / 32767)
        assert action.dof == HumanAction.DOF_TRANSLATION
        # the 3 bytes of garbage are reported as they are read (the stick is forwarded as it
        # moves, so the device is read as bytes arrive, possibly in two reports): 3 in total
        assert harness.spin_until(lambda: '(resynchronized; 3 in total)' in process.output), \
            process.output

        os.write(writer, js(JS_EVENT_BUTTON, 0, 0))  # deadman released
        action = answer()
        assert (action.command, action.engaged) == (0.0, False)

        os.close(writer)  # unplugged: the simulated human takes over at once, as configured
        writer = None
        action = answer(slider_position=0.05)
        assert action.source == HumanAction.SOURCE_SIMULATED, process.output
        assert action.engaged and action.command < 0.0
        assert action.source_detail.startswith('skilled (joystick disconnected (the simulated '
                                               'human stands in (on_input_lost: sim)')
        assert 'vanished' in process.output

        writer = os.open(fifo, os.O_RDWR)  # plugged in again
        os.write(writer, js(JS_EVENT_AXIS, 1, 32767, init=True)
                 + js(JS_EVENT_BUTTON, 0, 1, init=True))
        deadline = time.monotonic() + WAIT
        while action.source != HumanAction.SOURCE_DEVICE and time.monotonic() < deadline:
            harness.spin_until(lambda: False, timeout=0.1)
            action = answer()
        assert action.source == HumanAction.SOURCE_DEVICE, process.output
        assert action.command == -1.0, 'the INIT state of the reopened device'
        assert 'reappeared' in process.output
    finally:
        if writer is not None:
            os.close(writer)


def test_auto_selects_device_then_joy_and_never_the_simulated_human(start_node, harness,
                                                                      tmp_path):
    fifo = str(tmp_path / 'js0')
    os.mkfifo(fifo)  # exists, but nobody writes: not a present device
    process = harness.start(start_node, parameters={
        'input': 'auto', 'device': fifo, 'reopen_period': 0.2, 'joy_timeout': 0.5,
        'on_input_lost': 'zero', 'input_check_period': 0.05})
    harness.wait_for_human_node(process)
    step = 0

    def answer_until(source, command=None):
        nonlocal step
        deadline = time.monotonic() + WAIT
        while time.monotonic() < deadline:
            action, _ = harness.step(task_state(0, step, pendulum_angle=0.2), process)
            step += 1
            if action.source == source and (command is None
                                             or action.command == pytest.approx(command)):
                return action
            harness.spin_until(lambda: False, timeout=0.05)
        raise AssertionError(f'never switched to source {source} ({command}): last {action}'
                             f'\n{process.output}')

    # Nothing connected: zero held (was: the simulated human, silently).
    action = answer_until(HumanAction.SOURCE_NONE)
    assert action.source_detail.startswith('no joystick yet (zero held)'), action
    assert 'no joystick yet' in process.output, 'the log says why'

    harness.publish_joy([0.0, 0.5], [])
    answer_until(HumanAction.SOURCE_JOY, (0.5 - 0.05) / 0.95)  # deadzone 0.05 rescaled

    writer = os.open(fifo, os.O_RDWR)
    try:
        os.write(writer, js(JS_EVENT_AXIS, 1, 32767, init=True))
        answer_until(HumanAction.SOURCE_DEVICE, -1.0)
        assert 'auto: the device opened' in process.output
    finally:
        os.close(writer)
    answer_until(HumanAction.SOURCE_JOY)  # device gone, /joy still there

    harness.stop_joy()  # a real input was lost: the policy (zero), not the simulated human
    action = answer_until(HumanAction.SOURCE_NONE)
    assert (action.command, action.engaged) == (0.0, False)
    assert action.source_detail.startswith('joystick disconnected (zero held)')
    assert not any(a.source == HumanAction.SOURCE_SIMULATED for a in harness.action_log)


def status_values(status):
    return {pair.key: pair.value for pair in status.values}


def test_input_status_says_missing_ok_lost_and_not_a_joystick(start_node, harness, tmp_path):
    # The default policy (pause): a missing or lost joystick holds zero and the node reports
    # it on /hrc/human/input for the session to pause; /dev/urandom-like streams are lost with
    # the reason, and none of their bytes becomes a command.
    fifo = str(tmp_path / 'js0')
    process = harness.start(start_node, parameters={
        'input': 'device', 'device': fifo, 'reopen_period': 0.1, 'input_check_period': 0.05})
    harness.wait_for_human_node(process)

    def latest_status(state):
        harness.spin_until(lambda: harness.statuses
                           and status_values(harness.statuses[-1])['state'] == state)
        assert harness.statuses, process.output
        status = harness.statuses[-1]
        assert status_values(status)['state'] == state, (status, process.output)
        return status, status_values(status)

    status, values = latest_status('missing')
    assert status.level == DiagnosticStatus.ERROR and values['pause_requested'] == 'true'
    assert status.message.startswith('no joystick yet (zero held, session should pause)')
    assert 'No such file' in status.message
    action, _ = harness.step(task_state(0, 0, pendulum_angle=0.3), process)
    assert (action.source, action.command, action.engaged) == (HumanAction.SOURCE_NONE, 0.0,
                                                               False)

    os.mkfifo(fifo)
    writer = os.open(fifo, os.O_RDWR)
    try:
        os.write(writer, js(JS_EVENT_AXIS, 1, 0, init=True))
        status, values = latest_status('ok')
        assert status.level == DiagnosticStatus.OK and values['active'] == 'device'
        assert values['pause_requested'] == 'false' and status.hardware_id == fifo
        noise = numpy.random.default_rng(7).integers(0, 256, 16384, dtype=numpy.uint8)
        os.write(writer, noise.tobytes())
        status, values = latest_status('lost')
        assert status.level == DiagnosticStatus.ERROR and values['pause_requested'] == 'true'
        assert status.message.startswith('joystick disconnected (zero held, session should '
                                         'pause)')
        assert 'is not a joystick' in status.message
        for step in range(1, 6):
            action, _ = harness.step(task_state(0, step), process)
            assert action.source == HumanAction.SOURCE_NONE and action.command == 0.0
            assert 'not a joystick' in action.source_detail or 'no writer' in \
                action.source_detail
    finally:
        os.close(writer)
    assert int(status_values(harness.statuses[-1])['lost_count']) >= 1


def test_drives_the_real_sim_node_in_lockstep_without_a_missing_command(start_node, harness):
    states = []
    # A deep history: the sim runs as fast as the human answers, this listener must keep up.
    deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    harness.node.create_subscription(TaskState, harness.topic(topics.STATE), states.append,
                                     deep)
    remaps = []
    for name in (topics.STATE, topics.SESSION, topics.HUMAN_CMD_WRENCH, topics.ROBOT_CMD_WRENCH,
                 topics.CLOCK, topics.MARKERS, topics.CAMERA_IMAGE, topics.RESET_SERVICE):
        remaps += ['-r', f'{name}:={harness.topic(name)}']
    # The real sim under a name of this test: the human node reads its period and limits.
    sim_name = 'sim_' + harness.prefix[len('/test_'):]
    sim = start_node('hrc_sim_node', 'sim_node', ros_args=remaps + ['-r', f'__node:={sim_name}'],
                     parameters={'expected_actors': ['human'], 'marker_rate': 0.0,
                                 'lockstep_timeout': 1.0, 'robot_dof': 'translation'})
    human = harness.start(start_node, parameters={'input': 'sim', 'profile': 'skilled'},
                          sim_node=sim_name)
    harness.wait_for_human_node(human)
    assert harness.spin_until(lambda: f'from /{sim_name}: control period 0.2 s' in human.output)
    reset = harness.node.create_client(ResetEpisode, harness.topic(topics.RESET_SERVICE))
    assert harness.spin_until(reset.service_is_ready), sim.output

    def episode(index):
        """Start an episode as the agent does; return its states once the last arrived."""
        del states[:]
        future = reset.call_async(ResetEpisode.Request(seed=4 + index, episode=index))
        assert harness.spin_until(future.done), sim.output
        assert future.result().success, future.result().message
        # After the last state (truncated) the sim holds until the next reset.
        assert harness.spin_until(lambda: states and states[-1].truncated, timeout=60), \
            sim.output
        return list(states)

    # Episode 0 warms the graph up: the sim publishes its first state as soon as it is reset,
    # possibly before it has discovered the human node (a volatile sample is then lost and
    # that step counts as missing, by the lockstep timeout). Episode 1 is the measurement.
    episode(0)
    answered_before = {(a.episode, a.step) for a in harness.action_log}
    measured = episode(1)
    assert [state.step for state in measured] == list(range(201)), sim.output
    assert {state.episode for state in measured} == {1}
    assert not any(state.human_command_missing for state in measured), sim.output
    # The human held the beam: far from the stop where zero action leaves it.
    assert max(abs(state.pendulum_angle) for state in measured[20:]) < 0.4
    answered = {(a.episode, a.step) for a in harness.action_log} - answered_before
    assert answered == {(1, step) for step in range(200)}


@pytest.mark.parametrize('parameters, reason', [
    ({'input': 'keyboard'}, "input: 'keyboard' is not one of"),
    ({'profile': 'expert'}, "profile: 'expert' is not in"),
    ({'on_input_lost': 'panic'}, "on_input_lost: 'panic' is not one of"),
    ({'input': 'model'}, 'model_file: input model needs a checkpoint path'),
    ({'input': 'model', 'model_file': '/nonexistent/clone.pt'}, 'cannot read'),
])
def test_bad_parameters_exit_2_with_the_reason(start_node, parameters, reason):
    process = start_node('hrc_joystick_node', 'human_node', parameters=parameters)
    assert process.wait(timeout=30) == 2
    assert reason in process.output


@pytest.mark.parametrize('content, reason', [
    (b'profiles: {paper: [\n', 'not valid YAML (line 2'),
    (b'- paper\n- skilled\n', 'expected a mapping with "profiles:", got list'),
    (bytes(range(256)) * 4, 'not a YAML text file (binary content)'),
    (b'profiles:\n  paper: 5\n', "profile 'paper': expected a mapping of fields, got int"),
    (None, 'cannot read: No such file or directory'),
])
def test_a_bad_profiles_file_exits_2_with_the_reason(start_node, tmp_path, content, reason):
    # Was: a traceback and exit 1 for a profiles_file that is not YAML or is a list.
    path = tmp_path / 'profiles.yaml'
    if content is not None:
        path.write_bytes(content)
    process = start_node('hrc_joystick_node', 'human_node',
                         parameters={'input': 'sim', 'profiles_file': str(path)})
    assert process.wait(timeout=30) == 2, process.output
    assert reason in process.output
    assert 'Traceback' not in process.output
