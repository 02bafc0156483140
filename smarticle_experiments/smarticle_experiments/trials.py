"""What the trial kinds share: the glider measurements of a recording, the pair start, MSD fits and the
library versions a trial's numbers depend on. The kinds themselves are modules of ``smarticle_experiments.kinds``.

Lengths in the results are in body lengths (``_bl``) or in W (``_w``, W = BL for the smarticle), angles in
degrees (``_deg``), speeds as stated. ``trouble`` is the SimTrouble message that ended the trial early ('' if
none): such a trial still returns what it measured, and the report counts and lists it.

Gliders follow the glider analysis's rules (``smarticle_tracking.gliders``, docs/gliders.md): bound = r
under ``r_bind_bl`` (1.6 BL) in any frame of a period, from the poses; **isolated** = in at least 90 % of
its bound periods no third robot's centre comes within ``isolation_w`` W (default 2 W) of either robot's
centre. P1 counts trials with an isolated glider of at least ``positive_periods`` periods.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from smarticle_sim.batch import Recording
from smarticle_sim.settings import SimConfig
from smarticle_tracking.gliders import Glider, GliderConfig, analyse_gliders
from smarticle_tracking.msd import fit_msd_exponent, msd

from .configs import config_of
from .params import GliderParams

__all__ = ['add_contact_fractions', 'analyse_recording', 'code_versions', 'config_of', 'ensemble_msd', 'finite',
           'glider_record', 'msd_beta', 'pair_start', 'rounded']


# ------------------------------------------------------------------ glider measurements


def rounded(values: np.ndarray, digits: int) -> list[Any]:
    """A nested list of rounded floats, NaN as None (JSON has no NaN)."""
    arr = np.round(np.asarray(values, dtype=float), digits)
    return [rounded(row, digits) if np.ndim(row) else (None if not math.isfinite(row) else float(row))
            for row in arr]


def finite(value: float) -> float | None:
    """A float, or None for NaN / inf."""
    return float(value) if math.isfinite(value) else None


def glider_record(g: Glider, period: float, bl: float) -> dict[str, Any]:
    """One glider as a JSON-ready dict (lengths in BL = W, angles in degrees)."""
    return {
        'i': g.i, 'j': g.j, 'class': g.glider_class.value, 'start_period': g.start_period,
        'lifetime_periods': g.lifetime_periods, 'ongoing': g.ongoing,
        'r_bl': finite(g.r_mean / bl), 'theta_deg': finite(math.degrees(g.theta_mean) % 360.0),
        'phi_deg': finite(math.degrees(g.phi_mean) % 360.0), 'distance_w': finite(g.distance / bl),
        'path_w': finite(g.path_length / bl), 'v_com_w_per_period': finite(g.v_com * period / bl),
        'beta': finite(g.beta), 'isolated': g.isolated, 'isolation': round(g.isolation, 4),
        'com_path_w': rounded(g.com_path / bl, 4),
    }


def analyse_recording(config: SimConfig, rec: Recording, period: float, p: GliderParams) -> dict[str, Any]:
    """Gliders of a recording (the glider analysis's one bound rule, on poses) plus per-trial figures."""
    bl = config.robot.body_length
    gcfg = GliderConfig(period=period, r_bind=float(p.r_bind_bl) * bl, min_periods=int(p.min_periods),
                        isolation_distance=float(p.isolation_w) * bl,
                        body_length=bl, width=bl)
    analysis = analyse_gliders(rec.time, rec.poses, gcfg)
    gliders = [glider_record(g, period, bl) for g in analysis.gliders]
    per = max(1, round(period / (config.physics.control_tick * rec.meta['sample_every'])))
    positive = int(p.positive_periods)
    longest = max(gliders, key=lambda g: g['lifetime_periods'], default=None)
    return {
        'periods_run': (len(rec.time) - 1) / per if len(rec.time) else 0.0,
        'trouble': rec.trouble,
        'peak_tilt_deg': finite(float(rec.meta.get('peak_tilt_deg', math.nan))),
        'peak_overlap_mm': finite(float(rec.meta.get('peak_overlap_mm', math.nan))),
        'n_gliders': len(gliders),
        'positive': any(g['lifetime_periods'] >= positive for g in gliders),
        'positive_isolated': any(g['lifetime_periods'] >= positive and g['isolated'] for g in gliders),
        'longest_periods': longest['lifetime_periods'] if longest else 0,
        'longest_class': longest['class'] if longest else '',
        'longest_distance_w': longest['distance_w'] if longest else None,
        'gliders': gliders,
        'trajectory_bl': rounded(rec.poses[::per, :, :2] / bl, 3) if p.trajectory else [],
        'trajectory_dt': period,
    }


def add_contact_fractions(gliders: Sequence[dict[str, Any]], periods: Mapping[tuple[int, int], set[int]]) -> None:
    """Give each glider record ``contact_fraction``: the share of its bound periods in which its two robots
    touched at some physics step (a pair bound by r alone can sit still side by side without touching)."""
    for g in gliders:
        touched = periods.get((min(g['i'], g['j']), max(g['i'], g['j'])), set())
        span = range(g['start_period'], g['start_period'] + g['lifetime_periods'])
        g['contact_fraction'] = round(sum(q in touched for q in span) / max(len(span), 1), 4)


def pair_start(p: Mapping[str, Any], seed: int) -> tuple[float, float, float]:
    """The pair start (r BL, theta deg, phi deg): the spec's plus seeded uniform jitter ``start_jitter``."""
    jitter = np.asarray(p['start_jitter'], dtype=float)
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, size=3) if np.any(jitter) else np.zeros(3)
    return (float(p['r_bl'] + jitter[0] * u[0]), float(p['theta_deg'] + jitter[1] * u[1]),
            float(p['phi_deg'] + jitter[2] * u[2]))


def ensemble_msd(paths: Sequence[Sequence[Sequence[float | None]]], max_lag: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The tracking package's ensemble MSD (``<x^2> - <x>^2``) of per-period paths (W): (lags, msd W^2)."""
    arrays = [np.array([[math.nan if v is None else v for v in row] for row in path], dtype=float)
              for path in paths if len(path) >= 2]
    if not arrays:
        return np.empty(0), np.empty(0)
    result = msd(arrays, max_lag=max_lag, subtract_mean=True)
    return result.lags.astype(float), result.msd


def msd_beta(lags: np.ndarray, values: np.ndarray) -> float:
    """The tracking package's power-law fit of an MSD curve (lags in periods); NaN if it cannot be fitted."""
    from smarticle_tracking.errors import MsdFitError
    from smarticle_tracking.msd import MsdResult

    if lags.size < 2:
        return math.nan
    result = MsdResult(lags.astype(np.intp), values, np.ones(lags.size, dtype=np.intp))
    try:
        return fit_msd_exponent(result).beta
    except MsdFitError:
        return math.nan


def code_versions() -> dict[str, str]:
    """Versions of the libraries a trial's numbers depend on (pybullet, numpy) in this process."""
    from importlib import metadata

    out = {'numpy': np.__version__}
    try:
        out['pybullet'] = metadata.version('pybullet')
    except metadata.PackageNotFoundError:
        out['pybullet'] = 'unknown'
    return out
