"""MSD estimator <x^2> - <x>^2 over time origins and the exponent beta."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_tracking.errors import GliderInputError, MsdFitError
from smarticle_tracking.msd import fit_msd_exponent, msd


def beta_of(paths: object, subtract_mean: bool, max_lag: int | None = None) -> float:
    """Fitted exponent over the default window."""
    return fit_msd_exponent(msd(paths, max_lag=max_lag, subtract_mean=subtract_mean)).beta


def test_exact_values_on_a_tiny_path() -> None:
    path = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    plain = msd(path, max_lag=2, subtract_mean=False)
    assert plain.lags.tolist() == [1, 2]
    assert plain.counts.tolist() == [3, 2]
    assert plain.msd[0] == pytest.approx((1 + 1 + 4) / 3)
    assert plain.msd[1] == pytest.approx((4 + 9) / 2)
    centred = msd(path, max_lag=2, subtract_mean=True)
    assert centred.msd[0] == pytest.approx(2.0 - (4 / 3) ** 2)      # <x^2> - <x>^2
    assert centred.msd[1] == pytest.approx(6.5 - 2.5 ** 2)


def test_ballistic_walk_gives_beta_two() -> None:
    rng = np.random.default_rng(1)
    steps = np.arange(400)[:, None] * np.array([[3e-3, 1e-3]])
    path = steps + rng.normal(scale=1e-4, size=steps.shape)
    assert beta_of(path, subtract_mean=False) == pytest.approx(2.0, abs=0.05)


def test_random_walk_gives_beta_one() -> None:
    rng = np.random.default_rng(7)
    path = np.cumsum(rng.normal(scale=1e-3, size=(4000, 2)), axis=0)
    # lags up to 100 of 4000 samples: each lag averages >= 3900 displacements, so one walk suffices
    assert beta_of(path, subtract_mean=True, max_lag=100) == pytest.approx(1.0, abs=0.1)
    assert beta_of(path, subtract_mean=False, max_lag=100) == pytest.approx(1.0, abs=0.1)


def test_ensemble_of_ballistic_gliders_in_random_directions_keeps_beta_two() -> None:
    rng = np.random.default_rng(2)
    k = np.arange(200)[:, None]
    paths = []
    for angle in rng.uniform(0, 2 * math.pi, 40):
        paths.append(k * 2e-3 * np.array([math.cos(angle), math.sin(angle)])
                     + rng.normal(scale=1e-4, size=(200, 2)))
    assert beta_of(paths, subtract_mean=True) == pytest.approx(2.0, abs=0.1)


def test_subtracting_the_mean_removes_a_common_drift() -> None:
    rng = np.random.default_rng(4)
    k = np.arange(1000)[:, None]
    paths = [k * np.array([[5e-3, 0.0]]) + np.cumsum(rng.normal(scale=1e-3, size=(1000, 2)), axis=0)
             for _ in range(10)]
    assert beta_of(paths, subtract_mean=True) == pytest.approx(1.0, abs=0.1)     # fluctuations only
    assert beta_of(paths, subtract_mean=False) > 1.8                              # drift dominates


def test_nan_samples_are_skipped_not_propagated() -> None:
    rng = np.random.default_rng(5)
    path = np.cumsum(rng.normal(size=(300, 2)), axis=0)
    holed = path.copy()
    holed[rng.choice(300, 40, replace=False)] = np.nan
    result = msd(holed, max_lag=20)
    assert np.all(np.isfinite(result.msd))
    lag = 3
    ok = np.all(np.isfinite(holed[lag:] - holed[:-lag]), axis=1)
    d = (holed[lag:] - holed[:-lag])[ok]
    assert result.counts[lag - 1] == ok.sum()
    assert result.msd[lag - 1] == pytest.approx(np.mean(np.sum(d ** 2, axis=1)) - np.sum(d.mean(axis=0) ** 2))


def test_fit_window_and_errors() -> None:
    path = np.arange(50.0)[:, None] * np.ones((1, 2))
    result = msd(path, max_lag=10, subtract_mean=False)
    fit = fit_msd_exponent(result, min_lag=2, max_lag=6, time_step=1.6)
    assert (fit.beta, fit.n_points, fit.min_lag, fit.max_lag) == (pytest.approx(2.0), 5, 2, 6)
    assert fit.prefactor == pytest.approx(2.0 / 1.6 ** 2)
    with pytest.raises(MsdFitError, match='at least 2 lags'):
        fit_msd_exponent(msd(path[:2], max_lag=1))
    with pytest.raises(GliderInputError):
        fit_msd_exponent(result, min_lag=5, max_lag=3)
    with pytest.raises(GliderInputError):
        msd(path, max_lag=0)
    with pytest.raises(GliderInputError):
        msd(np.zeros(10))
