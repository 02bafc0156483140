"""Online glider monitor: one frame at a time, the same definitions as the batch analysis.

Feed ``update(time, poses)`` in time order; it returns the pairs bound right now. A pair is reported
while its run of bound periods is open: it was bound in the last completed period, or it has bound
(r < r_bind, the one bound rule of the batch analysis) in the current period already. Its ``age``
counts the run's periods, the current one included once it has bound. Its ``kind`` and ``label`` are
those of the run so far (``gliders.running_labels``): 'bound' before K periods, a bound pair from K, a
glider once it also travels the glider rate. When a period closes, runs that did not bind end; those
of at least K periods (bound pairs) go to ``finished`` (a bounded history). Memory is O(pairs +
history), not O(frames).
A run's ``isolation`` counts its periods in which no third robot came within ``isolation_distance`` of
either robot, as in the batch analysis.

All maths comes from :mod:`smarticle_common.pairs` and :mod:`smarticle_tracking.gliders`
(pair_coordinates, pair_centres, period_index, frame_hits, frame_sums, stretch_means,
classify_configuration), so the batch and online answers agree (tests/smarticle_tracking prove it).
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .errors import GliderConfigError, GliderInputError
from .gliders import (SUM_FIELDS, GliderClass, GliderConfig, PairKind, classify_configuration, frame_hits,
                      frame_sums, pair_kind, pair_label, period_index, stretch_means, travel_rate)
from smarticle_common.pairs import FloatArray, IntArray, as_pose_array, pair_centres, pair_coordinates, pair_indices


class BoundPair(NamedTuple):
    """A pair bound now (or a finished bound pair): latest coordinates and the run's statistics so far."""

    i: int
    j: int
    r: float                 # m, latest frame in which both were seen (finished: up to the run's end)
    theta: float             # rad, latest seen
    phi: float               # rad, latest seen
    phi_mean: float          # rad, circular mean over the run
    glider_class: GliderClass
    start_period: int
    start_time: float        # s
    age_periods: int
    age: float               # s, age_periods x T
    is_glider: bool          # a bound pair (age_periods >= K) travelling >= the glider rate so far
    distance: float          # m, net centre-of-mass displacement over the run (per-period samples)
    isolation: float = 1.0   # fraction of the run's periods with no third robot within isolation_distance
    isolated: bool = True    # isolation >= isolated_fraction: a pair, not part of a cluster
    kind: PairKind = PairKind.BOUND      # bound (age < K), bound pair, or glider
    travel_w_per_100: float = math.nan   # net travel in W per 100 periods of the run so far

    @property
    def is_bound_pair(self) -> bool:
        """True once the run has lasted K periods (a glider is a bound pair too)."""
        return self.kind is not PairKind.BOUND

    @property
    def label(self) -> str:
        """'bound', then 'C1 bound pair', 'C1 glider', ...: only once each definition is met."""
        return pair_label(self.kind, self.glider_class)


