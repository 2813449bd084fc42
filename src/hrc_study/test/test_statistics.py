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


def test_the_exact_sign_test_by_hand():
    from hrc_study.statistics import sign_test

    # 8 of 10 pairs one way: P(X >= 8) for X ~ Bin(10, 1/2) = (45 + 10 + 1) / 1024 = 0.0547,
    # two-sided 0.109; the log-rank test stratified by pair said 0.029 (a normal approximation)
    claimed, other = sign_test(8, 2)
    assert claimed == pytest.approx(56 / 1024)
    assert min(1.0, 2 * claimed) == pytest.approx(0.109, abs=5e-4)
    assert other == pytest.approx(1013 / 1024)          # P(X <= 8)
    assert sign_test(0, 0) == (1.0, 1.0)


def test_the_exact_signed_rank_permutation_by_hand():
    from hrc_study.statistics import signed_rank_permutation

    # d = -3, -1, +2: ranks 3, 1, 2, signed sum -3 - 1 + 2 = -2. The 8 sign flips give
    # -6, -4, -2, 0, 0, 2, 4, 6: P(sum <= -2) = 3/8, P(sum >= -2) = 6/8
    less, greater = signed_rank_permutation([-3.0, -1.0, 2.0, 0.0])     # the zero is dropped
    assert less == pytest.approx(3 / 8) and greater == pytest.approx(6 / 8)
    # tied sizes stay exact: -1, -1, -1, +1: signed sum -2 (ranks 2.5 each: -5)
    less, _ = signed_rank_permutation([-1.0, -1.0, -1.0, 1.0])
    assert less == pytest.approx(5 / 16)                # 3 or 4 minus signs of 16 flips
    # one pair that differs (the rest tied, as when every other seed sits at the floor): the
    # two flips -1 and +1, so P(sum <= -1) = 1/2, P(sum >= -1) = 1; a study with it reports
    assert signed_rank_permutation([0.0, -4.0, 0.0]) == (0.5, 1.0)
    assert signed_rank_permutation([2.0]) == (1.0, 0.5)


def test_paired_censored_differences_keep_only_known_orders():
    from hrc_study.statistics import paired_differences

    # both converged: 10 - 14; x converged at 5 before y was censored at 9: at least 4 sooner;
    # y censored at 3 before x converged at 8: unknown (0); both censored: unknown (0)
    differences = paired_differences([10, 5, 8, 20], [1, 1, 1, 0], [14, 9, 3, 30], [1, 0, 0, 0])
    assert list(differences) == [-4.0, -4.0, 0.0, 0.0]


def test_the_paired_test_sees_a_paired_effect_the_plain_one_misses():
    from hrc_study.statistics import paired_sooner

    # ten seeds of very different speed; within each seed x converges 5 episodes before y
    base = numpy.arange(10) * 20.0 + 20
    x, y = base, base + 5
    paired = paired_sooner(x, [1] * 10, y, [1] * 10)
    assert paired.p_value == pytest.approx(1 / 1024) and paired.p_reverse == 1.0
    assert 'sooner in 10, later in 0' in paired.detail
    assert logrank_faster(x, [1] * 10, y, [1] * 10).p_value > 0.2
    # 8 pairs sooner by 1, 2 later by 30: the sign test says 0.055, the ranks see the size
    x = numpy.array([10.0] * 8 + [40.0] * 2)
    y = numpy.array([11.0] * 8 + [10.0] * 2)
    sized = paired_sooner(x, [1] * 10, y, [1] * 10)
    assert 'exact sign test p = 0.0547' in sized.detail
    assert sized.p_value > 0.1           # the two large losses outweigh eight small wins


def test_pairs_needed_for_a_small_effect():
    from hrc_study.statistics import pairs_needed

    # differences of mean 1 and sd 5: dz = 0.2; ((1.645 + 0.842) / 0.2)^2 * pi / 3 = 161.9
    differences = numpy.array([1.0 - 5.0, 1.0 + 5.0] * 5) * 1.0
    dz, pairs = pairs_needed(differences)
    sd = float(numpy.std(differences, ddof=1))
    assert dz == pytest.approx(1.0 / sd)
    expected = ((1.6448536 + 0.8416212) / (1.0 / sd)) ** 2 * math.pi / 3
    assert pairs == math.ceil(expected)
    assert pairs_needed([1.0, 1.0]) == (pytest.approx(math.nan, nan_ok=True),
                                        pytest.approx(math.nan, nan_ok=True))


def test_censored_counts_mann_whitney_and_the_paired_test_disagree():
    # human-involved episodes of sessions that never converged: case 1's are capped at 260
    # because its robot-alone step used 40 of the 300 episodes, case 3's at 300. Mann-Whitney
    # calls 260 < 300 significant; nothing converged, so the paired test knows nothing.
    from hrc_study.statistics import paired_sooner

    case1, case3 = [260.0] * 10, [300.0] * 10
    assert mann_whitney_less(case1, case3).p_value < 1e-4
    survival = paired_sooner(case1, [0] * 10, case3, [0] * 10)
    assert survival.p_value == 1.0 and survival.p_reverse == 1.0
    assert logrank_faster(case1, [0] * 10, case3, [0] * 10).p_value == 1.0
