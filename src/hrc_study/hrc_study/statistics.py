"""The statistics of the study (pure: numpy and scipy, no ROS).

* :func:`mean_interval`: mean with a Student-t confidence interval (the partner tools' tables;
  Table II uses :func:`hrc_bag.report.intervals.bca_interval`; :class:`Interval` is that
  module's).
* :func:`kaplan_meier`: episodes to convergence as right-censored data (a session that hits the
  episode limit without converging is censored at the limit): the Kaplan-Meier median with the
  confidence interval of Brookmeyer and Crowley (1982), read off the pointwise log-log interval
  of the survival function (scipy.stats.ecdf on scipy.stats.CensoredData).
* :func:`restricted_mean`: the restricted mean of a censored time up to the limit (for times all
  censored at the limit it is the plain mean of the observed counts), with a bootstrap interval.
* :func:`mann_whitney_less` / :func:`logrank_faster`: the one-sided unpaired tests, with
  their effect sizes; :func:`wilcoxon_less` / :func:`stratified_logrank_faster`: their paired
  counterparts for sessions that pair (same seed and simulated person in both cases): the
  Wilcoxon signed-rank test (exact for n <= 50 without ties) and the log-rank test stratified
  by pair (Klein and Moeschberger 2003, section 7.5; scipy has no stratified log-rank, so it
  is written here: the per-stratum observed-minus-expected events and hypergeometric
  variances summed over the strata, a normal approximation).
* :func:`holm`: Holm's step-down adjustment of a family of p-values (Holm 1979).
"""

from dataclasses import dataclass
import math
import warnings

from hrc_bag.report.intervals import CONFIDENCE, finite, Interval
import numpy
from scipy import stats


def mean_interval(values, confidence: float = CONFIDENCE) -> Interval:
    """Return the mean of the finite values with its Student-t confidence interval.

    One value: the interval is not estimable (NaN bounds); no value: everything NaN.
    """
    data = finite(values)
    if data.size == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    mean = float(data.mean())
    if data.size < 2:
        return Interval(mean, math.nan, math.nan, 1)
    half = float(stats.t.ppf(0.5 + confidence / 2, data.size - 1)
                 * data.std(ddof=1) / math.sqrt(data.size))
    return Interval(mean, mean - half, mean + half, int(data.size))


@dataclass(frozen=True)
class SurvivalSummary:
    """Kaplan-Meier summary of times to an event (here: episodes to convergence)."""

    median: float          # NaN: the survival function never falls to 0.5 ("not reached")
    low: float             # lower bound of the median's interval (NaN: not estimable)
    high: float            # upper bound (NaN: not reached within the data, i.e. unbounded)
    events: int            # sessions that converged
    count: int             # sessions
    limit: float           # largest censoring time (the episode limit), NaN if none censored

    def describe(self, decimals: int = 0) -> str:
        """Return e.g. '85 [70, 112]', '> 300 (not reached)' or '85 [70, not reached]'."""
        if math.isnan(self.median):
            bound = self.limit if not math.isnan(self.limit) else math.nan
            return f'> {bound:.{decimals}f} (not reached)' if not math.isnan(bound) \
                else 'n/a'
        low = 'n/a' if math.isnan(self.low) else f'{self.low:.{decimals}f}'
        high = 'not reached' if math.isnan(self.high) else f'{self.high:.{decimals}f}'
        return f'{self.median:.{decimals}f} [{low}, {high}]'


def censored(times, events) -> stats.CensoredData:
    """Return scipy CensoredData: ``times[i]`` observed if ``events[i]``, else right-censored."""
    times = numpy.asarray(times, dtype=float)
    events = numpy.asarray(events, dtype=bool)
    return stats.CensoredData(uncensored=times[events], right=times[~events])


def _first_time_at_or_below(times, probabilities, level: float) -> float:
    below = numpy.nonzero(numpy.asarray(probabilities) <= level + 1e-12)[0]
    return float(times[below[0]]) if below.size else math.nan


