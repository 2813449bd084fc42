"""Fig. 5's data: training and judging returns per episode position over the seeds (no ROS)."""

from dataclasses import dataclass
import warnings

import numpy

from hrc_bag.report.records import final_block_start, record_kind


def returns_of_kind(session, kind: str) -> list:
    """Return [(episode position, return)] of the ``kind`` episodes before the final block.

    The position counts every episode of training from 1 (training and judging episodes share
    one axis). Sessions whose summaries do not say their kind (bags before
    ``EpisodeSummary.kind``): every non-evaluation episode is 'training', none 'judging'.
    """
    points = []
    for index, episode in enumerate(session.episodes[:final_block_start(session)]):
        if record_kind(episode) == kind:
            points.append((index + 1, episode.episode_return))
    return points


def training_returns(session) -> list:
    """Return the returns of the training episodes before the final block (judging excluded)."""
    return [value for _, value in returns_of_kind(session, 'training')]


@dataclass
class ReturnBand:
    """Return per episode position across all sessions of a case (Fig. 5)."""

    episodes: list          # episode positions 1..longest session
    median: list            # median over the sessions (NaN before any session has a value)
    low: list               # 25th percentile over the sessions
    high: list              # 75th percentile
    running: list           # sessions still training at that position
    stops: list             # each session's last position (converged or stopped at the limit)


def return_band(sessions, kind: str = 'training') -> ReturnBand:
    """Return the median and inter-quartile range of ``kind`` returns per episode position.

    Every session counts at every position: after its last episode (it converged, or stopped at
    the episode limit) its last return is carried forward, and between two episodes of the
    kind (judging) the earlier value holds. No survivor averaging: the band is over all
    sessions that have had an episode of the kind by then; the band is the inter-quartile range
    (half of the sessions lie inside it), not an interval of the mean. One session: its curve.
    """
    series = [returns_of_kind(session, kind) for session in sessions]
    lengths = [final_block_start(session) for session in sessions]
    longest = max(lengths, default=0)
    values = numpy.full((len(series), longest), numpy.nan)
    for row, points in enumerate(series):
        for position, value in points:
            values[row, position - 1:] = value
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)   # columns without a value yet
        low, median, high = (numpy.nanpercentile(values, quantile, axis=0).tolist()
                             if longest else [] for quantile in (25, 50, 75))
    running = [sum(1 for length in lengths if length >= position)
               for position in range(1, longest + 1)]
    return ReturnBand(list(range(1, longest + 1)), median, low, high, running, lengths)


def first_human_episode(session):
    """Return the position of the first training episode with the human (None: never)."""
    for index, episode in enumerate(session.episodes[:final_block_start(session)]):
        if record_kind(episode) == 'training' and episode.human_involved:
            return index + 1
    return None
