"""Messages held for a moment and handed on in the order DDS received them (pure, no rclpy).

The recorder takes its subscriptions' messages topic after topic, so when it lags behind it
gets one topic's messages later than another topic's received after them. Each message waits
here ``reorder_window`` seconds of its log time (the DDS reception time), or longer while the
recorder lags: LAG_FACTOR times the largest lag of the last LAG_MEMORY_NS, at most
LAG_LIMIT_NS, so an episode's file is not closed before its messages still queued in DDS are
in. :class:`hrc_bag.recording.EpisodeRecorder` routes what comes out.
"""

import collections
import heapq
import itertools
import typing

from hrc_common.contract import NS_PER_S

# the wait for late messages follows the executor's lag of the last second, times 1.5, up to
# 5 s (a log time older than that comes from another clock, e.g. a test's synthetic times)
LAG_MEMORY_NS = NS_PER_S            # 1 s
LAG_FACTOR = 1.5
LAG_LIMIT_NS = 5 * NS_PER_S         # 5 s


class ReceptionOrder:
    """A heap of (message, event) by log time, with the lag-following wait (module docstring)."""

    def __init__(self, reorder_window: float, wall_clock: typing.Callable):
        self._window_ns = int(reorder_window * NS_PER_S)   # reorder_window: s
        self._wall_clock = wall_clock       # ns since the epoch, the clock of the log times
        self._heap = []                     # (log time, arrival, message, event)
        self._arrivals = itertools.count()
        # (arrival ns, lag ns) of the last LAG_MEMORY_NS, lags decreasing: a sliding maximum
        self._lags = collections.deque()

    def add(self, messages: list) -> None:
        """Hold ``(message, event)`` pairs taken together (one message: a list of one).

        The executor's lag is counted once per call, as the lag of its oldest message (every
        message was taken at the same moment, so that lag is the largest).
        """
        if not messages:
            return
        oldest = messages[0][0].log_time
        for message, event in messages:
            heapq.heappush(self._heap, (message.log_time, next(self._arrivals), message, event))
            oldest = min(oldest, message.log_time)
        now = self._wall_clock()
        lag = now - oldest
        while self._lags and self._lags[-1][1] <= lag:
            self._lags.pop()
        self._lags.append((now, lag))

    def waiting_window(self, now: int) -> int:
        """Return how long (ns) a message waits for others: reorder_window or the lag."""
        while self._lags and self._lags[0][0] < now - LAG_MEMORY_NS:
            self._lags.popleft()
        lag = self._lags[0][1] if self._lags else 0
        return max(self._window_ns, min(int(LAG_FACTOR * lag), LAG_LIMIT_NS))

    def due(self, everything: bool = False):
        """Yield (message, event) received more than waiting_window ago (all: everything)."""
        now = self._wall_clock()
        threshold = now - self.waiting_window(now)
        while self._heap and (everything or self._heap[0][0] <= threshold):
            _, _, message, event = heapq.heappop(self._heap)
            yield message, event