def kaplan_meier(times, events, confidence: float = CONFIDENCE) -> SurvivalSummary:
    """Return the Kaplan-Meier median of right-censored ``times`` with its interval.

    The median is the first time at which the estimated survival S(t) is <= 0.5. Its interval
    (Brookmeyer-Crowley) holds the times whose pointwise interval of S(t) contains 0.5: from
    the first time the interval's lower limit is <= 0.5 to the first time its upper limit is
    (NaN when that never happens within the data: the interval is open-ended).
    """
    times = numpy.asarray(times, dtype=float)
    events = numpy.asarray(events, dtype=bool)
    if times.size == 0:
        return SurvivalSummary(math.nan, math.nan, math.nan, 0, 0, math.nan)
    limit = float(times[~events].max()) if (~events).any() else math.nan
    if not events.any():
        return SurvivalSummary(math.nan, math.nan, math.nan, 0, int(times.size), limit)
    survival = stats.ecdf(censored(times, events)).sf
    grid = survival.quantiles
    median = _first_time_at_or_below(grid, survival.probabilities, 0.5)
    with warnings.catch_warnings():
        # "undefined at some observations": where S(t) is 0 or 1, handled below
        warnings.simplefilter('ignore', RuntimeWarning)
        band = survival.confidence_interval(confidence, method='log-log')
    # the log-log band is undefined where S(t) is 0 or 1: the point estimate stands in there
    point = survival.probabilities
    low = _first_time_at_or_below(grid, numpy.where(numpy.isnan(band.low.probabilities), point,
                                                    band.low.probabilities), 0.5)
    high = _first_time_at_or_below(grid, numpy.where(numpy.isnan(band.high.probabilities),
                                                     point, band.high.probabilities), 0.5)
    return SurvivalSummary(median, low, high, int(events.sum()), int(times.size), limit)


def restricted_mean(times, limit: float) -> float:
    """Return the mean of min(time, limit): the area under S(t) up to ``limit``.

    With every censored time at the limit (sessions stopped by the episode limit) this is the
    restricted mean survival time of the Kaplan-Meier curve, exactly.
    """
    data = finite(times)
    return float(numpy.minimum(data, limit).mean()) if data.size else math.nan


def bootstrap_interval(values, statistic, resamples: int = 2000, seed: int = 0,
                       confidence: float = CONFIDENCE) -> Interval:
    """Return ``statistic(values)`` with a percentile bootstrap interval (seeded)."""
    data = numpy.asarray(list(values), dtype=float)
    if data.size == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    estimate = float(statistic(data))
    if data.size < 2:
        return Interval(estimate, math.nan, math.nan, int(data.size))
    generator = numpy.random.default_rng(seed)
    draws = generator.integers(0, data.size, size=(resamples, data.size))
    replicates = numpy.array([statistic(data[row]) for row in draws], dtype=float)
    tail = (1 - confidence) / 2 * 100
    low, high = numpy.nanpercentile(replicates, [tail, 100 - tail])
    return Interval(estimate, float(low), float(high), int(data.size))


@dataclass(frozen=True)
class TestResult:
    """A one-sided test of "x is lower/faster/fewer than y" with its effect size."""

    test: str              # the test's name
    p_value: float         # one-sided, in the claimed direction
    p_reverse: float       # one-sided, in the opposite direction
    effect: float          # effect size (sign: positive = in the claimed direction)
    effect_name: str
    detail: str            # the compared estimates, in words
    floor_p: float = 0.0   # the smallest one-sided p the test can give on this design (power)


def rank_biserial(x, y) -> float:
    """Return P(x < y) - P(x > y) over all pairs (Cliff's delta of y over x), in [-1, 1]."""
    x, y = finite(x), finite(y)
    if x.size == 0 or y.size == 0:
        return math.nan
    difference = x[:, None] - y[None, :]
    return float(((difference < 0).sum() - (difference > 0).sum()) / difference.size)


