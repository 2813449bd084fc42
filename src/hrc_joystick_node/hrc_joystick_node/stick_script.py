"""A scripted stick: a joystick trajectory read from a CSV file, in simulation time; pure.

The human input ``script`` drives the person's command from this trajectory instead of a device:
a joystick of the person's kind (the stick's deadzone, inversion and enable button apply as to
a real stick) without a person and without wall time, so a session with it is deterministic and
the ROS graph and the in-process engine give the same bytes. It serves tests (the graph-vs-engine
equivalence of the joystick path), demonstrations without hardware, and replaying a stick trace.

The file (plain CSV, parsed as numbers only; nothing in it is run)::

    time,axis,enable
    0.0,0.0,1
    0.5,0.6,1
    1.2,-0.4,0

``time``: seconds from the start of each episode (the trajectory restarts with every episode),
strictly increasing, the first 0; ``axis``: the raw stick position in [-1, 1] (the Joy
convention); ``enable`` (optional column): the enable button, 0 or 1. Each row holds until the
next one (a stick is sampled; a value between rows is not interpolated); the last row holds to
the episode's end.
"""

import bisect
import csv
import math
import typing


class StickScriptError(ValueError):
    """A stick script file that cannot be used (the message lists every reason)."""


class StickSample(typing.NamedTuple):
    """The stick at one moment: its raw axis and whether the enable button is held."""

    axis: float
    enable: typing.Optional[bool]   # None: the file has no enable column


class StickScript:
    """A stick trajectory: :meth:`at` gives the stick at a time from the episode's start."""

    def __init__(self, times: typing.Sequence[float], samples: typing.Sequence[StickSample],
                 name: str = 'script'):
        self.times = list(times)
        self.samples = list(samples)
        self.name = name

    @classmethod
    def load(cls, path: str) -> 'StickScript':
        """Read and check a script file; StickScriptError with every reason if unusable."""
        try:
            with open(path, newline='') as stream:
                rows = list(csv.reader(stream))
        except OSError as error:
            raise StickScriptError(f'stick script {path}: cannot read it ({error})')
        except (csv.Error, UnicodeDecodeError) as error:
            raise StickScriptError(f'stick script {path}: not a CSV text file ({error})')
        return cls.parse(rows, path)

    @classmethod
    def parse(cls, rows: typing.List[typing.List[str]], name: str) -> 'StickScript':
        """Build a script from CSV rows (a header then numbers); every reason at once."""
        rows = [row for row in rows if any(cell.strip() for cell in row)]
        if not rows:
            raise StickScriptError(f'stick script {name}: empty (expected a header '
                                   f'"time,axis[,enable]" and at least one row)')
        header = [cell.strip().lower() for cell in rows[0]]
        if header not in (['time', 'axis'], ['time', 'axis', 'enable']):
            raise StickScriptError(f'stick script {name}: the header must be "time,axis" or '
                                   f'"time,axis,enable", got {",".join(rows[0])!r}')
        has_enable = len(header) == 3
        reasons, times, samples = [], [], []
        for line, row in enumerate(rows[1:], start=2):
            if len(row) != len(header):
                reasons.append(f'line {line}: {len(row)} values, expected {len(header)}')
                continue
            try:
                values = [float(cell) for cell in row]
            except ValueError:
                reasons.append(f'line {line}: not numbers: {",".join(row)!r}')
                continue
            time, axis = values[0], values[1]
            if not all(math.isfinite(value) for value in values):
                reasons.append(f'line {line}: values must be finite numbers')
                continue
            if times and time <= times[-1]:
                reasons.append(f'line {line}: time {time:g} s is not after {times[-1]:g} s')
            if not -1.0 <= axis <= 1.0:
                reasons.append(f'line {line}: axis {axis:g} is outside [-1, 1]')
            enable = None
            if has_enable:
                if values[2] not in (0.0, 1.0):
                    reasons.append(f'line {line}: enable must be 0 or 1, got {row[2]!r}')
                enable = values[2] == 1.0
            times.append(time)
            samples.append(StickSample(axis, enable))
        if not samples and not reasons:
            reasons.append('no rows after the header')
        if times and times[0] != 0.0:
            reasons.append(f'the first time must be 0 (the episode start), got {times[0]:g} s')
        if reasons:
            raise StickScriptError(f'stick script {name}: ' + '; '.join(reasons))
        return cls(times, samples, name)

    def at(self, time: float) -> StickSample:
        """Return the stick at ``time`` s from the episode's start (the row then in force)."""
        index = bisect.bisect_right(self.times, time + 1e-9) - 1   # a row applies from its time
        return self.samples[max(index, 0)]
