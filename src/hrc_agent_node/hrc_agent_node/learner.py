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

On a machine with few cores the update competes with the control steps for the CPU and, inside
the agent's process, for the interpreter lock. So the learner thread lowers its own scheduling
priority (``niceness``: Linux keeps a nice value per thread) and, while an update runs, the
interpreter's switch interval is shortened (``switch_interval``) so that the control thread
waits at most about that long for the lock; both back to what they were when the update is
swapped in. 0 for either: as before.
"""

import os
import sys
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

    def __init__(self, agent, niceness: int = 0, switch_interval: float = 0.0):
        """Learn for ``agent`` in a thread; see the module docstring for the two settings.

        ``niceness``: added to the learner thread's nice value; ``switch_interval`` (s): the
        interpreter's while an update runs (0: unchanged).
        """
        self.agent = agent
        self.niceness = int(niceness)
        self.switch_interval = float(switch_interval)
        self._thread = None
        self._stats = None
        self._error = None
        self._switch_interval_before = None

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
            lower_this_threads_priority(self.niceness)
            try:
                self._stats = self.agent.update(buffer)
            except BaseException as error:  # noqa: B902 - re-raised in the control thread
                self._error = error

        if self.switch_interval > 0:
            self._switch_interval_before = sys.getswitchinterval()
            sys.setswitchinterval(min(self.switch_interval, self._switch_interval_before))
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
        if self._switch_interval_before is not None:
            sys.setswitchinterval(self._switch_interval_before)
            self._switch_interval_before = None
        self.agent.release_actor()
        if self._error is not None:
            error, self._error = self._error, None
            raise RuntimeError('the background update failed') from error
        stats, self._stats = self._stats, None
        return stats


def lower_this_threads_priority(niceness: int) -> None:
    """Add ``niceness`` to the calling thread's nice value (at most 19; Linux: per thread).

    Best effort: where the system has no per-thread nice value or refuses, nothing changes
    (lowering one's own priority needs no privilege on Linux).
    """
    if niceness <= 0 or not hasattr(os, 'setpriority'):
        return
    thread = threading.get_native_id()
    try:
        os.setpriority(os.PRIO_PROCESS, thread,
                       min(19, os.getpriority(os.PRIO_PROCESS, thread) + niceness))
    except OSError:
        pass


def make_learner(mode: str, agent, niceness: int = 0, switch_interval: float = 0.0):
    """Return the learner of ``mode`` (one of LEARNER_MODES) for ``agent``.

    ``niceness`` and ``switch_interval``: the background learner's (see the module docstring).
    """
    if mode == 'synchronous':
        return SynchronousLearner(agent)
    if mode == 'background':
        return BackgroundLearner(agent, niceness, switch_interval)
    raise ValueError(f'learner mode {mode!r} is not one of {LEARNER_MODES}')
