"""The sim's log lines (pure): the one-line episode summary and throttled warnings."""

from collections import Counter
import typing

from hrc_sim_node.commands import ACTORS


class WarningThrottle:
    """At most one warning per ``period`` (s) for each kind; says how many were suppressed."""

    def __init__(self, period: float):
        self.period = period
        self._last = {}                  # kind -> (time of the last warning, suppressed since)

    def admit(self, kind: str, now: float) -> typing.Optional[str]:
        """Return None to suppress, else a suffix ('' or ' (N more like this in ...)')."""
        last, suppressed = self._last.get(kind, (None, 0))
        if last is not None and now - last < self.period:
            self._last[kind] = (last, suppressed + 1)
            return None
        self._last[kind] = (now, 0)
        if suppressed:
            return f' ({suppressed} more like this in the last {now - last:.1f} s)'
        return ''


def summary_line(episode: int, state, counters: Counter, mode: str, end: str = '') -> str:
    """Return the one-line summary of an episode (where each body ended, events)."""
    end = end or ('truncated' if state.truncated else 'terminated' if state.terminated
                  else 'stopped')
    parts = [f'episode {episode} {end} after {state.step} steps ({state.time:.1f} s sim):',
             f'slider S_x={state.slider_position:+.4f} m,',
             f'pendulum P_z={state.pendulum_angle:+.4f} rad,',
             f'ball B_y={state.ball_position:+.4f} m;',
             'missing commands ' + ', '.join(
                 f'{actor} {counters[actor + "_missing"]}' for actor in ACTORS) + ';']
    events = [f'{name} {count}' for name, count in sorted(counters.items())
              if count and not name.endswith('_missing')]
    parts.append(', '.join(events) if events else 'no refused/clamped/off-axis/stale commands')
    parts.append(f'({mode})')
    return ' '.join(parts)
