"""Glider analysis: bound pairs per gait period, gliders, C1/C2 class, lifetime, transport, MSD exponent.

The definitions, stated here once and used by the batch analysis, the live monitor, ``smarticle-bag
analyze``, the demo and the experiments (also in docs/gliders.md and docs/glossary.md):

* **Periods.** Period ``q`` covers times ``[t0 + q T, t0 + (q + 1) T)``; ``t0`` is the gait start
  (default: the first frame). Frames before ``t0`` belong to no period and are ignored.
* **Bound (the one rule).** Pair (i, j) is bound in period q if, in at least one frame of q, their
  centre distance r is below ``r_bind`` (default ``R_BIND_BL`` = 1.6 BL, from the poses alone). The
  optional ``contacts`` input (touching counts as bound too) is a diagnostic that no shipped analysis
  uses. A frame where either robot is unseen (NaN pose) gives no r. A period with no frames is unbound.
* **Bound pair.** A run of at least ``min_periods`` (K, default 30) consecutive bound periods. Its
  lifetime is the run length (periods, and seconds = periods x T); ``ongoing`` marks a run still bound
  in the last period of the data (its lifetime is then a lower bound). The ``Glider`` records of an
  analysis are its bound pairs.
* **Glider.** A bound pair that travels: the net displacement of its centre of mass over its run is at
  least ``travel_min_w_per_100`` (default ``TRAVEL_MIN_W_PER_100`` = 1 W) per 100 periods of the run
  (0.3 W over a run of 30 periods, 0.4 W over 40). A still pair is a bound pair, not a glider.
* **Class**, by bands of the circular mean of phi over every seen frame of the run: **C1** within
  ``class_tolerance`` (default 45 deg) of 180 deg (135 to 225 deg, anti-aligned), **C2** within it of
  0 deg (315 to 45 deg, aligned), else **unclassified** (between the bands).
* **Labels while a run goes on** (the live monitor, the demo's animation): after n bound periods the
  run so far is ``bound`` (n < K), a ``bound pair`` (n >= K) or a ``glider`` (a bound pair whose
  per-period samples so far travel at least the glider rate over n periods); its class is that of the
  mean phi so far. A label appears only once its definition is met.
* **Isolated.** A bound pair's ``isolation`` is the fraction of its bound periods in which no third
  robot's centre comes within ``isolation_distance`` (default 2 W) of either robot's centre in any seen
  frame of the period; it is **isolated** (a pair, not part of a cluster or train) if ``isolation >=
  isolated_fraction`` (default 0.9). With two robots every bound pair is isolated.
* **Centre-of-mass path.** One sample per period of the run: the pair's centre of mass (mean of the
  two body centres) at the first frame of the period in which both robots are seen (a stroboscopic
  sample at nearly the same gait phase, so the within-cycle wiggle drops out); NaN if never seen.
* **Distance travelled** = ``|R_last - R_first|`` of that path (net transport, m; / W for W units).
  **Path length** = sum of ``|R(q + 1) - R(q)|`` over consecutive seen periods.
* **V_com** = mean of ``|R(q + 1) - R(q)| / T`` over consecutive seen periods (mean per-period
  centre-of-mass speed, m/s). ``net_speed`` = distance travelled / time between the first and last
  seen samples.
* **MSD and beta**: :mod:`smarticle_tracking.msd` on the per-period path, lags in periods; beta fitted
  over lags ``msd_min_lag..msd_max_lag`` (default up to a quarter of the run). Per glider the plain
  time-averaged MSD is used unless ``msd_subtract_mean``; :func:`ensemble_msd` applies the paper's
  ``<x^2> - <x>^2`` over an ensemble of gliders.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import Enum
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GliderConfigError, GliderInputError, MsdFitError
from .msd import MsdResult, default_max_lag, fit_msd_exponent, msd
from smarticle_common.pairs import (BODY_LENGTH, PairCoordinates, angular_distance, as_pose_array, circular_mean,
                    pair_centres, pair_coordinates, pair_indices)
from smarticle_common.facts import GAIT_PERIOD, R_BIND_BL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

#: Default bind distance: ``R_BIND_BL`` = 1.6 BL (8.6 cm) between body centres (the one bound rule).
DEFAULT_R_BIND = R_BIND_BL * BODY_LENGTH
#: Default isolation distance: no third robot's centre within 2 W of either glider robot's centre.
DEFAULT_ISOLATION_DISTANCE = 2.0 * BODY_LENGTH
#: Default K: a run of this many consecutive bound periods is a bound pair (the paper's 30 for lifetimes).
MIN_PERIODS = 30
#: The glider rule: a bound pair whose centre of mass travels (net) at least this many W per 100 periods of
#: its run. A lone robot drifts about 0.15 W per 100 periods, a still in-phase pair 0.1 W or less, P1's dense
#: bound pairs 0.3 W (median); a pair gliding a tenth of a period apart 3-4 W (docs/gliders.md).
TRAVEL_MIN_W_PER_100 = 1.0
#: The class bands: C1 within this of 180 deg (135 to 225 deg), C2 within it of 0 deg (315 to 45 deg).
CLASS_TOLERANCE = math.radians(45.0)
#: Per-frame sums accumulated per period, in this order along the last axis.
SUM_FIELDS: tuple[str, ...] = ('count', 'r', 'phi_cos', 'phi_sin', 'theta_cos', 'theta_sin')
_PERIOD_EPS = 1e-9


class GliderClass(Enum):
    """Binding symmetry of a bound pair or glider (paper Fig. 2), by the band of its mean phi."""

    C1 = 'C1'                       # anti-aligned: phi within the tolerance of pi (135 to 225 deg by default)
    C2 = 'C2'                       # aligned: phi within the tolerance of 0 (315 to 45 deg by default)
    UNCLASSIFIED = 'unclassified'   # phi mean between the bands


class PairKind(Enum):
    """What a run of bound periods is, by the definitions above."""

    BOUND = 'bound'                 # bound in fewer than K consecutive periods so far
    BOUND_PAIR = 'bound pair'       # bound >= K periods, travelling less than the glider rate
    GLIDER = 'glider'               # a bound pair travelling >= the glider rate


@dataclass(frozen=True)
class GliderConfig:
    """Glider-analysis settings, SI units (m, s, rad); ``width`` is the W of the paper's distances."""

    period: float = GAIT_PERIOD
    r_bind: float = DEFAULT_R_BIND
    min_periods: int = MIN_PERIODS
    class_tolerance: float = CLASS_TOLERANCE
    body_length: float = BODY_LENGTH
    width: float = BODY_LENGTH
    msd_min_lag: int = 1
    msd_max_lag: int | None = None
    msd_subtract_mean: bool = False
    isolation_distance: float = DEFAULT_ISOLATION_DISTANCE
    isolated_fraction: float = 0.9
    travel_min_w_per_100: float = TRAVEL_MIN_W_PER_100

    def __post_init__(self) -> None:
        for name in ('period', 'r_bind', 'body_length', 'width', 'isolation_distance'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise GliderConfigError(f'{name} must be a positive finite number, got {value!r}')
        if not _is_count(self.min_periods) or self.min_periods < 1:
            raise GliderConfigError(f'min_periods (K) must be a whole number >= 1, got {self.min_periods!r}')
        rate = self.travel_min_w_per_100
        if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate >= 0.0):
            raise GliderConfigError(f'travel_min_w_per_100 (the glider rule, W per 100 periods) must be a finite '
                                    f'number >= 0, got {rate!r}')
        frac = self.isolated_fraction
        if not (isinstance(frac, (int, float)) and 0.0 <= frac <= 1.0):
            raise GliderConfigError(f'isolated_fraction must be in [0, 1], got {frac!r}')
        tol = self.class_tolerance
        if not (isinstance(tol, (int, float)) and 0.0 < tol <= math.pi / 2):
            raise GliderConfigError(f'class_tolerance must be in (0, pi/2] rad so C1 and C2 cannot '
                                    f'overlap, got {tol!r}')
        if not _is_count(self.msd_min_lag) or self.msd_min_lag < 1:
            raise GliderConfigError(f'msd_min_lag must be a whole number >= 1, got {self.msd_min_lag!r}')
        if self.msd_max_lag is not None and (not _is_count(self.msd_max_lag)
                                             or self.msd_max_lag < self.msd_min_lag + 1):
            raise GliderConfigError(f'msd_max_lag must be None or a whole number > msd_min_lag '
                                    f'({self.msd_min_lag}), got {self.msd_max_lag!r}')


