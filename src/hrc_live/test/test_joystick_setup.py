"""The joystick set-up helper against a FIFO carrying the Linux js_event stream.

The helper runs as the installed executable; the test holds the FIFO open read-write (so it
never blocks and a writer is always present) and writes what a joystick would send.
"""

import os
import pty
import subprocess

from hrc_common import qos, topics
from hrc_common.contract import SimLimits
from hrc_common.params import load_yaml
from hrc_common.executables import executable_path
from hrc_testing.nodes import serve_sim_parameters, wait_for
from hrc_joystick_node.human_node import HumanParams
from hrc_joystick_node.js_event import (JS_EVENT_AXIS, JS_EVENT_BUTTON, JS_EVENT_INIT,
                                        pack_event)
from hrc_live.joystick_watch import deadzone_from_rest
from hrc_msgs.msg import HumanAction, TaskState
from hrc_sim_node.physics import PhysicsParams
import pytest
import yaml

HELPER = [str(executable_path('hrc_bringup', 'hrc')), 'joystick', 'setup']
# Rest positions (raw) of four axes as a slightly worn gamepad reports them, six buttons up.
REST = (0, 1200, 0, -300)


def initial_state() -> bytes:
    """Return the INIT events the driver sends right after open()."""
    events = [pack_event(0, value, JS_EVENT_AXIS | JS_EVENT_INIT, number)
              for number, value in enumerate(REST)]
    events += [pack_event(0, 0, JS_EVENT_BUTTON | JS_EVENT_INIT, number) for number in range(6)]
    return b''.join(events)


@pytest.fixture
def fifo(tmp_path):
    """Return (path, writer fd) of a FIFO standing in for /dev/input/js0."""
    path = tmp_path / 'js0'
    os.mkfifo(path)
    writer = os.open(path, os.O_RDWR | os.O_NONBLOCK)
    yield path, writer
    os.close(writer)


