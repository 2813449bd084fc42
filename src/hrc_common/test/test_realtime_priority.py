"""The opt-in realtime scheduling of node processes (HRC_REALTIME_PRIORITY)."""

import errno
import os
import subprocess
import sys
import textwrap

import pytest

from hrc_common.contract import REALTIME_SWITCH_INTERVAL_S
from hrc_common.nodes import run_nodes
from hrc_common.realtime import (apply_realtime_priority, REALTIME_PRIORITY_VARIABLE,
                                 realtime_priority_of)


def test_off_by_default_and_values_checked():
    assert realtime_priority_of({}) == (0, '')
    assert realtime_priority_of({REALTIME_PRIORITY_VARIABLE: ''}) == (0, '')
    assert realtime_priority_of({REALTIME_PRIORITY_VARIABLE: '0'}) == (0, '')
    assert realtime_priority_of({REALTIME_PRIORITY_VARIABLE: ' 50 '}) == (50, '')
    for bad in ('100', '-1', 'high', '1.5'):
        priority, problem = realtime_priority_of({REALTIME_PRIORITY_VARIABLE: bad})
        assert priority == 0
        assert f'{REALTIME_PRIORITY_VARIABLE}={bad!r}' in problem and '1..99' in problem


def test_off_changes_nothing():
    calls = []
    assert apply_realtime_priority(0, [1, 2], lambda *args: calls.append(args)) == ''
    assert calls == []


def test_every_thread_switched_with_reset_on_fork(monkeypatch):
    monkeypatch.setattr(sys, 'setswitchinterval', lambda value: calls.append(('switch', value)))
    calls = []
    line = apply_realtime_priority(40, [11, 12, 13],
                                   lambda tid, policy, param: calls.append(
                                       (tid, policy, param.sched_priority)))
    policy = os.SCHED_FIFO | os.SCHED_RESET_ON_FORK
    assert calls == [(11, policy, 40), (12, policy, 40), (13, policy, 40),
                     ('switch', REALTIME_SWITCH_INTERVAL_S)]
    assert '3 thread(s) on SCHED_FIFO priority 40' in line


def test_not_permitted_is_a_line_not_a_crash_and_undoes_what_it_did(monkeypatch):
    monkeypatch.setattr(sys, 'setswitchinterval', lambda value: switched.append(value))
    switched, calls = [], []

    def scheduler(tid, policy, param):
        calls.append((tid, policy))
        if tid == 12 and policy != os.SCHED_OTHER:
            raise PermissionError(errno.EPERM, 'Operation not permitted')

    line = apply_realtime_priority(40, [11, 12, 13], scheduler)
    assert 'SCHED_FIFO not permitted (Operation not permitted' in line
    assert 'running on the ordinary scheduler' in line
    # thread 11 was switched before 12 failed: put back; 13 never touched; interval unchanged
    assert calls[-1] == (11, os.SCHED_OTHER) and all(tid != 13 for tid, _ in calls)
    assert switched == []


def test_a_thread_that_ended_meanwhile_is_skipped(monkeypatch):
    monkeypatch.setattr(sys, 'setswitchinterval', lambda value: None)

    def scheduler(tid, policy, param):
        if tid == 12:
            raise ProcessLookupError(errno.ESRCH, 'No such process')

    assert '2 thread(s) on SCHED_FIFO' in apply_realtime_priority(5, [11, 12, 13], scheduler)


def test_bad_value_refused_before_start_with_exit_code_2(monkeypatch, capsys):
    monkeypatch.setenv(REALTIME_PRIORITY_VARIABLE, 'max')
    made = []
    code = run_nodes([lambda: made.append(1)], 'probe_node', 'probe', args=['probe_node'])
    assert code == 2 and made == []
    assert f"{REALTIME_PRIORITY_VARIABLE}='max' is not a SCHED_FIFO priority" in \
        capsys.readouterr().err


# In a child process (its scheduling must not leak into the test runner): the threads alive
# when the priority is applied run on SCHED_FIFO, a thread started afterwards does not.
CHILD = textwrap.dedent("""
    import os, sys, threading
    from hrc_common.realtime import apply_realtime_priority
    done = threading.Event()
    before = threading.Thread(target=done.wait); before.start()
    line = apply_realtime_priority(7)
    policies = {}
    after = threading.Thread(target=lambda: policies.update(
        after=os.sched_getscheduler(0))); after.start(); after.join()
    policies['main'] = os.sched_getscheduler(0)
    policies['before'] = os.sched_getscheduler(before.native_id)
    done.set(); before.join()
    print(line); print(policies['main'], policies['before'], policies['after'],
                       sys.getswitchinterval())
""")


def test_in_a_real_process_threads_now_fifo_threads_later_ordinary():
    result = subprocess.run([sys.executable, '-c', CHILD], capture_output=True, text=True,
                            timeout=30)
    assert result.returncode == 0, result.stderr
    line, figures = result.stdout.strip().splitlines()
    main, before, after, interval = figures.split()
    if 'not permitted' in line:   # no root / CAP_SYS_NICE here: nothing may have changed
        assert (int(main), int(before), int(after)) == (os.SCHED_OTHER,) * 3
        assert float(interval) == pytest.approx(0.005)
        return
    assert 'SCHED_FIFO priority 7' in line
    assert int(main) & ~os.SCHED_RESET_ON_FORK == os.SCHED_FIFO
    assert int(before) & ~os.SCHED_RESET_ON_FORK == os.SCHED_FIFO
    assert int(after) == os.SCHED_OTHER
    assert float(interval) == pytest.approx(REALTIME_SWITCH_INTERVAL_S)