def _is_count(value: object) -> bool:
    """True for a Python or NumPy integer that is not a bool."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def classify_configuration(phi: float, tolerance: float = CLASS_TOLERANCE) -> GliderClass:
    """Classify a (mean) relative heading phi (rad) by its band: C1 (near pi), C2 (near 0) or unclassified."""
    if not math.isfinite(phi):
        return GliderClass.UNCLASSIFIED
    if float(angular_distance(phi, math.pi)) <= tolerance:
        return GliderClass.C1
    if float(angular_distance(phi, 0.0)) <= tolerance:
        return GliderClass.C2
    return GliderClass.UNCLASSIFIED


def travel_rate(distance: float, periods: int, width: float) -> float:
    """Net travel ``distance`` (m) of a run of ``periods`` periods in W per 100 periods (NaN if unknown)."""
    if periods < 1 or not math.isfinite(distance):
        return math.nan
    return 100.0 * distance / width / periods


def pair_kind(periods: int, distance: float, config: GliderConfig) -> PairKind:
    """Bound, bound pair or glider: a run of ``periods`` bound periods whose centre travelled ``distance`` (m)."""
    if periods < config.min_periods:
        return PairKind.BOUND
    rate = travel_rate(distance, periods, config.width)
    return PairKind.GLIDER if rate >= config.travel_min_w_per_100 else PairKind.BOUND_PAIR


def pair_label(kind: PairKind, glider_class: GliderClass) -> str:
    """The words for a run: 'bound' before K periods, then e.g. 'C1 bound pair' or 'C1 glider'."""
    if kind is PairKind.BOUND:
        return kind.value
    return f'{glider_class.value} {kind.value}'


def period_index(times: ArrayLike, t0: float, period: float) -> IntArray:
    """Gait period index ``floor((t - t0) / period)`` of each time (a time on a boundary starts it)."""
    return np.floor((np.asarray(times, dtype=float) - t0) / period + _PERIOD_EPS).astype(np.intp)


def frame_hits(r: ArrayLike, r_bind: float, contacts: ArrayLike | None = None) -> BoolArray:
    """Per frame and pair: touching (``contacts``) or r < r_bind; an unseen (NaN) r never binds."""
    r_arr = np.asarray(r, dtype=float)
    with np.errstate(invalid='ignore'):
        hits: BoolArray = np.isfinite(r_arr) & (r_arr < r_bind)
    if contacts is not None:
        hits = hits | np.asarray(contacts, dtype=bool)
    return hits


def frame_sums(coords: PairCoordinates) -> FloatArray:
    """Per-frame contributions (T, P, len(SUM_FIELDS)) to the period sums; unseen frames add zeros."""
    seen = np.isfinite(coords.r) & np.isfinite(coords.theta) & np.isfinite(coords.phi)
    r = np.where(seen, coords.r, 0.0)
    phi = np.where(seen, coords.phi, 0.0)
    theta = np.where(seen, coords.theta, 0.0)
    return np.stack([seen.astype(float), r,
                     np.where(seen, np.cos(phi), 0.0), np.where(seen, np.sin(phi), 0.0),
                     np.where(seen, np.cos(theta), 0.0), np.where(seen, np.sin(theta), 0.0)],
                    axis=-1)


class StretchMeans(NamedTuple):
    """Means over the seen frames of a stretch of periods (NaN when none was seen)."""

    r: FloatArray | float
    theta: FloatArray | float
    phi: FloatArray | float
    frames: FloatArray | float


def stretch_means(sums: ArrayLike) -> StretchMeans:
    """Mean r and circular means of theta and phi from summed ``frame_sums`` (..., 6)."""
    s = np.asarray(sums, dtype=float)
    count = s[..., 0]
    with np.errstate(invalid='ignore', divide='ignore'):
        r_mean = np.where(count > 0, s[..., 1] / np.maximum(count, 1.0), np.nan)
    return StretchMeans(r_mean, circular_mean(s[..., 4], s[..., 5], count),
                        circular_mean(s[..., 2], s[..., 3], count), count)


class PeriodTable(NamedTuple):
    """Per-period view of a run: Q periods x P pairs."""

    start_times: FloatArray   # (Q,) start time of each period (s)
    bound: BoolArray          # (Q, P) bound in that period
    sums: FloatArray          # (Q, P, 6) summed frame_sums over the period's frames
    strobe: FloatArray        # (Q, P, 2) centre of mass at the first frame both robots are seen


class Runs(NamedTuple):
    """Runs of consecutive bound periods: pair index, first period, one past the last period."""

    pair: IntArray
    start: IntArray
    stop: IntArray


def bound_runs(bound: ArrayLike) -> Runs:
    """All maximal runs of True along axis 0 of a (Q, P) bound table, ordered by pair then start."""
    table = np.asarray(bound, dtype=bool)
    if table.ndim != 2:
        raise GliderInputError(f'bound must be a (Q, P) table, got shape {table.shape}')
    padded = np.zeros((table.shape[1], table.shape[0] + 2), dtype=np.int8)
    padded[:, 1:-1] = table.T
    edges = np.diff(padded, axis=1)
    pair, start = np.nonzero(edges == 1)
    _, stop = np.nonzero(edges == -1)
    return Runs(pair.astype(np.intp), start.astype(np.intp), stop.astype(np.intp))


@dataclass(frozen=True, eq=False)
class Glider:
    """One bound pair (bound for at least K consecutive periods) with its transport statistics; a glider
    when ``is_glider`` (it travels at least the glider rate)."""

    i: int
    j: int
    pair_index: int
    start_period: int
    lifetime_periods: int
    start_time: float              # s
    lifetime: float                # s, lifetime_periods x T
    ongoing: bool                  # still bound in the last period of the data
    glider_class: GliderClass
    r_mean: float                  # m
    theta_mean: float              # rad, circular mean
    phi_mean: float                # rad, circular mean
    distance: float                # m, net centre-of-mass displacement
    path_length: float             # m
    v_com: float                   # m/s, mean per-period centre-of-mass speed
    net_speed: float               # m/s, distance / time between first and last seen samples
    beta: float                    # MSD exponent, NaN if the run is too short to fit
    isolation: float               # fraction of its periods with no third robot within isolation_distance
    isolated: bool                 # isolation >= config.isolated_fraction: a pair, not part of a cluster
    travel_w_per_100: float        # net travel in W per 100 periods of the run (NaN if never seen)
    kind: PairKind                 # BOUND_PAIR or GLIDER
    com_path: FloatArray = field(repr=False)   # (lifetime_periods, 2) per-period samples, NaN unseen
    msd: MsdResult = field(repr=False)

    @property
    def end_time(self) -> float:
        """End of the last bound period (s)."""
        return self.start_time + self.lifetime

    @property
    def is_glider(self) -> bool:
        """True when this bound pair travels at least the glider rate."""
        return self.kind is PairKind.GLIDER

    @property
    def label(self) -> str:
        """'C1 glider', 'C2 bound pair', ...: class and kind."""
        return pair_label(self.kind, self.glider_class)


@dataclass(frozen=True, eq=False)
class GliderAnalysis:
    """Everything the batch analysis computed for one run."""

    config: GliderConfig
    t0: float
    times: FloatArray           # (T,) frame times used (at or after t0)
    poses: FloatArray           # (T, N, 3) the poses of those frames (unseen: NaN)
    coords: PairCoordinates     # (T, P) r, theta, phi and the pair list
    periods: PeriodTable
    gliders: tuple[Glider, ...]


class PathStats(NamedTuple):
    """Transport along a per-period centre-of-mass path."""

    distance: float
    path_length: float
    v_com: float
    net_speed: float


def path_stats(path: ArrayLike, period: float) -> PathStats:
    """Distance, path length, V_com and net speed of a per-period path (L, 2); NaN rows skipped."""
    arr = np.asarray(path, dtype=float)
    seen = np.flatnonzero(np.all(np.isfinite(arr), axis=1))
    if seen.size < 2:
        return PathStats(0.0 if seen.size else math.nan, 0.0 if seen.size else math.nan,
                         math.nan, math.nan)
    distance = float(np.linalg.norm(arr[seen[-1]] - arr[seen[0]]))
    steps = np.linalg.norm(arr[1:] - arr[:-1], axis=1)
    steps = steps[np.isfinite(steps)]
    v_com = float(steps.mean() / period) if steps.size else math.nan
    net_speed = distance / (float(seen[-1] - seen[0]) * period)
    return PathStats(distance, float(steps.sum()), v_com, net_speed)


def _validate(times: ArrayLike, poses: ArrayLike, contacts: ArrayLike | None,
              ) -> tuple[FloatArray, FloatArray, BoolArray | None]:
    """Check shapes and times of the batch input."""
    arr = as_pose_array(poses)
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size != arr.shape[0]:
        raise GliderInputError(f'times must be 1-D with one entry per frame ({arr.shape[0]}), '
                               f'got shape {t.shape}')
    if t.size == 0:
        raise GliderInputError('no frames: times and poses are empty')
    if not np.all(np.isfinite(t)):
        raise GliderInputError('times must all be finite (drop frames without a timestamp)')
    if np.any(np.diff(t) < 0.0):
        first = int(np.flatnonzero(np.diff(t) < 0.0)[0]) + 1
        raise GliderInputError(f'times must not decrease: frame {first} at {t[first]!r} s comes after '
                               f'{t[first - 1]!r} s; sort the frames by time')
    mask = None
    if contacts is not None:
        mask = np.asarray(contacts)
        n_pairs = arr.shape[1] * (arr.shape[1] - 1) // 2
        if mask.shape != (arr.shape[0], n_pairs):
            raise GliderInputError(f'contacts must have shape (T, P) = ({arr.shape[0]}, {n_pairs}), '
                                   f'one column per pair in pair_indices order, got {mask.shape}')
        mask = mask.astype(bool)
    return t, arr, mask


def period_table(times: FloatArray, coords: PairCoordinates, centres: FloatArray, hits: BoolArray,
                 t0: float, period: float) -> PeriodTable:
    """Reduce per-frame data (sorted times >= t0) to the per-period table."""
    q = period_index(times, t0, period)
    n_periods = int(q[-1]) + 1
    n_pairs = coords.pairs.shape[0]
    starts = np.flatnonzero(np.r_[True, q[1:] != q[:-1]])
    rows = q[starts]
    bound = np.zeros((n_periods, n_pairs), dtype=bool)
    bound[rows] = np.logical_or.reduceat(hits, starts, axis=0)
    sums = np.zeros((n_periods, n_pairs, len(SUM_FIELDS)))
    sums[rows] = np.add.reduceat(frame_sums(coords), starts, axis=0)
    seen = np.all(np.isfinite(centres), axis=2)
    frame_no = np.where(seen, np.arange(times.size)[:, None], times.size)
    first = np.minimum.reduceat(frame_no, starts, axis=0)          # (U, P), T where never seen
    padded = np.concatenate([centres, np.full((1, n_pairs, 2), np.nan)], axis=0)
    strobe = np.full((n_periods, n_pairs, 2), np.nan)
    strobe[rows] = padded[first, np.arange(n_pairs)[None, :]]
    start_times = t0 + period * np.arange(n_periods, dtype=float)
    return PeriodTable(start_times, bound, sums, strobe)


def _fit_beta(result: MsdResult, config: GliderConfig) -> float:
    """Beta of one glider's MSD, NaN when the run is too short for the lag window."""
    try:
        return fit_msd_exponent(result, config.msd_min_lag, config.msd_max_lag, config.period).beta
    except MsdFitError:
        return math.nan


