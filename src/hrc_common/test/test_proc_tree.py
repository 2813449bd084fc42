"""A process tree's CPU for the benchmarks (hrc_common.proc_tree): what it counts, leaves out.

``thread_cpu_ns`` reads the living threads of a process and its descendants from /proc
schedstat: a busy grandchild counts, a process outside the tree (this one) does not, and one
that has left the tree no longer does. ``bench/middleware.py`` reports the recorder's running
CPU cost with it; the SIGKILL bench finds the recorder among a session's processes with
``descendants``.
"""

import os
import signal
import subprocess
import sys
import time

import pytest

from hrc_common.proc_tree import cpu_between, descendants, thread_cpu_ns


def tree_cpu_seconds(root_pid: int) -> float:
    """Return the CPU (s) of the living threads of ``root_pid``'s descendants, not its own."""
    return sum(ns for (pid, _), ns in thread_cpu_ns(root_pid).items() if pid != root_pid) / 1e9

# A child that starts a grandchild which spins on the CPU for 0.4 s, then both sleep.
SPIN = ('import subprocess, sys, time\n'
        'code = "import time\\nend = time.process_time() + 0.4\\n'
        'while time.process_time() < end: pass\\ntime.sleep(30)"\n'
        'grandchild = subprocess.Popen([sys.executable, "-c", code])\n'
        'time.sleep(30)\n')


def scheduler_state(pid: int) -> str:
    """Return the process's state letter in /proc (R running, S sleeping, ...)."""
    with open(f'/proc/{pid}/stat') as stat:
        return stat.read().rsplit(')', 1)[1].split()[0]


def spin_here(seconds: float) -> None:
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


def test_a_busy_grandchild_counts_and_the_caller_does_not():
    child = subprocess.Popen([sys.executable, '-c', SPIN])
    grandchild = None
    try:
        deadline = time.monotonic() + 60       # s: two interpreters start on a busy machine
        while time.monotonic() < deadline and not descendants(child.pid):
            time.sleep(0.02)
        grandchildren = descendants(child.pid)
        assert len(grandchildren) == 1
        grandchild = grandchildren[0]
        start = thread_cpu_ns(child.pid)
        while time.monotonic() < deadline and tree_cpu_seconds(child.pid) < 0.4:
            time.sleep(0.05)
        # the grandchild's 0.4 s of spinning (and its interpreter's start-up)
        assert 0.4 <= tree_cpu_seconds(child.pid) < 5.0
        assert tree_cpu_seconds(grandchild) == 0.0       # it has no descendants of its own
        # With the root: the child's own threads too; the window counts what was spent in it.
        assert cpu_between(start, thread_cpu_ns(child.pid)) > 0.2
        # Now the tree sleeps (the grandchild's spin is over: it sleeps, state S): 0.5 s of
        # this process's own CPU must not show.
        while time.monotonic() < deadline and scheduler_state(grandchild) != 'S':
            time.sleep(0.02)
        assert scheduler_state(grandchild) == 'S'
        before = tree_cpu_seconds(child.pid)
        spin_here(0.5)
        assert tree_cpu_seconds(child.pid) - before < 0.1
        child.kill()
        child.wait()
        # Orphaned by the kill: no longer a descendant of this process, so not counted.
        assert grandchild not in descendants(os.getpid())
    finally:
        child.kill()
        child.wait()
        if grandchild is not None:
            os.kill(grandchild, signal.SIGKILL)


def test_a_window_counts_threads_born_in_it_and_loses_those_that_ended():
    start = {(1, 1): 5_000_000_000, (1, 2): 1_000_000_000, (2, 2): 300_000_000}
    end = {(1, 1): 5_500_000_000, (1, 3): 200_000_000}     # (1, 2) and (2, 2) ended
    assert cpu_between(start, end) == pytest.approx(0.5 + 0.2)


def test_a_process_without_children_has_no_descendants():
    child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(10)'])
    try:
        time.sleep(0.2)
        assert descendants(child.pid) == []
        assert tree_cpu_seconds(child.pid) == 0.0
        assert child.pid in descendants(os.getpid())
    finally:
        child.kill()
        child.wait()
