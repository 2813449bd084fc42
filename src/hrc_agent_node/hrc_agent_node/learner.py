"""Who runs a policy update, and when its new weights reach the actor. Pure (no rclpy).

:class:`~hrc_agent_node.agent_core.AgentCore` hands a full rollout to a learner at a step
boundary (or at an episode's end) and asks it, at every later step boundary of a training
episode, whether new weights are ready. Two modes:

* :class:`SynchronousLearner` (lockstep, the offline loop, the in-process engine, and every
  episode the agent node runs in lockstep): the update runs at once in the caller's thread, so
  the action for the state at which the update was due already comes from the new weights. The
  swap happens at a defined step, so a session is reproduced from its seed and the ROS graph
  and the in-process engine stay bit-identical.
* :class:`BackgroundLearner` (the agent node's realtime episodes): the update runs in a thread
  on the learner's networks while the actor keeps acting with a frozen copy of the old ones;
  the first step boundary after the update finished swaps the new weights in. The control step
  never waits for an update. Which step that is depends on wall time, so realtime sessions are
  not reproducible step for step (they are not in any case: a person's timing is not).

The learned object (``agent``, the PPO learner) needs ``update(buffer) -> dict``,
``freeze_actor()`` (act with a copy of the current weights from now on) and ``release_actor()``
(act with the learner's weights again). Samples collected while a background update runs come
from the old policy; PPO's clipped ratio is computed against the log-probabilities they were
drawn with, so they stay valid for the next update (slightly off-policy, as any asynchronous
actor-learner).
"""

import threading

LEARNER_MODES = ('synchronous', 'background')


class SynchronousLearner:
    """Run each update at once in the caller's thread (deterministic)."""

    mode = 'synchronous'

    def __init__(self, agent):
        self.agent = agent

    @property
    def busy(self) -> bool:
        """Return False: a synchronous update has finished when :meth:`start` returns."""
        return False

    def start(self, buffer) -> dict:
        """Update on ``buffer`` now; return the update's statistics (the new weights act next)."""
        return self.agent.update(buffer)

    def poll(self):
        """Return None: nothing is ever pending."""
        return None

    def wait(self):
        """Return None: nothing is ever pending."""
        return None


class BackgroundLearner:
    """Run each update in a thread; the actor acts with the old weights until it finished."""

    mode = 'background'

    def __init__(self, agent):
        self.agent = agent
        self._thread = None
        self._stats = None
        self._error = None

    @property
    def busy(self) -> bool:
        """Return True while an update started by :meth:`start` has not been swapped in."""
        return self._thread is not None

    def start(self, buffer):
        """Start an update on ``buffer`` (which the caller must not change any more); None."""
        if self.busy:
            raise RuntimeError('an update is still running: poll() or wait() first')
        self.agent.freeze_actor()
        self._stats, self._error = None, None

        def run():
            try:
                self._stats = self.agent.update(buffer)
            except BaseException as error:  # noqa: B902 - re-raised in the control thread
                self._error = error

        self._thread = threading.Thread(target=run, name='hrc-learner', daemon=True)
        self._thread.start()
        return None

    def poll(self):
        """At a step boundary: swap in finished weights and return their statistics, else None."""
        if self._thread is None or self._thread.is_alive():
            return None
        return self._finish()

    def wait(self):
        """Wait for a running update, swap its weights in, return its statistics (None: none)."""
        if self._thread is None:
            return None
        return self._finish()

    def _finish(self):
        self._thread.join()
        self._thread = None
        self.agent.release_actor()
        if self._error is not None:
            error, self._error = self._error, None
            raise RuntimeError('the background update failed') from error
        stats, self._stats = self._stats, None
        return stats


def make_learner(mode: str, agent):
    """Return the learner of ``mode`` (one of LEARNER_MODES) for ``agent``."""
    if mode == 'synchronous':
        return SynchronousLearner(agent)
    if mode == 'background':
        return BackgroundLearner(agent)
    raise ValueError(f'learner mode {mode!r} is not one of {LEARNER_MODES}')