def isolation_fraction(frame_periods: IntArray, poses: FloatArray, i: int, j: int, start: int, stop: int,
                       config: GliderConfig) -> float:
    """Fraction of periods ``[start, stop)`` in which no third robot comes within the isolation distance.

    ``frame_periods`` is each frame's period index (``period_index``). A third robot is near in a period
    if, in any frame of it where both are seen, its centre lies within ``config.isolation_distance`` of
    robot i's or robot j's centre. 1.0 when there is no third robot.
    """
    n = poses.shape[1]
    others = np.array([k for k in range(n) if k not in (i, j)], dtype=np.intp)
    if others.size == 0 or stop <= start:
        return 1.0
    q = frame_periods
    in_run = (q >= start) & (q < stop)
    xy = poses[in_run][:, :, :2]
    with np.errstate(invalid='ignore'):
        d_i = np.linalg.norm(xy[:, others] - xy[:, i:i + 1], axis=2)
        d_j = np.linalg.norm(xy[:, others] - xy[:, j:j + 1], axis=2)
        near_frame = np.any((d_i < config.isolation_distance) | (d_j < config.isolation_distance), axis=1)
    crowded = np.zeros(stop - start, dtype=bool)
    np.logical_or.at(crowded, q[in_run] - start, near_frame)
    return float(1.0 - crowded.mean())


