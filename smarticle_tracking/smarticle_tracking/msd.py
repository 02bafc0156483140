"""Mean-square displacement of centre-of-mass paths and its power-law exponent beta.

Estimator (paper, End matter: ``<sigma^2(t)> = <x^2(t)> - <x(t)>^2``, ``<sigma^2> ~ t^beta``):

* A path is a sequence of planar positions ``R(q)`` sampled once per gait period (NaN = not seen).
* For a lag of ``k`` samples, the displacements are ``x = R(q + k) - R(q)`` over **every time origin**
  ``q`` of **every path** given (overlapping windows) whose two ends are both finite.
* ``sigma^2(k) = mean(|x|^2) - |mean(x)|^2`` (summed over both components) when ``subtract_mean``,
  else the plain ``mean(|x|^2)``.  The mean drift ``<x>`` is taken over the same set of displacements.
  For a single straight-moving glider that mean is the glider's own drift, so subtracting it removes
  the very transport being measured; see docs/gliders.md for when to use which.
* ``beta`` is the least-squares slope of ``log sigma^2`` against ``log(k dt)`` over a lag window.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GliderInputError, MsdFitError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


class MsdResult(NamedTuple):
    """MSD per lag: ``lags`` in samples (1..max_lag), ``msd`` in m^2, ``counts`` of displacements."""

    lags: IntArray
    msd: FloatArray
    counts: IntArray


class PowerLawFit(NamedTuple):
    """Fit ``msd = prefactor * (lag * dt) ** beta`` over ``n_points`` lags from ``min_lag`` to ``max_lag``."""

    beta: float
    prefactor: float
    n_points: int
    min_lag: int
    max_lag: int


def _as_paths(paths: ArrayLike | Sequence[ArrayLike]) -> list[FloatArray]:
    """Normalise one (L, d) path, a (n, L, d) stack or a sequence of paths to a list of arrays."""
    if isinstance(paths, (list, tuple)) and paths and all(np.ndim(p) == 2 for p in paths):
        candidates = [np.asarray(p, dtype=float) for p in paths]
    else:
        whole = np.asarray(paths, dtype=float)
        candidates = list(whole) if whole.ndim == 3 else [whole]
    if not candidates:
        raise GliderInputError('msd needs at least one path')
    dims = {p.shape[1] if p.ndim == 2 else -1 for p in candidates}
    if len(dims) != 1 or -1 in dims or 0 in dims:
        raise GliderInputError('every path must have shape (L, d) with the same d >= 1, got '
                               f'{[p.shape for p in candidates]}')
    return candidates


def default_max_lag(length: int) -> int:
    """Default largest lag for a path of ``length`` samples: a quarter of it, at least 1."""
    return max(1, int(length) // 4)


def msd(paths: ArrayLike | Sequence[ArrayLike], max_lag: int | None = None,
        subtract_mean: bool = True) -> MsdResult:
    """MSD of one (L, d) path or an ensemble of paths over lags 1..max_lag (NaN samples skipped)."""
    arrays = _as_paths(paths)
    longest = max(len(p) for p in arrays)
    if max_lag is None:
        max_lag = default_max_lag(longest)
    if isinstance(max_lag, bool) or not isinstance(max_lag, (int, np.integer)) or max_lag < 1:
        raise GliderInputError(f'max_lag must be a whole number of samples >= 1, got {max_lag!r}')
    lags = np.arange(1, int(max_lag) + 1, dtype=np.intp)
    values = np.full(lags.size, np.nan)
    counts = np.zeros(lags.size, dtype=np.intp)
    dim = arrays[0].shape[1]
    finite = [np.all(np.isfinite(p), axis=1) for p in arrays]
    clean = [np.where(ok[:, None], p, 0.0) for p, ok in zip(arrays, finite, strict=True)]
    for n, lag in enumerate(lags):
        total_sq = 0.0
        total = np.zeros(dim)
        count = 0
        for path, ok in zip(clean, finite, strict=True):
            if lag >= len(path):
                continue
            both = ok[lag:] & ok[:-lag]
            step = (path[lag:] - path[:-lag])[both]
            total_sq += float(np.einsum('ij,ij->', step, step))
            total += step.sum(axis=0)
            count += int(both.sum())
        if count:
            mean_sq = total_sq / count
            if subtract_mean:
                mean = total / count
                mean_sq = max(mean_sq - float(mean @ mean), 0.0)
            values[n] = mean_sq
            counts[n] = count
    return MsdResult(lags, values, counts)


def fit_msd_exponent(result: MsdResult, min_lag: int = 1, max_lag: int | None = None,
                     time_step: float = 1.0) -> PowerLawFit:
    """Fit beta on log-log axes over lags ``min_lag..max_lag`` (samples); ``time_step`` s per sample."""
    if not (math.isfinite(time_step) and time_step > 0.0):
        raise GliderInputError(f'time_step must be a positive number of seconds, got {time_step!r}')
    hi = int(result.lags[-1]) if max_lag is None and result.lags.size else (max_lag or 0)
    if min_lag < 1 or hi < min_lag:
        raise GliderInputError(f'lag window must satisfy 1 <= min_lag <= max_lag, got ({min_lag}, {max_lag})')
    use = ((result.lags >= min_lag) & (result.lags <= hi) & (result.counts > 0)
           & np.isfinite(result.msd) & (result.msd > 0.0))
    if int(use.sum()) < 2:
        raise MsdFitError(f'need at least 2 lags with a positive MSD in [{min_lag}, {hi}] to fit beta, '
                          f'got {int(use.sum())}: use a longer path or a wider lag window')
    log_t = np.log(result.lags[use] * time_step)
    log_m = np.log(result.msd[use])
    beta, intercept = np.polyfit(log_t, log_m, 1)
    return PowerLawFit(float(beta), float(math.exp(intercept)), int(use.sum()), int(min_lag), int(hi))
