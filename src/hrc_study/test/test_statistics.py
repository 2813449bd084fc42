"""The study's statistics against values computed by hand (each fails on a wrong estimator)."""

import math

import numpy
import pytest

from hrc_study.statistics import (holm, kaplan_meier, logrank_faster, mann_whitney_less,
                                  mean_interval, rank_biserial, restricted_mean)


def test_kaplan_meier_median_accounts_for_censoring():
    # events at 1, 2, 4, 5; censored at 3, 6, 6. S(4) = 6/7 * 5/6 * 3/4 = 0.536,
    # S(5) = 0.536 * 2/3 = 0.357: median 5. Censored-as-events gives 4, dropping them 3.
    summary = kaplan_meier([1, 2, 3, 4, 5, 6, 6], [1, 1, 0, 1, 1, 0, 0])
    assert summary.median == 5.0
    assert summary.events == 4 and summary.count == 7 and summary.limit == 6.0
    # the survival interval at the end stays above 0.5: the upper bound is not reached
    assert math.isnan(summary.high)
    assert summary.low <= summary.median


def test_kaplan_meier_without_censoring_is_the_lower_sample_median():
    summary = kaplan_meier(list(range(1, 11)), [True] * 10)
    assert summary.median == 5.0     # first t with S(t) <= 0.5; numpy's median would be 5.5
    assert summary.low <= 5.0 <= summary.high <= 10


def test_kaplan_meier_median_not_reached_when_most_runs_hit_the_limit():
    summary = kaplan_meier([50, 60, 300, 300, 300], [1, 1, 0, 0, 0])
    assert math.isnan(summary.median)
    assert summary.describe() == '> 300 (not reached)'


def test_holm_adjusts_known_p_values():
    # sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1 = 0.02, 0.03, 0.06, 0.04 -> monotone 0.06
    assert holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])
    adjusted = holm([0.02, math.nan])
    assert adjusted[0] == pytest.approx(0.02) and math.isnan(adjusted[1])


def test_mean_interval_student_t():
    # mean 3, s = 1.5811, t(0.975, 4) = 2.7764: half width 1.9632
    interval = mean_interval([1, 2, 3, 4, 5])
    assert interval.estimate == 3.0
    assert interval.high - 3.0 == pytest.approx(1.9632, abs=1e-4)
    assert math.isnan(mean_interval([7.0]).low)
    assert mean_interval([math.nan, 2.0, 4.0]).count == 2


def test_rank_biserial_and_mann_whitney_direction():
    assert rank_biserial([1, 2, 3], [4, 5, 6]) == 1.0
    assert rank_biserial([4, 5, 6], [1, 2, 3]) == -1.0
    assert rank_biserial([1, 5], [3]) == 0.0
    lower = mann_whitney_less([1, 2, 3, 4, 5], [6, 7, 8, 9, 10])
    assert lower.p_value == pytest.approx(1 / 252)      # exact: one of C(10, 5) orderings
    assert lower.p_reverse == pytest.approx(1.0)


def test_restricted_mean_and_logrank_direction():
    assert restricted_mean([10, 20, 400], 300) == pytest.approx(110)
    fast = logrank_faster([10, 12, 14, 16, 18], [1] * 5, [40, 50, 300, 300, 300],
                          [1, 1, 0, 0, 0])
    assert fast.p_value < 0.01 < fast.p_reverse
    assert fast.effect > 0


# ---------------------------------------------------------------- the intervals and paired tests


def test_bca_interval_tracks_the_exact_interval_of_an_exponential_mean():
    # exponential data, n = 10: the exact 95% interval of the mean is
    # 2 n xbar / chi2(0.975, 2n) .. 2 n xbar / chi2(0.025, 2n); Student t is symmetric and too
    # low on both ends, BCa follows the skew
    from scipy import stats

    from hrc_bag.report.intervals import bca_interval

    sample = numpy.random.default_rng(3).exponential(1.0, 10)
    total = 2 * sample.sum()
    exact = (total / stats.chi2.ppf(0.975, 20), total / stats.chi2.ppf(0.025, 20))
    bca = bca_interval(sample)
    student = mean_interval(sample)
    bca_miss = abs(bca.low - exact[0]) + abs(bca.high - exact[1])
    student_miss = abs(student.low - exact[0]) + abs(student.high - exact[1])
    assert bca_miss < 0.6 * student_miss
    assert bca.high > student.high      # the long right tail