def measure_run(table: PeriodTable, pairs: IntArray, pair: int, start: int, stop: int,
                config: GliderConfig, frame_periods: IntArray | None = None,
                poses: FloatArray | None = None) -> Glider:
    """Measure one run of bound periods ``[start, stop)`` of pair index ``pair``.

    ``frame_periods`` (each frame's period index) and ``poses`` (all robots) give the isolation; without
    them the glider counts as isolated.
    """
    means = stretch_means(table.sums[start:stop, pair].sum(axis=0))
    path = table.strobe[start:stop, pair].copy()
    stats = path_stats(path, config.period)
    max_lag = config.msd_max_lag or default_max_lag(len(path))
    result = msd(path, max_lag=min(max_lag, max(len(path) - 1, 1)),
                 subtract_mean=config.msd_subtract_mean)
    phi_mean = float(means.phi)
    i, j = int(pairs[pair, 0]), int(pairs[pair, 1])
    lifetime = int(stop - start)
    isolation = 1.0 if frame_periods is None or poses is None else \
        isolation_fraction(frame_periods, poses, i, j, start, stop, config)
    return Glider(
        i=i, j=j, pair_index=int(pair),
        start_period=int(start), lifetime_periods=lifetime,
        start_time=float(table.start_times[start]), lifetime=float(lifetime * config.period),
        ongoing=bool(stop == table.bound.shape[0]),
        glider_class=classify_configuration(phi_mean, config.class_tolerance),
        r_mean=float(means.r), theta_mean=float(means.theta), phi_mean=phi_mean,
        distance=stats.distance, path_length=stats.path_length, v_com=stats.v_com,
        net_speed=stats.net_speed, beta=_fit_beta(result, config), isolation=isolation,
        isolated=bool(isolation >= config.isolated_fraction),
        travel_w_per_100=travel_rate(stats.distance, lifetime, config.width),
        kind=pair_kind(lifetime, stats.distance, config), com_path=path, msd=result)


