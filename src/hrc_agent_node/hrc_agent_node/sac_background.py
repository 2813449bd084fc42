"""SAC's gradient steps in a learner thread, for the realtime episodes of a person. Pure.

Under the ``step`` schedule SAC owes ``sac_updates_per_step`` critic steps and one actor step for
every stored transition. Taken inside the control step, as the lockstep sessions do, they
delay the robot's command by tens of milliseconds and, on a machine with two cores, push the
sim's and the person's loop off its period (bench/realtime_jitter.py --compare-learning). In a
realtime episode the control step only stores the transition and acts; this thread takes the
owed steps as they come, at a lower scheduling priority (``niceness``, Linux keeps one per
thread) and with a short interpreter switch interval while it runs, holding the learner's lock
one gradient step at a time, so an action waits at most one gradient step. What it has not
done by the episode's end runs in ``SAC.update()``, between episodes.

A realtime session is not reproducible step for step in any case (a person's timing is not);
the lockstep sessions, the graph and the in-process engine never use this thread.
"""

import sys
import threading

from hrc_agent_node.learner import lower_this_threads_priority

# s: how long the idle thread sleeps before looking for owed steps again (woken at once by
# every stored transition; the timeout only bounds a missed wake-up)
IDLE_WAIT_S = 0.05


class BackgroundSACLearning:
    """A thread that takes a SAC learner's owed gradient steps until stopped."""

    def __init__(self, sac, niceness: int = 0, switch_interval: float = 0.0):
        self.sac = sac
        self.niceness = int(niceness)
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._switch_interval_before = None
        if switch_interval > 0:
            self._switch_interval_before = sys.getswitchinterval()
            sys.setswitchinterval(min(float(switch_interval), self._switch_interval_before))
        self.error = None
        self._thread = threading.Thread(target=self._run, name='hrc-sac-learner', daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """Say that a transition was stored (its gradient steps are owed)."""
        self._wake.set()

    def stop(self) -> None:
        """Stop after the current gradient step; re-raise a failure of the thread."""
        self._stop.set()
        self._wake.set()
        self._thread.join()
        if self._switch_interval_before is not None:
            sys.setswitchinterval(self._switch_interval_before)
            self._switch_interval_before = None
        if self.error is not None:
            raise RuntimeError('the background SAC learning failed') from self.error

    def _run(self) -> None:
        lower_this_threads_priority(self.niceness)
        try:
            while not self._stop.is_set():
                if not self.sac.learn_one_owed():
                    self._wake.wait(IDLE_WAIT_S)
                    self._wake.clear()
        except BaseException as error:  # noqa: B902 - re-raised in the control thread by stop()
            self.error = error