class GliderMonitor:
    """Streaming glider detector with bounded memory; one instance per arena."""

    def __init__(self, config: GliderConfig | None = None, t0: float | None = None,
                 history: int = 100) -> None:
        if isinstance(history, bool) or not isinstance(history, int) or history < 1:
            raise GliderConfigError(f'history must be a whole number >= 1, got {history!r}')
        if t0 is not None and not math.isfinite(t0):
            raise GliderConfigError(f't0 must be a finite time in seconds or None, got {t0!r}')
        self.config = GliderConfig() if config is None else config
        self._t0_given = None if t0 is None else float(t0)
        self.finished: deque[BoundPair] = deque(maxlen=history)
        self.pairs = np.zeros((0, 2), dtype=np.intp)
        self._t0: float | None = self._t0_given
        self._n_robots: int | None = None
        self._last_time = -math.inf
        self._period: int | None = None
        self._done = False
        self.reset()

    @property
    def t0(self) -> float | None:
        """Start of period 0 (s): the given t0, or the first frame's time; None before any frame."""
        return self._t0

    @property
    def current_period(self) -> int | None:
        """Index of the period being accumulated, None before the first frame."""
        return self._period

    def _allocate(self, n_robots: int) -> None:
        """Size the per-pair state for ``n_robots`` robots."""
        self._n_robots = n_robots
        self.pairs = pair_indices(n_robots)
        n = len(self.pairs)
        fields = len(SUM_FIELDS)
        self._hit = np.zeros(n, dtype=bool)
        self._crowd = np.zeros(n, dtype=bool)        # a third robot came near in the current period
        self._run_crowded = np.zeros(n, dtype=np.intp)
        others = np.ones((n, n_robots), dtype=bool)
        others[np.arange(n), self.pairs[:, 0]] = False
        others[np.arange(n), self.pairs[:, 1]] = False
        self._others = others
        self._sums = np.zeros((n, fields))
        self._strobe = np.full((n, 2), np.nan)
        self._run_len = np.zeros(n, dtype=np.intp)
        self._run_start = np.zeros(n, dtype=np.intp)
        self._run_sums = np.zeros((n, fields))
        self._run_first = np.full((n, 2), np.nan)
        self._run_last = np.full((n, 2), np.nan)
        self._latest = np.full((n, 3), np.nan)       # r, theta, phi of the latest seen frame
        self._run_latest = np.full((n, 3), np.nan)   # the same, as of the run's last bound period

    def update(self, time: float, poses: ArrayLike, contacts: ArrayLike | None = None,
               ) -> tuple[BoundPair, ...]:
        """Add one frame (time s, poses (N, 3), optional contacts (P,)) and return the bound pairs."""
        return self.bound_pairs() if self.add(time, poses, contacts) else ()

    def add(self, time: float, poses: ArrayLike, contacts: ArrayLike | None = None) -> bool:
        """Add one frame as ``update`` does, without building the bound pairs (``bound_pairs`` gives them);
        False for a frame before the gait start (in no period)."""
        if self._done:
            raise GliderInputError('the monitor was finished; call reset() before feeding a new run')
        if not math.isfinite(time):
            raise GliderInputError(f'frame time must be finite, got {time!r}')
        if time < self._last_time:
            raise GliderInputError(f'time went backwards: {time!r} s after {self._last_time!r} s')
        frame = as_pose_array(poses)
        if frame.shape[0] != 1:
            raise GliderInputError(f'update takes one frame of poses (N, 3), got shape {np.shape(poses)}')
        if self._n_robots is None:
            self._allocate(frame.shape[1])
        elif frame.shape[1] != self._n_robots:
            raise GliderInputError(f'frame has {frame.shape[1]} robots, the monitor tracks '
                                   f'{self._n_robots}; call reset() to change the team')
        mask = None
        if contacts is not None:
            mask = np.asarray(contacts)
            if mask.shape != (len(self.pairs),):
                raise GliderInputError(f'contacts must have shape ({len(self.pairs)},), one per pair, '
                                       f'got {mask.shape}')
            mask = mask.astype(bool)[np.newaxis]
        self._last_time = float(time)
        if self._t0 is None:
            self._t0 = float(time)
        q = int(period_index(time, self._t0, self.config.period))
        if q < 0:
            return False                  # before the gait start: in no period
        if self._period is None:
            self._period = q
        elif q > self._period:
            self._close_period()
            if q > self._period + 1:
                self._close_period()      # skipped periods have no frames: every run ends
            self._period = q
        self._accumulate(frame, mask)
        return True

    def _accumulate(self, frame: FloatArray, mask: ArrayLike | None) -> None:
        """Add one frame's coordinates, hits, sums and centre of mass to the current period."""
        coords = pair_coordinates(frame, self.pairs)
        self._hit |= frame_hits(coords.r, self.config.r_bind, mask)[0]
        if frame.shape[1] > 2:
            xy = frame[0, :, :2]
            with np.errstate(invalid='ignore'):
                near = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2) < self.config.isolation_distance
            self._crowd |= np.any((near[self.pairs[:, 0]] | near[self.pairs[:, 1]]) & self._others, axis=1)
        self._sums += frame_sums(coords)[0]
        centres = pair_centres(frame, self.pairs)[0]
        first = np.all(np.isnan(self._strobe), axis=1) & np.all(np.isfinite(centres), axis=1)
        self._strobe[first] = centres[first]
        latest = np.stack([coords.r[0], coords.theta[0], coords.phi[0]], axis=1)
        seen = np.all(np.isfinite(latest), axis=1)
        self._latest[seen] = latest[seen]

    def _close_period(self) -> None:
        """End the current period: extend the runs that bound in it, end the others."""
        hit = self._hit
        ended = (self._run_len > 0) & ~hit
        long_enough = ended & (self._run_len >= self.config.min_periods)
        self.finished.extend(self._snapshot(np.flatnonzero(long_enough), include_current=False))
        new = hit & (self._run_len == 0)
        self._run_start[new] = self._period if self._period is not None else 0
        self._run_sums[new] = 0.0
        self._run_first[new] = np.nan
        self._run_last[new] = np.nan
        self._run_crowded[new] = 0
        self._run_len = np.where(hit, self._run_len + 1, 0)
        self._run_crowded = np.where(hit, self._run_crowded + (hit & self._crowd), 0)
        self._run_sums[hit] += self._sums[hit]
        sampled = hit & np.all(np.isfinite(self._strobe), axis=1)
        fill = sampled & np.all(np.isnan(self._run_first), axis=1)
        self._run_first[fill] = self._strobe[fill]
        self._run_last[sampled] = self._strobe[sampled]
        self._run_latest[hit] = self._latest[hit]
        self._hit = np.zeros_like(hit)
        self._crowd = np.zeros_like(hit)
        self._sums = np.zeros_like(self._sums)
        self._strobe = np.full_like(self._strobe, np.nan)

    def _snapshot(self, chosen: IntArray, include_current: bool) -> list[BoundPair]:
        """Describe the open runs of pair indices ``chosen`` (with the current period if it has bound)."""
        p = np.asarray(chosen, dtype=np.intp)
        sums = self._run_sums[p].copy()
        age = self._run_len[p].copy()
        crowded = self._run_crowded[p].copy()
        start = self._run_start[p].copy()
        first, last = self._run_first[p].copy(), self._run_last[p].copy()
        latest = self._latest[p] if include_current else self._run_latest[p]
        if include_current:
            hit = self._hit[p]
            start = np.where(hit & (age == 0), self._period if self._period is not None else 0, start)
            age = age + hit
            crowded = crowded + (hit & self._crowd[p])
            sums[hit] += self._sums[p][hit]
            sampled = hit & np.all(np.isfinite(self._strobe[p]), axis=1)
            last[sampled] = self._strobe[p][sampled]
            fill = sampled & np.any(np.isnan(first), axis=1)
            first[fill] = self._strobe[p][fill]
        phi_mean = np.asarray(stretch_means(sums).phi, dtype=float)
        distance = np.linalg.norm(last - first, axis=1)          # NaN where never sampled
        t0 = self._t0 if self._t0 is not None else 0.0
        period = self.config.period
        with np.errstate(invalid='ignore', divide='ignore'):
            isolation = np.where(age > 0, 1.0 - crowded / np.maximum(age, 1), 1.0)
        kinds = [pair_kind(int(age[k]), float(distance[k]), self.config) for k in range(len(p))]
        return [BoundPair(
            i=int(self.pairs[pk, 0]), j=int(self.pairs[pk, 1]),
            r=float(latest[k, 0]), theta=float(latest[k, 1]), phi=float(latest[k, 2]),
            phi_mean=float(phi_mean[k]),
            glider_class=classify_configuration(float(phi_mean[k]), self.config.class_tolerance),
            start_period=int(start[k]), start_time=t0 + int(start[k]) * period,
            age_periods=int(age[k]), age=int(age[k]) * period,
            is_glider=kinds[k] is PairKind.GLIDER, distance=float(distance[k]),
            isolation=float(isolation[k]), isolated=bool(isolation[k] >= self.config.isolated_fraction),
            kind=kinds[k], travel_w_per_100=travel_rate(float(distance[k]), int(age[k]), self.config.width))
            for k, pk in enumerate(p)]

    def bound_pairs(self) -> tuple[BoundPair, ...]:
        """The pairs whose run of bound periods is open now, in pair order."""
        if self._n_robots is None:
            return ()
        open_runs = np.flatnonzero((self._run_len > 0) | self._hit)
        return tuple(self._snapshot(open_runs, include_current=True))

    def finish(self) -> tuple[BoundPair, ...]:
        """End of data: close the current period; return the finished bound pairs, then the still-open ones."""
        if self._period is None or self._done:
            return tuple(self.finished)
        self._close_period()
        self._done = True
        still_open = self._snapshot(np.flatnonzero(self._run_len >= self.config.min_periods),
                                    include_current=False)
        return (*self.finished, *still_open)

    def reset(self) -> None:
        """Forget every frame, run and finished glider; keep the config and a t0 given at construction."""
        self.finished.clear()
        self._t0 = self._t0_given
        self._n_robots = None
        self._last_time = -math.inf
        self._period = None
        self._done = False
