"""The sim node's side of "lockstep never outruns its recorder" (the rule: recorder_gate).

A mixin of :class:`hrc_sim_node.sim_node.SimNode`: it owns the acknowledgement's subscription
and a one-second check that says, while a step is held, how long the sim has waited, and
stops the sim (exit code 3, :class:`RecorderStalled`) after ``recorder_timeout``.
"""

import time

from hrc_common import qos, topics
from hrc_common.contract import NS_PER_S
from hrc_sim_node.protocol import stamp_ns
from hrc_sim_node.recorder_gate import RecorderGate, window_states
from hrc_sim_node.sim_params import LOCKSTEP
from std_msgs.msg import Header

# s: how often a held step is checked, and how often its warning is repeated at most
CHECK_PERIOD_S = 1.0
WARN_AFTER_S = 5.0
EXIT_RECORDER_STALLED = 3


class RecorderStalled(RuntimeError):
    """The recorder acknowledged nothing for recorder_timeout while the sim waited for it."""


class RecorderWait:
    """Hold lockstep steps the recorder has not caught up with (mixin of SimNode)."""

    def _setup_recorder_wait(self, params, slices: int) -> None:
        window = window_states(slices)
        self.recorder_gate = RecorderGate(params.await_recorder, window,
                                          round(params.control_period * NS_PER_S))
        self._recorder_warned_at = 0.0
        if not params.await_recorder:
            return
        self.create_subscription(Header, topics.RECORDER_PROGRESS, self._on_recorder_progress,
                                 qos.RECORDER_PROGRESS_QOS,
                                 event_callbacks=qos.NO_SUBSCRIPTION_EVENTS)
        self.create_timer(CHECK_PERIOD_S, self._check_recorder)
        self.get_logger().info(f'lockstep awaits the recorder: at most {window} states ahead '
                               f'of {topics.RECORDER_PROGRESS}')

    def _recorder_holds(self, order) -> bool:
        """Return True (and keep ``order``) if a lockstep step must wait for the recorder."""
        if self.protocol.mode != LOCKSTEP or self.recorder_gate.admits():
            return False
        self.recorder_gate.hold(order, time.monotonic())
        return True

    def _on_recorder_progress(self, message: Header) -> None:
        order = self.recorder_gate.on_progress(stamp_ns(message.stamp.sec,
                                                        message.stamp.nanosec))
        if order is not None and self.protocol.mode == LOCKSTEP:
            if self._recorder_warned_at:
                self.get_logger().info('the recorder caught up: lockstep goes on')
            self._recorder_warned_at = 0.0
            self._advance(order)

    def _check_recorder(self) -> None:
        now = time.monotonic()
        waited = self.recorder_gate.waited(now)
        if waited > self.params.recorder_timeout:
            raise RecorderStalled(
                f'the recorder acknowledged no state of {topics.STATE} for {waited:.0f} s '
                f'(recorder_timeout): stopping, the bags would miss what the session runs')
        if waited >= WARN_AFTER_S and now - self._recorder_warned_at >= WARN_AFTER_S:
            self._recorder_warned_at = now
            self.get_logger().warning(
                f'waiting for the recorder for {waited:.0f} s: it has not taken the states '
                f'after step {self._state.step if self._state else 0} (stalled or stopped); '
                f'lockstep goes on when it does, or stops after recorder_timeout '
                f'{self.params.recorder_timeout:g} s')
