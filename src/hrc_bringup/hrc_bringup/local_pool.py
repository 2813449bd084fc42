"""The sweep's embedded executor: a process per session on this machine, at most N at once.

``multiprocessing.Pool`` hangs when one of its workers dies (a killed worker's task is never
answered, and ``terminate`` after an interrupt can wait forever on the pool's own threads);
``concurrent.futures.ProcessPoolExecutor`` notices, but breaks the whole pool and loses every
session in progress. Here each task runs in a process of its own (spawned: a fresh interpreter,
no forked torch or PyBullet state) that sends its outcome through a pipe and exits. The driver
waits on the pipes: an outcome arrives, or the pipe ends without one when the process died
(killed, out of memory); that task alone is reported as lost, with how it ended, and the others
go on. A process start costs about a second against sessions of minutes.
"""

import multiprocessing
import multiprocessing.connection
import signal
import time

WAKE_PERIOD_S = 0.5         # the wait wakes this often so the main thread handles signals
STOP_GRACE_S = 10.0         # after SIGTERM, before SIGKILL, when the sweep is aborted


def _work(function, task, sender) -> None:
    """Worker process: run ``function(task)``, send its outcome, exit."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)    # Ctrl-C is the driver's to handle
    sender.send(function(task))
    sender.close()


def describe_exit(exitcode) -> str:
    """Return how a worker process ended ('killed by SIGKILL', 'exit code 1')."""
    if exitcode is not None and exitcode < 0:
        try:
            return f'killed by {signal.Signals(-exitcode).name}'
        except ValueError:
            return f'killed by signal {-exitcode}'
    return f'exit code {exitcode}'


class LocalPool:
    """A process per task on this machine, ``workers`` at a time."""

    def __init__(self, workers: int, lost=None):
        """``lost(task, how, seconds)``: the outcome of a task whose process died (or None)."""
        self.workers = workers
        self.lost = lost or (lambda task, how, seconds: None)
        self.context = multiprocessing.get_context('spawn')
        self.running = {}       # receiving end of the pipe -> (process, task, start time)

    def describe(self) -> str:
        """Return what runs the tasks."""
        return f'local process pool ({self.workers} workers)'

    def run(self, tasks, on_done, function=None):
        """Run every task (``function(task)``); call ``on_done(outcome)`` as each finishes.

        The wait for the next outcome wakes every :data:`WAKE_PERIOD_S`: Python runs signal
        handlers in the main thread only, and a SIGTERM or Ctrl-C the kernel hands to another
        thread does not end the main thread's wait, so without the wake the sweep would go on
        until the next session ended (minutes).
        """
        if function is None:
            from hrc_bringup.experiment_task import run_task as function  # lazy: torch
        waiting = list(tasks)
        while waiting or self.running:
            while waiting and len(self.running) < self.workers:
                self._start(function, waiting.pop(0))
            for receiver in multiprocessing.connection.wait(list(self.running),
                                                            timeout=WAKE_PERIOD_S):
                on_done(self._finish(receiver))

    def _start(self, function, task) -> None:
        receiver, sender = self.context.Pipe(duplex=False)
        process = self.context.Process(target=_work, args=(function, task, sender),
                                       daemon=True)
        process.start()
        sender.close()          # the worker holds the other end: its exit ends the pipe
        self.running[receiver] = (process, task, time.monotonic())

    def _finish(self, receiver):
        process, task, started = self.running.pop(receiver)
        try:
            outcome, answered = receiver.recv(), True
        except EOFError:        # the process ended without an outcome
            outcome, answered = None, False
        receiver.close()
        process.join()
        if not answered:
            outcome = self.lost(task, f'its worker process died '
                                f'({describe_exit(process.exitcode)})',
                                time.monotonic() - started)
        return outcome

    def close(self, abort: bool = False):
        """Stop the workers (``abort``: at once, sessions in progress are lost)."""
        processes = [process for process, _, _ in self.running.values()]
        for process in processes if abort else []:
            process.terminate()
        for process in processes:
            process.join(STOP_GRACE_S if abort else None)
            if process.is_alive():
                process.kill()
                process.join()
        for receiver in self.running:
            receiver.close()
        self.running.clear()