def test_bca_interval_never_leaves_the_physical_range():
    from hrc_bag.report.intervals import bca_interval

    # an effort (a variance, >= 0) that is near zero in 9 of 10 seeds: Student t goes negative
    efforts = [0.0001] * 9 + [0.05]
    assert mean_interval(efforts).low < 0
    interval = bca_interval(efforts, floor=0.0)
    assert interval.low >= 0.0 and interval.low <= interval.estimate <= interval.high
    # a percentage near its ceiling stays <= 100
    assert bca_interval([100] * 8 + [90, 95], floor=0, ceiling=100).high <= 100
    same = bca_interval([2.0] * 5)
    assert (same.low, same.high) == (2.0, 2.0)
    assert math.isnan(bca_interval([1.0]).low)


def test_wilcoxon_uses_the_pairing_that_mann_whitney_ignores():
    # ten pairs (seeds) of very different levels; x is below its twin by 0.1 in every pair:
    # the exact signed-rank p is 1/2^10, while the unpaired test sees two overlapping samples
    from hrc_study.statistics import wilcoxon_less

    levels = numpy.arange(10) * 1.0
    x, y = levels + numpy.linspace(0, 0.01, 10), levels + 0.1
    paired = wilcoxon_less(x, y)
    assert paired.p_value == pytest.approx(1 / 1024)
    assert paired.effect == 1.0
    assert mann_whitney_less(x, y).p_value > 0.3


def test_stratified_logrank_by_hand_and_equal_to_scipy_for_one_stratum():
    from scipy import stats

    from hrc_study.statistics import stratified_logrank, stratified_logrank_faster

    # stratum A: x converges at 1, y at 2; stratum B: x at 3, y censored at 5.
    # A, t = 1: 2 at risk (1 of x), 1 event of x: O - E = 1 - 1/2, V = 1/4; t = 2: y alone.
    # B, t = 3: likewise O - E = 1/2, V = 1/4. Total 1 and 1/2: Z = sqrt 2, p = 0.0786.
    result = stratified_logrank_faster([1, 3], [1, 1], [2, 5], [1, 0], ['A', 'B'], ['A', 'B'])
    assert result.p_value == pytest.approx(stats.norm.sf(math.sqrt(2)))
    assert result.p_value == pytest.approx(0.0786, abs=1e-4)
    # one stratum: the plain log-rank statistic (scipy)
    x_times, x_events = [3, 5, 7, 9, 12, 15], [1, 1, 0, 1, 1, 0]
    y_times, y_events = [6, 8, 10, 14, 20, 20], [1, 0, 1, 1, 0, 0]
    difference, variance = stratified_logrank(x_times + y_times, x_events + y_events,
                                              [True] * 6 + [False] * 6, [0] * 12)
    plain = stats.logrank(stats.CensoredData(
        uncensored=[t for t, e in zip(y_times, y_events) if e],
        right=[t for t, e in zip(y_times, y_events) if not e]), stats.CensoredData(
        uncensored=[t for t, e in zip(x_times, x_events) if e],
        right=[t for t, e in zip(x_times, x_events) if not e]))
    assert difference / math.sqrt(variance) == pytest.approx(abs(plain.statistic))


def test_stratified_logrank_sees_a_paired_effect_the_plain_one_misses():
    from hrc_study.statistics import stratified_logrank_faster

    # ten seeds of very different speed; within each seed x converges 5 episodes before y
    base = numpy.arange(10) * 20.0 + 20
    x, y = base, base + 5
    strata = list(range(10))
    paired = stratified_logrank_faster(x, [1] * 10, y, [1] * 10, strata, strata)
    assert paired.p_value < 0.01 < paired.p_reverse
    assert logrank_faster(x, [1] * 10, y, [1] * 10).p_value > 0.2


def test_censored_counts_mann_whitney_and_the_survival_test_disagree():
    # human-involved episodes of sessions that never converged: case 1's are capped at 260
    # because its robot-alone step used 40 of the 300 episodes, case 3's at 300. Mann-Whitney
    # calls 260 < 300 significant; nothing converged, so the survival test knows nothing.
    from hrc_study.statistics import stratified_logrank_faster

    case1, case3 = [260.0] * 10, [300.0] * 10
    assert mann_whitney_less(case1, case3).p_value < 1e-4
    strata = list(range(10))
    survival = stratified_logrank_faster(case1, [0] * 10, case3, [0] * 10, strata, strata)
    assert survival.p_value == 1.0 and survival.p_reverse == 1.0
    assert logrank_faster(case1, [0] * 10, case3, [0] * 10).p_value == 1.0