def analyse_gliders(times: ArrayLike, poses: ArrayLike, config: GliderConfig | None = None,
                    contacts: ArrayLike | None = None, t0: float | None = None) -> GliderAnalysis:
    """Find and measure every glider in a run of poses (T, N, 3) at ``times`` (T,) seconds."""
    cfg = GliderConfig() if config is None else config
    t, arr, mask = _validate(times, poses, contacts)
    start = float(t[0]) if t0 is None else float(t0)
    if not math.isfinite(start):
        raise GliderInputError(f't0 must be a finite time in seconds, got {t0!r}')
    keep = slice(int(np.searchsorted(t, start - _PERIOD_EPS * cfg.period, side='left')), None)
    t, arr = t[keep], arr[keep]
    mask = None if mask is None else mask[keep]
    if t.size == 0:
        raise GliderInputError(f'no frames at or after t0 = {start!r} s')
    pairs = pair_indices(arr.shape[1])
    coords = pair_coordinates(arr, pairs)
    table = period_table(t, coords, pair_centres(arr, pairs), frame_hits(coords.r, cfg.r_bind, mask),
                         start, cfg.period)
    runs = bound_runs(table.bound)
    chosen = np.flatnonzero((runs.stop - runs.start) >= cfg.min_periods)
    chosen = chosen[np.lexsort((runs.pair[chosen], runs.start[chosen]))]   # by start, then pair
    frame_periods = period_index(t, start, cfg.period)       # once for every glider's isolation
    gliders = tuple(measure_run(table, pairs, int(runs.pair[k]), int(runs.start[k]), int(runs.stop[k]), cfg,
                                frame_periods, arr)
                    for k in chosen)
    return GliderAnalysis(cfg, start, t, arr, coords, table, gliders)


