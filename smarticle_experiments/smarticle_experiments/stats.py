"""Uncertainties from scipy.stats: Wilson intervals, Kaplan-Meier lifetimes, bootstrap intervals of means.

* Proportions: ``scipy.stats.binomtest(k, n).proportion_ci(0.95, method='wilson')``; two proportions
  compared by Fisher's exact test (``scipy.stats.fisher_exact``, two-sided).
* Lifetimes cut off by the end of a trial: Kaplan-Meier survival ``scipy.stats.ecdf`` of
  ``CensoredData`` (right-censored = still bound at the end); the median and its 95 % interval are read
  off the survival curve and its pointwise 95 % band (log-log) where they cross 0.5.
* Means over trajectories (beta, V_com, r, distance, drift): ``scipy.stats.bootstrap`` (BCa, 9999
  resamples, a fixed seed so a report is reproducible; percentile when BCa is degenerate; no interval
  for fewer than 3 values).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

CONFIDENCE = 0.95
BOOTSTRAP_RESAMPLES = 9999
BOOTSTRAP_SEED = 0
#: Fewest values a bootstrap interval is given for (below: the mean without an interval).
MIN_BOOTSTRAP = 3


@dataclass(frozen=True)
class Estimate:
    """A value with its 95 % interval, the sample size and the method that gave the interval."""

    value: float
    low: float
    high: float
    n: int
    method: str

    def contains(self, x: float) -> bool | None:
        """True if ``x`` lies inside the interval (None if the interval is undefined)."""
        if not (math.isfinite(self.low) and math.isfinite(self.high)):
            return None
        return self.low <= x <= self.high

    def text(self, fmt: str = '.3g', scale: float = 1.0) -> str:
        """``value [low, high]`` with the format ``fmt`` (values times ``scale``)."""
        if math.isinf(self.value) and math.isfinite(self.low):
            return f'> {format(self.low * scale, fmt)} (not reached)'
        if not math.isfinite(self.value):
            return f'n/a (n = {self.n})'
        lo = format(self.low * scale, fmt) if math.isfinite(self.low) else '?'
        hi = format(self.high * scale, fmt) if math.isfinite(self.high) else '?'
        return f'{format(self.value * scale, fmt)} [{lo}, {hi}]'


def wilson(k: int, n: int) -> Estimate:
    """Proportion k/n with its 95 % Wilson interval (scipy.stats.binomtest)."""
    from scipy.stats import binomtest

    if n <= 0:
        return Estimate(math.nan, math.nan, math.nan, 0, 'Wilson')
    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=CONFIDENCE, method='wilson')
    return Estimate(k / n, float(ci.low), float(ci.high), int(n), 'Wilson')


def fisher_p(a: tuple[int, int], b: tuple[int, int]) -> float:
    """Fisher's exact test of two proportions, each (k, n): its two-sided p-value (scipy.stats.fisher_exact)."""
    from scipy.stats import fisher_exact

    return float(fisher_exact([[a[0], a[1] - a[0]], [b[0], b[1] - b[0]]]).pvalue)


def bootstrap_mean(values: Sequence[float]) -> Estimate:
    """Mean of ``values`` (NaN dropped) with a 95 % bootstrap interval (scipy.stats.bootstrap, BCa)."""
    from scipy.stats import bootstrap

    arr = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if arr.size == 0:
        return Estimate(math.nan, math.nan, math.nan, 0, 'bootstrap')
    mean = float(arr.mean())
    if arr.size < MIN_BOOTSTRAP:
        return Estimate(mean, math.nan, math.nan, int(arr.size), 'bootstrap')
    if np.all(arr == arr[0]):
        return Estimate(mean, mean, mean, int(arr.size), 'bootstrap')
    for method in ('BCa', 'percentile'):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            res = bootstrap((arr,), np.mean, confidence_level=CONFIDENCE, n_resamples=BOOTSTRAP_RESAMPLES,
                            method=method, rng=np.random.default_rng(BOOTSTRAP_SEED))
        low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
        if math.isfinite(low) and math.isfinite(high):
            return Estimate(mean, low, high, int(arr.size), f'bootstrap {method}')
    return Estimate(mean, math.nan, math.nan, int(arr.size), 'bootstrap')


@dataclass(frozen=True)
class Survival:
    """Kaplan-Meier survival of lifetimes: step curve, its 95 % band, and the median with its interval."""

    times: np.ndarray
    survival: np.ndarray
    low: np.ndarray
    high: np.ndarray
    median: Estimate
    n: int
    censored: int


def _first_below(times: np.ndarray, curve: np.ndarray, level: float = 0.5) -> float:
    """First time at which a survival curve drops to ``level`` or below (inf if never)."""
    below = np.flatnonzero(curve <= level)
    return float(times[below[0]]) if below.size else math.inf


def kaplan_meier(lifetimes: Sequence[float], censored: Sequence[bool]) -> Survival:
    """Kaplan-Meier survival of ``lifetimes`` where ``censored`` marks those cut off by the end of a trial."""
    from scipy.stats import CensoredData, ecdf

    life = np.asarray(lifetimes, dtype=float)
    cens = np.asarray(censored, dtype=bool)
    n, n_cens = int(life.size), int(cens.sum())
    if n == 0:
        empty = np.empty(0)
        return Survival(empty, empty, empty, empty, Estimate(math.nan, math.nan, math.nan, 0, 'Kaplan-Meier'), 0, 0)
    if n_cens == n:   # nothing ended: the median lies beyond every observation
        t = np.array([float(life.max())])
        one = np.ones(1)
        return Survival(t, one, one, one, Estimate(math.inf, float(life.max()), math.inf, n, 'Kaplan-Meier'), n, n_cens)
    data = CensoredData(uncensored=life[~cens], right=life[cens])
    sf = ecdf(data).sf
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        band = sf.confidence_interval(CONFIDENCE, method='log-log')
    times = np.asarray(sf.quantiles, dtype=float)
    surv = np.asarray(sf.probabilities, dtype=float)
    low = np.nan_to_num(np.asarray(band.low.probabilities, dtype=float), nan=0.0)
    high = np.nan_to_num(np.asarray(band.high.probabilities, dtype=float), nan=1.0)
    median = Estimate(_first_below(times, surv), _first_below(times, low), _first_below(times, high), n,
                      'Kaplan-Meier')
    return Survival(times, surv, low, high, median, n, n_cens)


def logrank(a: tuple[Sequence[float], Sequence[bool]], b: tuple[Sequence[float], Sequence[bool]]
            ) -> tuple[float, float]:
    """Log-rank test (``scipy.stats.logrank``) of two groups of right-censored lifetimes, each given as
    (lifetimes, censored): (statistic, p)."""
    from scipy.stats import CensoredData
    from scipy.stats import logrank as scipy_logrank

    def data(group: tuple[Sequence[float], Sequence[bool]]) -> CensoredData:
        life = np.asarray(group[0], dtype=float)
        cens = np.asarray(group[1], dtype=bool)
        return CensoredData(uncensored=life[~cens], right=life[cens])

    res = scipy_logrank(data(a), data(b))
    return float(res.statistic), float(res.pvalue)
