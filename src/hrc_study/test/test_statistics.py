"""The study's statistics against values computed by hand (each fails on a wrong estimator)."""

import math

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