def running_labels(analysis: GliderAnalysis, glider: Glider) -> tuple[str, ...]:
    """The label of ``glider``'s run as known after each of its periods: entry n - 1 after n bound periods
    ('bound' before K, then 'C1 bound pair', 'C1 glider', ...; class by the mean phi so far, travel by the
    per-period samples so far), what the live monitor reports in the run's n-th period."""
    cfg = analysis.config
    stop = glider.start_period + glider.lifetime_periods
    sums = np.cumsum(analysis.periods.sums[glider.start_period:stop, glider.pair_index], axis=0)
    phi = np.asarray(stretch_means(sums).phi, dtype=float).reshape(-1)
    path = glider.com_path
    index = np.arange(len(path))
    seen = np.all(np.isfinite(path), axis=1)
    last = np.maximum.accumulate(np.where(seen, index, -1))
    first = int(np.argmax(seen)) if seen.any() else 0
    with np.errstate(invalid='ignore'):
        distance = np.where(last >= 0, np.linalg.norm(path[np.maximum(last, 0)] - path[first], axis=1), np.nan)
    return tuple(pair_label(pair_kind(n + 1, float(distance[n]), cfg),
                            classify_configuration(float(phi[n]), cfg.class_tolerance))
                 for n in range(glider.lifetime_periods))


