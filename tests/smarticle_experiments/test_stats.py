"""Statistics: Wilson intervals, Kaplan-Meier with censoring, bootstrap means."""

from __future__ import annotations

import math

import pytest
from scipy.stats import binomtest

from smarticle_experiments.stats import bootstrap_mean, kaplan_meier, wilson


def test_wilson_is_scipys_interval() -> None:
    est = wilson(97, 151)
    ci = binomtest(97, 151).proportion_ci(method='wilson')
    assert (est.low, est.high) == pytest.approx((ci.low, ci.high))
    assert est.contains(0.64)
    assert wilson(0, 0).contains(0.5) is None
    assert wilson(0, 10).low == 0.0 and wilson(0, 10).high > 0.2


def test_kaplan_meier_counts_censored_lifetimes_as_survivors() -> None:
    life = [10, 20, 25, 25, 25, 25, 30]
    ended = kaplan_meier(life, [False] * 7)
    cut = kaplan_meier(life, [False, False, True, True, True, True, False])
    assert ended.median.value == 25
    assert cut.median.value == 30       # pairs still bound at 25 count as survivors, not as breakups
    assert cut.censored == 4 and cut.n == 7
    every = kaplan_meier([50, 60], [True, True])
    assert math.isinf(every.median.value) and every.median.low == 60


def test_bootstrap_mean_interval_is_reproducible() -> None:
    values = [1.0, 2.0, 2.5, 3.0, 4.0, 6.0]
    a, b = bootstrap_mean(values), bootstrap_mean(values)
    assert a == b
    assert a.low < a.value < a.high
    assert bootstrap_mean([]).n == 0
    assert bootstrap_mean([2.0, math.nan, 2.0]).value == 2.0
