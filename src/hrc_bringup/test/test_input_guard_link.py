"""The link watchdog of the input guard when the person joins after the robot learned alone.

The human node sends nothing while the person sits out a training step, so the
watchdog's silence must be counted from the person's joining, not from the first state of
the session: the first state of the person's first episode comes before their first answer.
"""

from types import SimpleNamespace

from hrc_bringup import input_guard
from hrc_common.contract import Phase
from hrc_msgs.msg import HumanAction, SessionStatus, TaskState


class FakeNode:
    """What InputGuard asks of an rclpy node, recording the publications."""

    def __init__(self):
        self.published = []

    def create_publisher(self, *_):
        return SimpleNamespace(publish=self.published.append)

    def create_client(self, *_):
        return SimpleNamespace(service_is_ready=lambda: False)

    def create_subscription(self, *_):
        return None


def test_the_silence_counts_from_the_persons_joining_and_a_real_one_still_pauses(monkeypatch):
    clock = [100.0]
    monkeypatch.setattr(input_guard.time, 'monotonic', lambda: clock[0])
    guard = input_guard.InputGuard(FakeNode(), 'sim', '', link_timeout=1.0)
    guard._on_status(SessionStatus(phase=int(Phase.TRAINING), human_involved=False))
    for _ in range(50):                  # 5 s of robot-alone states, nothing from the person
        guard._on_state(TaskState())
        guard.watch_link()
        clock[0] += 0.1
    assert guard.lost == ''
    # the person joins: the announcement, then the first state before their first answer
    guard._on_status(SessionStatus(phase=int(Phase.TRAINING), human_involved=True))
    guard._on_state(TaskState())
    guard.watch_link()
    assert guard.lost == ''
    guard._on_action(HumanAction(source=HumanAction.SOURCE_SIMULATED, source_detail='paper'))
    # then the person's side goes silent while states run: paused after link_timeout
    for _ in range(15):
        clock[0] += 0.1
        guard._on_state(TaskState())
        guard.watch_link()
    assert guard.lost.startswith('joystick disconnected: no answer from the person')
