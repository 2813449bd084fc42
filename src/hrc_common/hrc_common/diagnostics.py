"""Each node's health on ``/diagnostics`` (diagnostic_msgs/DiagnosticArray), the ROS convention.

A lab's tools (``rqt_runtime_monitor``, ``diagnostic_aggregator``, Foxglove's diagnostics
panel) read ``/diagnostics``; every hrc node that has a health to tell publishes its statuses
there once a second (``DIAGNOSTICS_PERIOD_S``), named ``<node>: <what>``, with the levels and
thresholds below (pure functions, tested on their own):

* human node, ``human: input``: its input status as on ``/hrc/human/input`` (OK connected, WARN
  on the simulated stand-in or a lost input the session does not pause for, ERROR lost);
* sim, ``sim: timing``: in realtime the period jitter of the last ``JITTER_WINDOW`` states
  (WARN above ``JITTER_WARN_SHARE`` of the control period, ERROR above
  ``JITTER_ERROR_SHARE``), and in both modes the commands missing and stale in the running
  episode (WARN from one, ERROR from ``MISSING_ERROR_SHARE`` of its steps);
* recorder, ``recorder: writing``: files closed, bytes, messages waiting, free disk space
  (WARN below ``DISK_WARN_BYTES``, ERROR below ``DISK_ERROR_BYTES`` or when recording stopped);
* agent, ``agent: learner``: whether it is updating and the last update's duration and losses
  (WARN when an update took longer than the break between episodes: the person waits for the
  robot; ERROR when a loss is not a finite number: the learner diverged).
"""

import collections
import math

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

DIAGNOSTICS_TOPIC = '/diagnostics'
DIAGNOSTICS_PERIOD_S = 1.0
OK, WARN, ERROR = 0, 1, 2                       # DiagnosticStatus.OK, WARN, ERROR
JITTER_WINDOW = 50                              # states
JITTER_WARN_SHARE, JITTER_ERROR_SHARE = 0.1, 0.5    # of the control period
MISSING_ERROR_SHARE = 0.05                      # of the running episode's steps
DISK_WARN_BYTES, DISK_ERROR_BYTES = 1 << 30, 100 << 20


def status(name: str, hardware_id: str, level: int, message: str,
           values: dict) -> DiagnosticStatus:
    """Return a DiagnosticStatus (values as text, the convention's key-value pairs)."""
    return DiagnosticStatus(level=bytes([level]), name=name, message=message,
                            hardware_id=hardware_id,
                            values=[KeyValue(key=key, value=str(value))
                                    for key, value in values.items()])


def timing_level(jitter_s, period_s: float, missing: int, stale: int, steps: int) -> tuple:
    """Return (level, message) of the sim's timing (``jitter_s`` None: lockstep, no clock)."""
    problems, level = [], OK
    if jitter_s is not None and jitter_s > JITTER_WARN_SHARE * period_s:
        level = ERROR if jitter_s > JITTER_ERROR_SHARE * period_s else WARN
        problems.append(f'period jitter {1000 * jitter_s:.0f} ms')
    if missing or stale:
        share = (missing + stale) / max(steps, 1)
        level = max(level, ERROR if share >= MISSING_ERROR_SHARE else WARN)
        problems.append(f'{missing} commands missing and {stale} stale in this episode')
    return level, '; '.join(problems) or 'on time, every command in time'


def disk_level(free_bytes: int, failed: str) -> tuple:
    """Return (level, message) of the recorder's writing."""
    if failed:
        return ERROR, f'recording stopped: {failed}'
    if free_bytes < DISK_ERROR_BYTES:
        return ERROR, f'{free_bytes >> 20} MiB free on the bags disk'
    if free_bytes < DISK_WARN_BYTES:
        return WARN, f'{free_bytes >> 20} MiB free on the bags disk'
    return OK, 'writing'


def learner_level(last_update, break_s: float) -> tuple:
    """Return (level, message) of the agent's learner from its last update's statistics.

    ``last_update`` holds ``seconds``, ``policy_loss`` and ``value_loss`` (None: no update
    yet); ``break_s`` is the break between episodes (s).
    """
    if last_update is None:
        return OK, 'no update yet (collecting samples)'
    losses = {name: last_update.get(name, 0.0) for name in ('policy_loss', 'value_loss')}
    diverged = [name for name, value in losses.items() if not math.isfinite(value)]
    if diverged:
        return ERROR, (f'the last update\'s {" and ".join(diverged)} is not a finite number: '
                       f'the learner diverged')
    seconds = last_update.get('seconds', 0.0)
    if break_s > 0 and seconds > break_s:
        return WARN, (f'the last update took {seconds:.1f} s, longer than the {break_s:.1f} s '
                      f'break between episodes (the person waits for the robot)')
    return OK, f'last update took {seconds:.2f} s'


class PeriodJitter:
    """The largest deviation (s) from the control period between the last states (wall time)."""

    def __init__(self, window: int = JITTER_WINDOW):
        self.intervals = collections.deque(maxlen=window)
        self.last = None

    def add(self, now: float, period: float, new_episode: bool) -> None:
        """Take a state published at monotonic ``now`` (a new episode: no interval before it)."""
        if self.last is not None and not new_episode:
            self.intervals.append(abs(now - self.last - period))
        self.last = now

    def jitter(self):
        """Return the largest deviation so far (s), 0 before two states."""
        return max(self.intervals, default=0.0)


class TimingHealth:
    """The sim's ``sim: timing``: period jitter and the running episode's late commands."""

    def __init__(self, period_s: float):
        self.period_s = period_s
        self.jitter = PeriodJitter()
        self.steps = self.missing = self.stale = 0

    def on_state(self, step: int, missing: dict, now: float) -> None:
        """Count a published period's state (step 0 starts an episode), at monotonic ``now``."""
        if step == 0:
            self.steps = self.missing = self.stale = 0
        self.steps += 1
        self.missing += sum(1 for value in missing.values() if value)
        self.jitter.add(now, self.period_s, step == 0)

    def on_stale(self) -> None:
        """Count a command that answered no awaited state."""
        self.stale += 1

    def status(self, realtime: bool, mode: str, episode: int) -> DiagnosticStatus:
        """Return the status (no jitter in lockstep: no clock to keep)."""
        jitter = self.jitter.jitter() if realtime else None
        level, words = timing_level(jitter, self.period_s, self.missing, self.stale,
                                    self.steps)
        return status('sim: timing', 'hrc sim', level, words, {
            'mode': mode, 'episode': episode,
            'period_jitter_ms': 'n/a (lockstep)' if jitter is None else f'{1000 * jitter:.1f}',
            'steps': self.steps, 'missing_commands': self.missing,
            'stale_commands': self.stale})


class DiagnosticsReporter:
    """Publishes ``collect()``'s statuses on /diagnostics every ``period`` s."""

    def __init__(self, node, collect, period: float = DIAGNOSTICS_PERIOD_S):
        self.node, self.collect = node, collect
        self.publisher = node.create_publisher(DiagnosticArray, DIAGNOSTICS_TOPIC, 10)
        node.create_timer(period, self.publish)

    def publish(self) -> None:
        """Publish the node's statuses now."""
        message = DiagnosticArray(status=list(self.collect()))
        message.header.stamp = self.node.get_clock().now().to_msg()
        self.publisher.publish(message)