def mann_whitney_less(x, y) -> TestResult:
    """Test "x tends to be lower than y" (one-sided Mann-Whitney U, exact when small).

    Effect: the rank-biserial correlation P(x < y) - P(x > y) (+1: every x below every y).
    """
    x, y = finite(x), finite(y)
    if x.size == 0 or y.size == 0:
        return TestResult('Mann-Whitney U', math.nan, math.nan, math.nan, 'rank-biserial r',
                          'no data')
    less = stats.mannwhitneyu(x, y, alternative='less').pvalue
    greater = stats.mannwhitneyu(x, y, alternative='greater').pvalue
    return TestResult('Mann-Whitney U (one-sided)', float(less), float(greater),
                      rank_biserial(x, y), 'rank-biserial r',
                      f'median {numpy.median(x):.4g} vs {numpy.median(y):.4g}',
                      1 / math.comb(x.size + y.size, x.size))


def logrank_faster(x_times, x_events, y_times, y_events) -> TestResult:
    """Test "x reaches the event (convergence) sooner than y" (one-sided logrank).

    Effect: the difference of the restricted means up to the common limit (y - x episodes;
    positive = x faster), which stays defined when a median is not reached.
    """
    x_data, y_data = censored(x_times, x_events), censored(y_times, y_events)
    if not (numpy.any(x_events) or numpy.any(y_events)):
        return TestResult('logrank (one-sided)', 1.0, 1.0, 0.0,
                          'difference of restricted means (episodes)',
                          'no session converged in either group')
    with warnings.catch_warnings():
        # every event at one time in both groups: no variance, the statistic is undefined
        warnings.simplefilter('ignore', RuntimeWarning)
        faster = stats.logrank(x_data, y_data, alternative='greater').pvalue
        slower = stats.logrank(x_data, y_data, alternative='less').pvalue
    faster, slower = (1.0 if math.isnan(p) else p for p in (faster, slower))
    limit = float(max(numpy.max(x_times), numpy.max(y_times)))
    x_mean, y_mean = restricted_mean(x_times, limit), restricted_mean(y_times, limit)
    x_km, y_km = kaplan_meier(x_times, x_events), kaplan_meier(y_times, y_events)
    return TestResult('logrank (one-sided)', float(faster), float(slower), y_mean - x_mean,
                      'difference of restricted means (episodes)',
                      f'KM median {x_km.describe()} vs {y_km.describe()}')


def signed_rank_biserial(differences) -> float:
    """Return the matched-pairs rank-biserial correlation of ``x - y`` (+1: every x lower).

    (sum of the ranks of |d| where d < 0 - sum where d > 0) / sum of all ranks; zeros dropped.
    """
    data = finite(differences)
    data = data[data != 0]
    if data.size == 0:
        return 0.0
    ranks = stats.rankdata(numpy.abs(data))
    return float((ranks[data < 0].sum() - ranks[data > 0].sum()) / ranks.sum())


def wilcoxon_less(x, y) -> TestResult:
    """Test "x tends to be lower than its twin y" (one-sided Wilcoxon signed-rank, paired).

    ``x[i]`` and ``y[i]`` are one pair (same seed and person in two cases); pairs with a NaN
    are dropped, zero differences too (Wilcoxon's rule). Effect: the matched-pairs
    rank-biserial correlation (+1: x below its twin in every pair).
    """
    x, y = numpy.asarray(list(x), dtype=float), numpy.asarray(list(y), dtype=float)
    keep = numpy.isfinite(x) & numpy.isfinite(y)
    differences = x[keep] - y[keep]
    name = 'Wilcoxon signed-rank (paired, one-sided)'
    if differences.size == 0:
        return TestResult(name, math.nan, math.nan, math.nan, 'matched rank-biserial r',
                          'no pairs')
    detail = (f'{int(keep.sum())} pairs, median difference '
              f'{numpy.median(differences):+.4g}')
    if not numpy.any(differences != 0):
        return TestResult(name, 1.0, 1.0, 0.0, 'matched rank-biserial r', detail)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')   # exact distribution unavailable with ties: normal
        less = stats.wilcoxon(differences, alternative='less').pvalue
        greater = stats.wilcoxon(differences, alternative='greater').pvalue
    # every pair in the claimed direction: the exact one-sided p is 2^-n, its smallest value
    floor = 0.5 ** int(numpy.count_nonzero(differences))
    return TestResult(name, float(less), float(greater), signed_rank_biserial(differences),
                      'matched rank-biserial r', detail, floor)