def ensemble_msd(gliders: Iterable[Glider], max_lag: int | None = None,
                 subtract_mean: bool = True) -> MsdResult:
    """The paper's ``<x^2> - <x>^2`` over all time origins of all given gliders' per-period paths."""
    paths = [g.com_path for g in gliders]
    if not paths:
        raise GliderInputError('ensemble_msd needs at least one glider')
    return msd(paths, max_lag=max_lag, subtract_mean=subtract_mean)


#: Columns of the glider table: key, header, format.
TABLE_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ('i', 'i', '{:d}'), ('j', 'j', '{:d}'), ('class', 'class', '{}'), ('kind', 'kind', '{}'),
    ('start_s', 'start [s]', '{:.1f}'), ('start_period', 'start [T]', '{:d}'),
    ('lifetime_periods', 'life [T]', '{:d}'), ('lifetime_s', 'life [s]', '{:.1f}'),
    ('ongoing', 'ongoing', '{}'), ('isolated', 'isolated', '{}'), ('phi_deg', 'phi [deg]', '{:.0f}'),
    ('r_bl', 'r [BL]', '{:.2f}'),
    ('distance_w', 'dist [W]', '{:.2f}'), ('travel_w_per_100', 'W / 100 T', '{:.2f}'), ('travels', 'travels', '{}'),
    ('path_w', 'path [W]', '{:.2f}'), ('beta', 'beta', '{:.2f}'), ('v_com_mm_s', 'V_com [mm/s]', '{:.2f}'),
)


