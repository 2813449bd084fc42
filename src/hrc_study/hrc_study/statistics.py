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
  their effect sizes; :func:`wilcoxon_less` / :func:`paired_sooner`: their paired
  counterparts for sessions that pair (same seed and simulated person in both cases): the
  Wilcoxon signed-rank test (exact for n <= 50 without ties) and, for censored counts, the
  exact signed-rank test by sign flips on the pairs whose order is known, with the exact sign
  test (:func:`sign_test`) beside it.
* :func:`pairs_needed`: the pairs a paired test would need for 80% power at the effect seen
  (what "inconclusive" means on these sessions).
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
    dz: float = math.nan   # paired designs: mean / sd of the differences (Cohen's dz)
    pairs_needed: float = math.nan   # pairs for 80% power at that dz (:func:`pairs_needed`)


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


def paired_differences(x_times, x_events, y_times, y_events):
    """Return the differences x - y of paired times to an event whose order is known.

    Both converged: t_x - t_y. One censored at c (it had not converged after c) and the other
    converged at t <= c: the difference is at least c - t in size, entered as that bound. The
    order is unknown when both are censored or when the censored one stopped first: 0 (a tie,
    which the tests drop).
    """
    differences = []
    for tx, ex, ty, ey in zip(x_times, x_events, y_times, y_events):
        tx, ty = float(tx), float(ty)
        if ex and ey:
            differences.append(tx - ty)
        elif ex and tx <= ty:          # y censored at ty, x converged first
            differences.append(tx - ty)
        elif ey and ty <= tx:          # x censored at tx, y converged first
            differences.append(tx - ty)
        else:
            differences.append(0.0)
    return numpy.asarray(differences, dtype=float)


def sign_test(wins: int, losses: int) -> tuple:
    """Return the exact one-sided sign-test p-values (claimed way, other way).

    ``wins``: pairs in the claimed direction, ``losses``: the other way (ties left out);
    X ~ Binomial(wins + losses, 1/2): P(X >= wins) and P(X <= wins). E.g. 8-2: 0.055 (two-sided
    0.109).
    """
    count = wins + losses
    if count == 0:
        return 1.0, 1.0
    return (float(stats.binomtest(wins, count, 0.5, 'greater').pvalue),
            float(stats.binomtest(wins, count, 0.5, 'less').pvalue))


def signed_rank_permutation(differences) -> tuple:
    """Return the exact one-sided p-values (d tends < 0, d tends > 0) of the signed-rank sum.

    The Wilcoxon signed-rank statistic's null distribution computed by flipping every sign
    (scipy.stats.permutation_test, all 2^n flips up to n = 20, else 20,000 seeded ones): exact
    with tied sizes, where scipy's wilcoxon falls back to a normal approximation. Zeros dropped.
    """
    data = finite(differences)
    data = data[data != 0]
    if data.size == 0:
        return 1.0, 1.0
    if data.size == 1:
        # Two equally likely flips, -1 and +1 (scipy's permutation_test needs two samples).
        return (0.5, 1.0) if data[0] < 0 else (1.0, 0.5)
    ranks = stats.rankdata(numpy.abs(data))

    def statistic(signs, axis=-1):
        return numpy.sum(numpy.sign(signs) * ranks, axis=axis)

    resamples = numpy.inf if data.size <= 20 else 20000
    values = []
    for alternative in ('less', 'greater'):
        result = stats.permutation_test((data,), statistic, permutation_type='samples',
                                        n_resamples=resamples, alternative=alternative,
                                        vectorized=True, random_state=0)
        values.append(float(result.pvalue))
    return tuple(values)


def paired_sooner(x_times, x_events, y_times, y_events) -> TestResult:
    """Test "x converges after fewer episodes than its twin y", exactly, pair by pair.

    The pairs (same seed and person) are compared directly (:func:`paired_differences`): the
    exact signed-rank test by sign flips (:func:`signed_rank_permutation`), so the size of each
    difference counts through its rank; the detail gives the sign counts with their exact sign
    test. This replaces a log-rank test stratified by pair: on strata of two sessions it is a
    sign test with a normal approximation (8-2: p 0.029 where the exact test gives 0.055) that
    ignores how much sooner one case was. Effect: the difference of restricted means (y - x
    episodes, positive = x sooner).
    """
    differences = paired_differences(x_times, x_events, y_times, y_events)
    wins, losses = int((differences < 0).sum()), int((differences > 0).sum())
    ties = int(differences.size) - wins - losses
    p_less, p_greater = signed_rank_permutation(differences)
    sign_less, _ = sign_test(wins, losses)
    limit = float(max(numpy.max(x_times), numpy.max(y_times))) if differences.size else 0.0
    effect = restricted_mean(y_times, limit) - restricted_mean(x_times, limit)
    x_km, y_km = kaplan_meier(x_times, x_events), kaplan_meier(y_times, y_events)
    detail = (f'KM median {x_km.describe()} vs {y_km.describe()}; sooner in {wins}, later in '
              f'{losses}, tied or undecided in {ties} of {differences.size} pairs (exact sign '
              f'test p = {sign_less:.3g})')
    return TestResult('exact signed-rank by pair (one-sided)', p_less, p_greater, effect,
                      'difference of restricted means (episodes)', detail,
                      0.5 ** (wins + losses) if wins + losses else 1.0)


def pairs_needed(differences, alpha: float = 0.05, power: float = 0.8) -> tuple:
    """Return (dz, pairs): the standardized paired effect and the pairs a test would need.

    dz = mean / standard deviation of the differences (Cohen's dz). Pairs for a one-sided test
    at ``alpha`` with ``power``: ((z_(1-alpha) + z_power) / dz)^2 for the paired t test (normal
    approximation), times pi / 3 for the signed-rank test (its asymptotic relative efficiency
    3 / pi under normal differences). (NaN, NaN): fewer than 2 differences or none vary.
    """
    data = finite(differences)
    if data.size < 2 or float(data.std(ddof=1)) == 0.0:
        return math.nan, math.nan
    dz = float(data.mean() / data.std(ddof=1))
    if dz == 0.0:
        return 0.0, math.inf
    pairs = ((stats.norm.ppf(1 - alpha) + stats.norm.ppf(power)) / abs(dz)) ** 2 * math.pi / 3
    return dz, float(math.ceil(pairs))


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