def stratified_logrank(times, events, in_x, strata) -> tuple:
    """Return (observed - expected events of group x, its variance) summed over strata.

    At every distinct event time of a stratum with n at risk (n_x of group x) and d events
    (d_x of x): expected d * n_x / n, hypergeometric variance
    d * (n_x / n) * (1 - n_x / n) * (n - d) / (n - 1). A positive sum: x has its events
    (convergence) sooner than expected under "no difference".
    """
    times = numpy.asarray(times, dtype=float)
    events = numpy.asarray(events, dtype=bool)
    in_x = numpy.asarray(in_x, dtype=bool)
    strata = numpy.asarray(strata)
    difference, variance = 0.0, 0.0
    for stratum in numpy.unique(strata):
        member = strata == stratum
        stratum_times, stratum_events, stratum_x = times[member], events[member], in_x[member]
        for time in numpy.unique(stratum_times[stratum_events]):
            at_risk = stratum_times >= time
            count, count_x = int(at_risk.sum()), int((at_risk & stratum_x).sum())
            happened = (stratum_times == time) & stratum_events
            deaths, deaths_x = int(happened.sum()), int((happened & stratum_x).sum())
            share = count_x / count
            difference += deaths_x - deaths * share
            if count > 1:
                variance += deaths * share * (1 - share) * (count - deaths) / (count - 1)
    return difference, variance


def stratified_logrank_faster(x_times, x_events, y_times, y_events, x_strata,
                              y_strata) -> TestResult:
    """Test "x reaches the event sooner than y" by the log-rank test stratified by pair.

    ``x_strata[i]`` names the stratum (seed and person) of ``x[i]``, likewise for y. One-sided
    p-values from Z = (O - E) / sqrt(V) against the standard normal. No event in a comparable
    position (V = 0): p = 1 both ways. Effect as :func:`logrank_faster`.
    """
    times = numpy.concatenate([numpy.asarray(x_times, float), numpy.asarray(y_times, float)])
    events = numpy.concatenate([numpy.asarray(x_events, bool), numpy.asarray(y_events, bool)])
    in_x = numpy.concatenate([numpy.ones(len(x_times), bool), numpy.zeros(len(y_times), bool)])
    strata = numpy.asarray([str(key) for key in list(x_strata) + list(y_strata)])
    difference, variance = stratified_logrank(times, events, in_x, strata)
    name = 'log-rank stratified by seed and person (one-sided)'
    limit = float(times.max()) if times.size else math.nan
    effect = restricted_mean(y_times, limit) - restricted_mean(x_times, limit)
    x_km, y_km = kaplan_meier(x_times, x_events), kaplan_meier(y_times, y_events)
    detail = (f'KM median {x_km.describe()} vs {y_km.describe()}; O - E = {difference:+.2f}, '
              f'V = {variance:.2f}')
    if variance <= 0:
        return TestResult(name, 1.0, 1.0, effect, 'difference of restricted means (episodes)',
                          detail + ' (no comparable event)')
    score = difference / math.sqrt(variance)
    return TestResult(name, float(stats.norm.sf(score)), float(stats.norm.cdf(score)), effect,
                      'difference of restricted means (episodes)', detail)


def holm(p_values) -> list:
    """Return Holm's adjusted p-values (same order as given; NaN stays NaN).

    The k-th smallest of m p-values is multiplied by m - k + 1 (k from 1), then made
    non-decreasing along that order and capped at 1.
    """
    values = numpy.asarray(list(p_values), dtype=float)
    adjusted = numpy.full(values.shape, math.nan)
    valid = numpy.nonzero(~numpy.isnan(values))[0]
    order = valid[numpy.argsort(values[valid], kind='stable')]
    running = 0.0
    for rank, index in enumerate(order):
        running = max(running, min(1.0, (order.size - rank) * values[index]))
        adjusted[index] = running
    return [float(value) for value in adjusted]
