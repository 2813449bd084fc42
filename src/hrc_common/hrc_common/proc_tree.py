"""A process tree's members and CPU time from Linux's /proc (for benchmarks), pure.

``descendants`` follows /proc's parent links; ``thread_cpu_ns`` reads every living thread's
schedstat (nanoseconds: /proc/<pid>/stat counts 10 ms ticks, too coarse for a window of a
second); ``cpu_between`` is the CPU spent between two such readings.
"""

import os


def descendants(root_pid: int) -> list:
    """Return the pids of ``root_pid``'s living descendants (from /proc's parent links)."""
    children = {}
    for entry in os.scandir('/proc'):
        if not entry.name.isdigit():
            continue
        try:
            with open(f'/proc/{entry.name}/stat') as stat:
                # "pid (comm) state ppid ...": comm may hold spaces and parentheses
                parent = int(stat.read().rsplit(')', 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue   # the process ended meanwhile
        children.setdefault(parent, []).append(int(entry.name))
    found, todo = [], [root_pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def thread_cpu_ns(root_pid: int) -> dict:
    """Return {(pid, tid): CPU ns} of the living threads of ``root_pid`` and its descendants."""
    cpu = {}
    for pid in [root_pid] + descendants(root_pid):
        try:
            tasks = os.listdir(f'/proc/{pid}/task')
        except OSError:
            continue
        for task in tasks:
            try:
                with open(f'/proc/{pid}/task/{task}/schedstat') as schedstat:
                    cpu[(pid, int(task))] = int(schedstat.read().split()[0])
            except (OSError, IndexError, ValueError):
                continue
    return cpu


def cpu_between(start: dict, end: dict) -> float:
    """Return the CPU (s) the threads alive at ``end`` spent since ``start`` (thread_cpu_ns).

    A thread born after ``start`` counts whole; one that ended before ``end`` (an update's
    learner thread) is not counted at all: its time is lost with it.
    """
    return sum(ns - start.get(key, 0) for key, ns in end.items()) / 1e9
