"""Progress of a long verb with the time left: a bar on a terminal, plain lines when piped.

The estimate is the mean time per finished unit so far times the units still to do (a
modelling choice: units of one sweep take about as long as each other; with a pool of
workers the mean is of the wall time between finishes, so it already counts the parallelism).
"""

import sys
import time

BAR_WIDTH = 24          # characters of the bar on a terminal


def duration(seconds: float) -> str:
    """Return ``seconds`` for a person: '45 s', '3 min 20 s', '2 h 05 min'."""
    seconds = max(0, int(round(seconds)))
    if seconds < 60:
        return f'{seconds} s'
    if seconds < 3600:
        return f'{seconds // 60} min {seconds % 60:02d} s'
    return f'{seconds // 3600} h {seconds % 3600 // 60:02d} min'


class TimeLeft:
    """Say how far a job of ``total`` units is and how long it still needs.

    ``show(done, message)`` prints ``message`` for good; on a terminal a bar under it is
    redrawn in place (``[#####.....] 3/12 sessions, 1 min 05 s, about 2 min 10 s left``), when
    piped the same numbers end the message's line (a log keeps every line).
    """

    def __init__(self, total: int, unit: str, stream=None, clock=time.monotonic,
                 interactive=None):
        self.total, self.unit = total, unit
        self.stream = stream if stream is not None else sys.stdout
        self.clock = clock
        self.started = clock()
        self.interactive = (self.stream.isatty() if interactive is None else interactive)
        self._bar_shown = False

    def status(self, done: int) -> str:
        """Return '3/12 sessions, 1 min 05 s, about 2 min 10 s left' for ``done`` units."""
        elapsed = self.clock() - self.started
        text = f'{done}/{self.total} {self.unit}, {duration(elapsed)}'
        if 0 < done < self.total:
            text += f', about {duration(elapsed / done * (self.total - done))} left'
        elif done >= self.total:
            text += ', done'
        return text

    def bar(self, done: int) -> str:
        """Return the terminal's bar line for ``done`` units."""
        filled = BAR_WIDTH * min(done, self.total) // max(self.total, 1)
        return f'[{"#" * filled}{"." * (BAR_WIDTH - filled)}] {self.status(done)}'

    def show(self, done: int, message: str) -> None:
        """Print ``message`` with the progress after ``done`` units."""
        if self.interactive:
            self.stream.write(f'\r\033[K{message}\n{self.bar(done)}')
            self._bar_shown = True
        else:
            self.stream.write(f'{message} [{self.status(done)}]\n')
        self.stream.flush()

    def close(self) -> None:
        """End the bar's line on a terminal (the lines after it start on their own)."""
        if self._bar_shown:
            self.stream.write('\n')
            self.stream.flush()
            self._bar_shown = False