def glider_table(gliders: Sequence[Glider], config: GliderConfig | None = None,
                 ) -> list[dict[str, object]]:
    """One row per bound pair: ids, class, kind, start, lifetime, travel (W, W per 100 periods), beta, V_com."""
    cfg = GliderConfig() if config is None else config
    return [{
        'i': g.i, 'j': g.j, 'class': g.glider_class.value, 'kind': g.kind.value,
        'start_s': g.start_time, 'start_period': g.start_period,
        'lifetime_periods': g.lifetime_periods, 'lifetime_s': g.lifetime, 'ongoing': g.ongoing,
        'isolated': g.isolated, 'isolation': g.isolation,
        'phi_deg': math.degrees(g.phi_mean), 'r_bl': g.r_mean / cfg.body_length,
        'distance_w': g.distance / cfg.width, 'travel_w_per_100': g.travel_w_per_100, 'travels': g.is_glider,
        'path_w': g.path_length / cfg.width,
        'beta': g.beta, 'v_com_mm_s': 1e3 * g.v_com,
    } for g in gliders]


def _cell(fmt: str, value: object) -> str:
    """Format one table cell; NaN shows as 'nan'."""
    if isinstance(value, float) and not math.isfinite(value):
        return 'nan'
    return fmt.format(value)


def rule_text(config: GliderConfig) -> str:
    """The definitions in one line, with the config's numbers (for the tables' headers)."""
    bl = config.r_bind / config.body_length
    tol = math.degrees(config.class_tolerance)
    return (f'bound pair: centre distance under {bl:.1f} BL in some frame of each of >= {config.min_periods} '
            f'periods in a row; glider: a bound pair whose centre of mass travels >= '
            f'{config.travel_min_w_per_100:g} W per 100 periods (net); C1: mean phi {180 - tol:.0f}-{180 + tol:.0f} '
            f'deg, C2: {360 - tol:.0f}-{tol:.0f} deg')


def glider_summary(gliders: Sequence[Glider]) -> str:
    """'2 bound pairs, 1 of them a glider (0-1 C1)': the count line of a report."""
    if not gliders:
        return 'no bound pair, no glider'
    moving = [g for g in gliders if g.is_glider]
    names = ', '.join(f'{g.i}-{g.j} {g.glider_class.value}' for g in moving)
    return (f'{len(gliders)} bound pair{"s" if len(gliders) != 1 else ""}, '
            + (f'{len(moving)} of them {"a glider" if len(moving) == 1 else "gliders"} ({names})' if moving
               else 'no glider'))


def format_glider_table(rows: Sequence[Mapping[str, object]]) -> str:
    """Format glider_table rows as an aligned plain-text table."""
    if not rows:
        return 'no bound pairs, so no gliders'
    header = [title for _, title, _ in TABLE_COLUMNS]
    body = [[_cell(fmt, row[key]) for key, _, fmt in TABLE_COLUMNS] for row in rows]
    widths = [max(len(line[c]) for line in [header, *body]) for c in range(len(header))]
    lines = ['  '.join(cell.rjust(w) for cell, w in zip(line, widths, strict=True))
             for line in [header, *body]]
    lines.insert(1, '  '.join('-' * w for w in widths))
    return '\n'.join(lines)
