"""Lockstep never outruns its recorder: the pure rule the sim node applies (no rclpy).

A lockstep sim steps as fast as its actors answer (about 2 ms a step in the graph). A recorder
that stalls (SIGSTOP, a swapped-out process, a slow disk under its drain) received nothing
while the writers' keep-last histories overwrote what it had not received: a recorder stopped
for 15 s missed whole episodes. The recorder therefore says how far it has taken the states
(the stamp of the newest ``/hrc/state`` after each batch it drains, on
``/hrc/recorder/progress``), and a sim that awaits it publishes no period state more than
:func:`window_states` control periods ahead of that stamp: the step is held until the recorder
catches up. Everything published inside the window is still in the writers' histories
(``STREAM_WRITER_DEPTH`` messages each), so the recorder gets it when it runs again.

Realtime sessions never wait (a person is acting); the report names the states a stalled
recorder missed there (``hrc_bag.report.loading.recording_gaps``).
"""

import typing

from hrc_common.qos_table import STREAM_WRITER_DEPTH

# Control periods a lockstep sim may run ahead of its recorder at most. The recorder drains its
# subscriptions every batch_period (0.05 s): at 50 states per batch the window costs a lockstep
# graph nothing measurable (it steps 2-3 ms a period); a smaller one would throttle it.
MAX_WINDOW_STATES = 50


def window_states(slices: int) -> int:
    """Return how many periods ahead of its recorder the sim may publish.

    The busiest recorded stream is the human's wrench, one message per human slice (``slices``
    a period); the window is what the writers' histories hold of it, with a period to spare.
    """
    return max(1, min(MAX_WINDOW_STATES, STREAM_WRITER_DEPTH // max(1, slices) - 1))


class RecorderGate:
    """Whether the next step may be taken, given the newest state the recorder acknowledged.

    Stamps are the protocol's: simulation time in integer ns, one control period per state.
    ``enabled`` False (a sim without a recorder to await) admits every step.
    """

    def __init__(self, enabled: bool, window: int, control_period_ns: int):
        self.enabled = enabled
        self.window_ns = window * control_period_ns
        self.acknowledged_ns = -1           # nothing acknowledged yet
        self.published_ns = -1              # no period state published yet
        self.held = None                    # the step order held until the recorder catches up
        self.held_since = None              # monotonic s

    def on_published(self, stamp_ns: int) -> None:
        """Note that a period state with ``stamp_ns`` was published."""
        self.published_ns = max(self.published_ns, stamp_ns)

    def admits(self) -> bool:
        """Return True if the next step may be taken now."""
        return (not self.enabled or self.published_ns < 0
                or self.published_ns - self.acknowledged_ns <= self.window_ns)

    def hold(self, order, now: float) -> None:
        """Keep ``order`` until the recorder has caught up (:meth:`on_progress`)."""
        self.held = order
        if self.held_since is None:
            self.held_since = now

    def on_progress(self, stamp_ns: int) -> typing.Optional[object]:
        """Take the recorder's newest state (``stamp_ns``); return the held order if now due."""
        if stamp_ns > self.acknowledged_ns:
            self.acknowledged_ns = stamp_ns
        if self.held is None or not self.admits():
            return None
        order, self.held, self.held_since = self.held, None, None
        return order

    def drop(self) -> None:
        """Forget a held order (an abort or a reset ends the episode it belongs to)."""
        self.held, self.held_since = None, None

    def waited(self, now: float) -> float:
        """Return how long (s) the held order has waited; 0 if none is held."""
        return 0.0 if self.held_since is None else now - self.held_since