def run_helper(*args, until=None, then=b'', timeout=60):
    """Run the helper; when it prints a line starting with ``until``, write ``then``."""
    process = subprocess.Popen([*HELPER, *map(str, args)], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    output = []
    for raw in process.stdout:
        line = raw.decode()
        output.append(line)
        if until is not None and line.startswith(until):
            then()
    return process.wait(timeout=timeout), ''.join(output)


def test_detects_axis_direction_rest_and_enable_button_and_writes_the_human_yaml(fifo, tmp_path):
    path, writer = fifo
    os.write(writer, initial_state())
    output_file = tmp_path / 'joystick.yaml'

    def operator_moves():
        # Stick 2 pushed right to the end (raw + = right/down, so "-" in the Joy convention:
        # the helper must invert), a little wobble on axis 1, button 4 held.
        os.write(writer, pack_event(10, 20000, JS_EVENT_AXIS, 2)
                 + pack_event(20, 32767, JS_EVENT_AXIS, 2)
                 + pack_event(25, 1500, JS_EVENT_AXIS, 1)
                 + pack_event(30, 1, JS_EVENT_BUTTON, 4))

    code, output = run_helper(path, '--non-interactive', '--detect', 1, '--show', '-o',
                              output_file, until='watching', then=operator_moves)
    assert code == 0, output
    assert 'axes 0:+0.00 1:-0.05 2:-1.00 3:+0.01 | buttons 0:0 1:0 2:0 3:0 4:1 5:0' in output
    document = yaml.safe_load(output_file.read_text())
    assert document == {'human': {'ros__parameters': {
        'input': 'device', 'device': str(path), 'axis': 2, 'invert': True,
        'deadzone': 0.05, 'enable_button': 4}}}
    # The human node's own loader accepts the file.
    params = load_yaml(HumanParams, output_file, 'human')
    assert (params.input, params.axis, params.invert, params.enable_button) == (
        'device', 2, True, 4)


def test_the_rest_position_sets_the_deadzone():
    assert deadzone_from_rest(0.0) == 0.05      # never below the human node's default
    assert deadzone_from_rest(0.1) == 0.17      # 1.5 x rest + 0.02
    assert deadzone_from_rest(0.9) == 0.5       # never above half the travel


def test_flags_override_detection_and_nothing_moved_is_an_error(fifo, tmp_path):
    path, writer = fifo
    os.write(writer, initial_state())
    output_file = tmp_path / 'joystick.yaml'
    code, output = run_helper(path, '--non-interactive', '--detect', 0.3, '-o', output_file)
    assert code == 1
    assert 'no axis moved by 0.3 or more within 0.3 s' in output
    assert not output_file.exists()
    os.write(writer, initial_state())
    code, output = run_helper(path, '--non-interactive', '--detect', 0.3, '--axis', 1,
                              '--no-invert', '--deadzone', 0.1, '--enable-button', -1, '-o',
                              output_file)
    assert code == 0, output
    assert yaml.safe_load(output_file.read_text())['human']['ros__parameters'] == {
        'input': 'device', 'device': str(path), 'axis': 1, 'invert': False, 'deadzone': 0.1,
        'enable_button': -1}


def test_lists_devices_and_says_when_there_are_none(tmp_path):
    for name in ('js0', 'js1'):
        os.mkfifo(tmp_path / name)
    result = subprocess.run([*HELPER, '--list', '--devices', str(tmp_path / 'js*')],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0
    assert result.stdout.splitlines() == [
        f'{tmp_path / "js0"}: (no name: not a joystick device)',
        f'{tmp_path / "js1"}: (no name: not a joystick device)']
    result = subprocess.run([*HELPER, '--list', '--devices', str(tmp_path / 'nothing*')],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 1 and 'no joystick devices' in result.stdout


def test_guided_set_up_at_a_terminal_with_live_values_a_redo_and_a_check(fifo, tmp_path):
    path, writer = fifo
    os.write(writer, initial_state())
    output_file = tmp_path / 'joystick.yaml'
    terminal, helper_side = pty.openpty()  # the helper asks questions only at a terminal
    process = subprocess.Popen([*HELPER, str(path), '-o', str(output_file)],
                               stdin=helper_side, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT)
    os.close(helper_side)

    def send(events=b'', answer=b'\n'):
        def act():
            os.write(writer, events)
            os.write(terminal, answer)
        return act

    def rest_noise(time_ms, peak):
        # Once the rest watch shows its first live line: a twitch to `peak`, back to 1000.
        return lambda: os.write(writer, pack_event(time_ms, peak, JS_EVENT_AXIS, 1)
                                + pack_event(time_ms + 1, 1000, JS_EVENT_AXIS, 1))

    # (the line the helper prints, what the operator does then), in order.
    script = [
        ('Move the sticks', send()),
        ('Push the stick', send(pack_event(10, -32767, JS_EVENT_AXIS, 1))),  # axis 1 fully up
        ('Step 1 of 3', send()),
        ('Let go of the stick', send(pack_event(20, 2000, JS_EVENT_AXIS, 1))),
        ('rest watch: axis 1', rest_noise(21, 2500)),   # live values during the rest watch
        ('Step 2 of 3', send(answer=b'r\n')),   # redo the rest step
        ('Let go of the stick', send(pack_event(23, 1500, JS_EVENT_AXIS, 1))),
        ('rest watch: axis 1', rest_noise(24, 1800)),
        ('Step 2 of 3', send()),
        ('Press and hold the button', send(pack_event(30, 1, JS_EVENT_BUTTON, 2))),
        ('axes 0:', lambda: None),               # live values while the button is held
        ('Step 3 of 3', send()),
        ('Check: move the stick', send(pack_event(40, -16384, JS_EVENT_AXIS, 1))),
        ('Press Enter to write the file', send()),
    ]
    output = []
    try:
        for raw in process.stdout:
            line = raw.decode()
            output.append(line)
            if script and line.startswith(script[0][0]):
                script.pop(0)[1]()
        assert process.wait(timeout=60) == 0, ''.join(output)
    finally:
        os.close(terminal)
    text = ''.join(output)
    assert not script, (script, text)
    assert 'axis 1\n' in text  # pushed up = + in the Joy convention: not inverted
    # The rest is the largest deviation seen, from the redone step: 1800, not 1000 or 1500.
    rest = 1800 / 32767
    assert (f'at rest the axis reads up to {rest:.3f} (the largest deviation seen): deadzone '
            f'{deadzone_from_rest(rest)}') in text
    assert text.count('Let go of the stick') == 2
    # The check shows the command the human node would send (half up, deadman held).
    shaped = (16384 / 32767 - deadzone_from_rest(rest)) / (1 - deadzone_from_rest(rest))
    assert f'axis 1 reads +0.50 -> command {shaped:+.2f}' in text and 'deadman held' in text
    assert yaml.safe_load(output_file.read_text())['human']['ros__parameters'] == {
        'input': 'device', 'device': str(path), 'axis': 1, 'invert': False,
        'deadzone': deadzone_from_rest(rest), 'enable_button': 2}


def test_the_human_node_reads_the_written_file_and_the_stick(fifo, tmp_path, start_node,
                                                             rclpy_context):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    path, writer = fifo
    output_file = tmp_path / 'joystick.yaml'
    os.write(writer, initial_state())
    code, output = run_helper(path, '--non-interactive', '--detect', 0.3, '--axis', 2,
                              '--invert', '--deadzone', 0.1, '--enable-button', 4, '-o',
                              output_file)
    assert code == 0, output
    node = rclpy.create_node('test_live_joystick', context=rclpy_context)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    # The sim's period and limits, which the human node reads before it answers states.
    sim_parameters = serve_sim_parameters(rclpy_context, SimLimits.of(PhysicsParams()))
    executor.add_node(sim_parameters)
    human = start_node('hrc_joystick_node', 'human_node', params_file=output_file)
    assert wait_for(lambda: 'opened' in human.output, timeout=60), human.output
    # The stick half-way right (raw +16384: -0.5 in the Joy convention, +0.5 inverted) with the
    # enable button held.
    os.write(writer, initial_state() + pack_event(40, 16384, JS_EVENT_AXIS, 2)
             + pack_event(50, 1, JS_EVENT_BUTTON, 4))
    actions = []
    node.create_subscription(HumanAction, topics.HUMAN_ACTION, actions.append,
                             qos.HUMAN_ACTION_QOS)
    states = node.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
    step = [0]

    def engaged_action():
        step[0] += 1
        message = TaskState(episode=0, step=step[0])
        message.header.stamp.sec = step[0]
        states.publish(message)
        executor.spin_once(timeout_sec=0.2)
        return any(action.engaged and action.command != 0.0 for action in actions)

    assert wait_for(engaged_action, timeout=60), human.output
    action = next(action for action in actions if action.engaged and action.command != 0.0)
    assert action.source == HumanAction.SOURCE_DEVICE and str(path) in action.source_detail
    assert action.command == pytest.approx((16384 / 32767 - 0.1) / 0.9, abs=1e-3)
    executor.shutdown()
    sim_parameters.destroy_node()
    node.destroy_node()


def test_help_lists_the_options():
    result = subprocess.run([*HELPER, '--help'], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0
    for option in ('--list', '--axis', '--invert', '--deadzone', '--enable-button',
                   '--non-interactive', '--detect', '--output'):
        assert option in result.stdout
