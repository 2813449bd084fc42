"""The realtime scheduling option of every node process (``HRC_REALTIME_PRIORITY``).

Off by default. On, it puts a node process's threads on SCHED_FIFO, so the timing-critical
nodes of a realtime session preempt every ordinarily scheduled process the moment a timer or a
message wakes them (see :func:`apply_realtime_priority`).
"""

import os
import sys

from hrc_common.contract import REALTIME_SWITCH_INTERVAL_S

# HRC_REALTIME_PRIORITY: unset, empty or 0 = off (the default: the kernel's ordinary scheduler, as
# before); 1..99 = run the node process's threads on SCHED_FIFO at that priority (a realtime
# lab's setting for the timing-critical nodes; needs root or CAP_SYS_NICE, else a log line says
# it was not permitted and the node runs as before).
REALTIME_PRIORITY_VARIABLE = 'HRC_REALTIME_PRIORITY'
REALTIME_PRIORITY_RANGE = (1, 99)   # SCHED_FIFO's priorities on Linux
# The interpreter's thread switch interval while realtime scheduling is on:
# hrc_common.contract.REALTIME_SWITCH_INTERVAL_S (imported above; the agent's learner uses it too).


def realtime_priority_of(environ=None) -> tuple:
    """Return (priority, problem) of ``HRC_REALTIME_PRIORITY``: (0, '') when off or unset."""
    text = (os.environ if environ is None else environ).get(REALTIME_PRIORITY_VARIABLE, '')
    text = text.strip()
    if text in ('', '0'):
        return 0, ''
    low, high = REALTIME_PRIORITY_RANGE
    try:
        priority = int(text)
    except ValueError:
        priority = None
    if priority is None or not low <= priority <= high:
        return 0, (f'{REALTIME_PRIORITY_VARIABLE}={text!r} is not a SCHED_FIFO priority '
                   f'{low}..{high} (or 0 / unset: off)')
    return priority, ''


def process_thread_ids() -> list:
    """Return the kernel ids of this process's threads (Linux: /proc/self/task)."""
    return sorted(int(name) for name in os.listdir('/proc/self/task'))


def apply_realtime_priority(priority: int, thread_ids=None, scheduler=None) -> str:
    """Put this process's threads on SCHED_FIFO at ``priority``; return a line for the log.

    Every thread alive now is switched (the caller's, and the middleware's receive and writer
    threads, which deliver the messages the node waits on), each with SCHED_RESET_ON_FORK:
    threads started later (the agent's learner thread, a PPO update's worker threads) run on
    the ordinary scheduler, so a long computation cannot hold a core at realtime priority. Not
    permitted (no root or CAP_SYS_NICE), or not Linux: the line says so; nothing is changed and
    nothing is raised. ``scheduler`` (os.sched_setscheduler by default) is for tests.
    """
    if priority <= 0:
        return ''
    set_scheduler = scheduler or getattr(os, 'sched_setscheduler', None)
    if set_scheduler is None or not hasattr(os, 'SCHED_FIFO'):
        return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: realtime scheduling is not available '
                f'on this system; running on the ordinary scheduler')
    policy = os.SCHED_FIFO | getattr(os, 'SCHED_RESET_ON_FORK', 0)
    thread_ids = process_thread_ids() if thread_ids is None else thread_ids
    switched = []
    for thread_id in thread_ids:
        try:
            set_scheduler(thread_id, policy, os.sched_param(priority))
        except ProcessLookupError:
            continue   # the thread ended meanwhile
        except OSError as error:
            if switched:   # undo: all or nothing, so the log line is the whole truth
                for done in switched:
                    try:
                        set_scheduler(done, os.SCHED_OTHER, os.sched_param(0))
                    except OSError:
                        pass
            return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: SCHED_FIFO not permitted '
                    f'({error.strerror or error}; it needs root or CAP_SYS_NICE, e.g. '
                    f'`sudo setcap cap_sys_nice+ep` on the python binary or an rtprio limit '
                    f'in /etc/security/limits.conf); running on the ordinary scheduler')
        switched.append(thread_id)
    sys.setswitchinterval(REALTIME_SWITCH_INTERVAL_S)
    return (f'{REALTIME_PRIORITY_VARIABLE}={priority}: {len(switched)} thread(s) on SCHED_FIFO '
            f'priority {priority} (threads started later: ordinary scheduler); Python switch '
            f'interval {REALTIME_SWITCH_INTERVAL_S * 1000:g} ms')
