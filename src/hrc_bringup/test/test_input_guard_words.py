"""What the input guard decides and says: an abort is no lost joystick; a joystick back is said.

The guard reads the human node's answers (``/hrc/human/action``), its input status
(``/hrc/human/input``) and the agent's status (``/hrc/session``): three topics whose messages
arrive in any order, so nothing it decides may depend on that order.
"""

from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from hrc_bringup import input_guard
from hrc_common.contract import Phase, SimLimits
from hrc_common.paths import params_dir
from hrc_joystick_node.human_core import HumanCore, HumanParams, SOURCE_CODE
from hrc_joystick_node.human_profile import load_profiles
from hrc_msgs.msg import HumanAction, SessionStatus
import pytest


class FakeNode:
    """What InputGuard asks of an rclpy node; publications by topic, publishers counted."""

    def __init__(self, joy_publishers: int = 0):
        self.published, self.publishers, self.joy_publishers = {}, [], joy_publishers
        self.destroyed = 0

    def create_publisher(self, _type, topic, _qos):
        self.publishers.append(topic)
        return SimpleNamespace(publish=lambda message: self.published.setdefault(
            topic, []).append(message))

    def destroy_publisher(self, publisher):
        self.destroyed += 1

    def create_client(self, *_):
        return SimpleNamespace(service_is_ready=lambda: False)

    def create_subscription(self, *_):
        return None

    def create_service(self, *_):
        return object()

    def count_publishers(self, _topic):
        return self.joy_publishers


def abort_answer_of_the_human_node() -> HumanAction:
    """Return the zero the real human core sends when it sees the operator's abort."""
    core = HumanCore(HumanParams(input='sim', profile='paper'),
                     load_profiles(params_dir() / 'sim_human.yaml'))
    core.set_limits(SimLimits(control_period=0.2, max_force=2.0, max_torque=0.5))
    core.on_inputs(False, '', False, '')
    core.on_session('translation', True, ['slider'])
    core.answer(0, 0, 0, SimpleNamespace(step=0, time=0.0, slider_position=0.0,
                                         slider_velocity=0.0, pendulum_angle=0.1,
                                         pendulum_angular_velocity=0.0, ball_position=0.0,
                                         ball_velocity=0.0))
    core.on_session('translation', True, ['slider'], aborted=True)
    zero = core.abort_answer()
    return HumanAction(source=SOURCE_CODE[zero.source], source_detail=zero.detail)


def input_status(ok: bool, message: str) -> DiagnosticStatus:
    return DiagnosticStatus(message=message, values=[
        KeyValue(key='state', value='ok' if ok else 'lost'),
        KeyValue(key='pause_requested', value='false' if ok else 'true')])


def test_an_operator_abort_is_not_a_lost_joystick_whichever_topic_comes_first():
    guard = input_guard.InputGuard(FakeNode(), 'device', '/dev/input/js0')
    guard._on_status(SessionStatus(phase=int(Phase.TRAINING), human_involved=True,
                                   strategy='responsibility_guided'))
    # the human node's zero after the abort arrives before the agent's aborted status
    guard._on_action(abort_answer_of_the_human_node())
    assert guard.lost == ''
    guard._on_status(SessionStatus(phase=int(Phase.ABORTED), human_involved=True))
    assert guard.lost == ''
    # a real loss is still one
    guard = input_guard.InputGuard(FakeNode(), 'device', '/dev/input/js0')
    guard._on_status(SessionStatus(phase=int(Phase.TRAINING), human_involved=True,
                                   strategy='responsibility_guided'))
    guard._on_action(HumanAction(source=HumanAction.SOURCE_NONE,
                                 source_detail='/dev/input/js0 vanished (unplugged?)'))
    assert guard.lost == 'joystick disconnected: /dev/input/js0 vanished (unplugged?)'


def test_the_joystick_back_is_said_at_once_and_lost_again_too():
    node = FakeNode()
    guard = input_guard.InputGuard(node, 'device', '/dev/input/js0')
    guard._on_status(SessionStatus(phase=int(Phase.TRAINING), human_involved=True,
                                   strategy='responsibility_guided'))
    guard._on_input_status(input_status(False, '/dev/input/js0 vanished'))
    assert guard.lost.startswith('joystick disconnected')
    lost_words = [message.data for message in node.published['/hrc/session/input_lost']]
    assert lost_words == ['', guard.lost]
    # plugged in again: input_lost (the pages' and the agent's) is cleared before any resume
    guard._on_input_status(input_status(True, '/dev/input/js0 opens'))
    assert node.published['/hrc/session/input_lost'][-1].data == ''
    # unplugged again before the resume: said again
    guard._on_input_status(input_status(False, '/dev/input/js0 vanished'))
    assert node.published['/hrc/session/input_lost'][-1].data == guard.lost
    # the agent is the one writer of /hrc/session: the runner stands in for nobody
    assert '/hrc/session' not in node.publishers


def test_the_loss_ends_when_the_agents_status_runs_again_after_its_hold(capsys):
    """The agent holds in its process; its own statuses say the hold and the resume."""
    node = FakeNode()
    guard = input_guard.InputGuard(node, 'device', '/dev/input/js0')
    running = SessionStatus(phase=int(Phase.TRAINING), human_involved=True,
                            strategy='responsibility_guided', episode=4)
    guard._on_status(running)
    guard._on_input_status(input_status(False, '/dev/input/js0 vanished'))
    guard._on_status(running)          # a status from before the hold, late: still lost
    assert guard.lost and not guard.held
    guard._on_status(SessionStatus(phase=int(Phase.PAUSED), human_involved=True,
                                   message='joystick disconnected: paused'))
    assert guard.lost and guard.held
    guard._on_input_status(input_status(True, '/dev/input/js0 opens'))
    assert guard.lost                  # back, but not resumed yet
    guard._on_status(running)          # the operator's resume: the agent runs on
    assert guard.lost == '' and not guard.held
    assert node.published['/hrc/session/input_lost'][-1].data == ''
    assert 'resumed by the operator: the agent goes on in its process' in capsys.readouterr().out


@pytest.mark.parametrize('kind', ['joy', 'auto'])
def test_a_joy_node_that_is_there_is_not_called_missing(kind):
    present, why = input_guard.InputGuard(FakeNode(joy_publishers=1), kind, '/nonexistent/js9')\
        .present()
    assert present and why == '/joy has 1 publisher'
    present, why = input_guard.InputGuard(FakeNode(), 'joy', '/nonexistent/js9').present()
    assert not present and 'no joy node is running' in why
