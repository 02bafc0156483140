"""Constructed two-robot scenes with known pair coordinates, bound periods and transport."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

PERIOD = 1.6
FRAMES_PER_PERIOD = 8
R_BOUND = 0.08       # below the default r_bind (0.108 m)
R_FREE = 0.30        # above it


def pair_scene(bound: Sequence[bool], phi: float | Sequence[float] = math.pi, theta: float = math.pi / 2,
               velocity: tuple[float, float] = (0.0, 0.0), n_robots: int = 3,
               frames_per_period: int = FRAMES_PER_PERIOD, period: float = PERIOD,
               ) -> tuple[np.ndarray, np.ndarray]:
    """Robots 0 and 1 at r = R_BOUND in the periods where ``bound`` is True, else R_FREE.

    Robot 0 faces +y (body axis +x); robot 1 sits at polar angle ``theta`` in robot 0's body frame with
    relative heading ``phi`` (a constant or one value per frame). The pair's centre of mass moves at
    ``velocity`` (m/s). Other robots are parked far away. Returns (times (T,), poses (T, N, 3)).
    """
    mask = np.asarray(bound, dtype=bool)
    n_frames = mask.size * frames_per_period
    times = np.arange(n_frames) * (period / frames_per_period)
    r = np.where(np.repeat(mask, frames_per_period), R_BOUND, R_FREE)
    centre = np.outer(times, velocity)
    u = np.array([math.cos(theta), math.sin(theta)])
    poses = np.zeros((n_frames, n_robots, 3))
    poses[:, 0, :2] = centre - 0.5 * r[:, None] * u
    poses[:, 1, :2] = centre + 0.5 * r[:, None] * u
    poses[:, 0, 2] = math.pi / 2
    poses[:, 1, 2] = math.pi / 2 + np.broadcast_to(np.asarray(phi, dtype=float), (n_frames,))
    for k in range(2, n_robots):
        poses[:, k, :2] = (2.0 + k, 2.0)
    return times, poses


def periods(total: int, start: int, length: int) -> list[bool]:
    """A bound mask of ``total`` periods, True for ``length`` periods from ``start``."""
    return [start <= q < start + length for q in range(total)]
