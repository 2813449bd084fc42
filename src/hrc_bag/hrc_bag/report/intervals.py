"""Table II's intervals: a mean with its 95% BCa bootstrap interval (numpy, scipy; no ROS).

:func:`bca_interval`: a statistic (the mean) with a bias-corrected and accelerated bootstrap
interval (scipy.stats.bootstrap, method 'BCa', seeded), clipped to the quantity's physical
range (effort, errors and counts >= 0): with n = 10 on capped or skewed data the Student-t
interval leaves the range and the percentile bootstrap under-covers (Efron 1987).
:func:`column_interval` applies it to a column of Table II within that column's range;
:func:`cell` writes 'mean [low, high]'. One session: the value alone.
"""

from dataclasses import dataclass
import math
import warnings

import numpy

CONFIDENCE = 0.95
RESAMPLES = 9999                    # bootstrap resamples of a Table II cell
# Physical range of every column (floor, ceiling): an interval never leaves it.
RANGES = {'percentage': (0.0, 100.0)}
DEFAULT_RANGE = (0.0, math.inf)     # counts, errors (absolute values) and variances are >= 0
INTERVAL_NOTE = ('Intervals: 95% BCa bootstrap over the seeds of a case (scipy.stats.bootstrap, '
                 "seeded), kept within each quantity's physical range (>= 0; percentages <= "
                 '100).')


@dataclass(frozen=True)
class Interval:
    """An estimate with a two-sided confidence interval (NaN bounds: not estimable)."""

    estimate: float
    low: float
    high: float
    count: int

    def overlaps(self, other: 'Interval') -> bool:
        """Return whether the two intervals share a point (NaN bounds count as unbounded)."""
        low = -math.inf if math.isnan(self.low) else self.low
        high = math.inf if math.isnan(self.high) else self.high
        other_low = -math.inf if math.isnan(other.low) else other.low
        other_high = math.inf if math.isnan(other.high) else other.high
        return low <= other_high and other_low <= high

    def clipped(self, floor: float = -math.inf, ceiling: float = math.inf) -> 'Interval':
        """Return the interval with both bounds kept in [floor, ceiling] (NaN stays NaN)."""
        def clip(value):
            return value if math.isnan(value) else min(max(value, floor), ceiling)
        return Interval(self.estimate, clip(self.low), clip(self.high), self.count)


def finite(values) -> numpy.ndarray:
    """Return the finite values as a float array."""
    array = numpy.asarray(list(values), dtype=float)
    return array[numpy.isfinite(array)]


def bca_interval(values, statistic=numpy.mean, floor: float = -math.inf,
                 ceiling: float = math.inf, resamples: int = 9999, seed: int = 0,
                 confidence: float = CONFIDENCE) -> Interval:
    """Return ``statistic`` of the finite values with its BCa bootstrap interval (seeded).

    The bounds are clipped to [floor, ceiling], the quantity's physical range (an effort or a
    count cannot be negative). Every value equal: the interval is that value (no spread to
    resample); one value: not estimable (NaN bounds); none: everything NaN.
    """
    data = finite(values)
    if data.size == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    estimate = float(statistic(data))
    if data.size < 2:
        return Interval(estimate, math.nan, math.nan, 1)
    if numpy.all(data == data[0]):
        return Interval(estimate, estimate, estimate, int(data.size)).clipped(floor, ceiling)
    from scipy import stats  # lazy: scipy (about 1 s): only when an interval is computed
    with warnings.catch_warnings():
        # BCa's acceleration is undefined for some degenerate resamples: scipy warns, NaN
        warnings.simplefilter('ignore')
        result = stats.bootstrap((data,), statistic, n_resamples=resamples,
                                 confidence_level=confidence, method='BCa',
                                 rng=numpy.random.default_rng(seed))
    low, high = (float(bound) for bound in result.confidence_interval)
    return Interval(estimate, low, high, int(data.size)).clipped(floor, ceiling)


def column_interval(values, key: str, seed: int = 0, resamples: int = RESAMPLES) -> Interval:
    """Return the mean of one Table II column with its 95% BCa interval in the column's range."""
    floor, ceiling = RANGES.get(key, DEFAULT_RANGE)
    return bca_interval(values, floor=floor, ceiling=ceiling, seed=seed, resamples=resamples)


def cell(interval: Interval, decimals: int) -> str:
    """Return 'mean [low, high]' (or the mean alone, or n/a)."""
    if interval.count == 0 or math.isnan(interval.estimate):
        return 'n/a'
    if interval.count < 2:
        return f'{interval.estimate:.{decimals}f}'
    return (f'{interval.estimate:.{decimals}f} [{interval.low:.{decimals}f}, '
            f'{interval.high:.{decimals}f}]')
