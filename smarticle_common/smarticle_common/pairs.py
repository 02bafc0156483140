"""Pair coordinates of two smarticles (paper Fig. 3(a)), vectorised over frames and pairs: the one implementation.

Units, everywhere in the stack: ``r`` in metres (``to_body_lengths`` converts), angles in radians,
``theta`` and ``phi`` in [0, 2 pi) (``wrap_2pi``), headings in [-pi, pi) (``wrap_pi``).

Conventions (drawn in docs/gliders.md):

* A pose is ``(x, y, heading)`` in the arena frame: the body centre (m) and the angle (rad) of the
  body normal, which is the robot's heading (the body frame of ``smarticle_common.gait``: body x from
  joint 1 to joint 2, body y = the normal, so body x points at ``heading - pi/2``).
* For the ordered pair ``(i, j)`` with ``i < j``:

  - ``r``     distance between the two body centres (m);
  - ``theta`` polar angle of robot j's centre in robot i's body frame, measured counter-clockwise
    from robot i's **body axis** (+x, toward joint 2) in [0, 2 pi): ``theta = pi/2`` means j sits
    straight ahead of i, on its normal; quadrants 1 and 4 are the joint-2 (arm 2) side;
  - ``phi``   ``heading_j - heading_i`` wrapped to [0, 2 pi): C1 (anti-aligned) near pi, C2
    (aligned) near 0 / 2 pi.

* A non-finite pose component means "robot not seen in this frame": every quantity of a pair that
  involves it is NaN, and the downstream statistics skip NaNs rather than propagate them.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import PairInputError
from .facts import BODY_LENGTH

TWO_PI = 2.0 * math.pi

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


class PairCoordinates(NamedTuple):
    """Pair coordinates over time: arrays of shape (T, P), pair p is ``pairs[p] = (i, j)``."""

    r: FloatArray       # centre distance (m)
    theta: FloatArray   # polar angle of j in i's body frame, from i's body axis (rad, [0, 2pi))
    phi: FloatArray     # heading_j - heading_i (rad, [0, 2pi))
    pairs: IntArray     # (P, 2) robot indices, i < j


def wrap_2pi(angle: ArrayLike) -> FloatArray:
    """Wrap angles (rad) to [0, 2 pi) (pair angles theta and phi); NaN stays NaN."""
    wrapped = np.mod(np.asarray(angle, dtype=float), TWO_PI)
    # np.mod returns exactly 2 pi for tiny negative inputs; fold that onto 0.
    folded: FloatArray = np.where(wrapped >= TWO_PI, 0.0, wrapped)
    return folded


def wrap_pi(angle: float) -> float:
    """Wrap one angle (rad) to [-pi, pi) (headings)."""
    return (angle + math.pi) % TWO_PI - math.pi


def angular_distance(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Unsigned distance between angles ``a`` and ``b`` on the circle (rad, [0, pi])."""
    diff = np.mod(np.asarray(a, dtype=float) - np.asarray(b, dtype=float) + math.pi, TWO_PI)
    distance: FloatArray = np.abs(diff - math.pi)
    return distance


def to_body_lengths(length: ArrayLike, body_length: float = BODY_LENGTH) -> FloatArray:
    """Convert lengths in metres to body lengths (BL = ``body_length`` m)."""
    if not (math.isfinite(body_length) and body_length > 0.0):
        raise PairInputError(f'body_length must be a positive length in metres, got {body_length!r}')
    return np.asarray(length, dtype=float) / body_length


def pair_indices(n_robots: int) -> IntArray:
    """All unordered pairs ``(i, j)``, ``i < j``, of ``n_robots`` robots as a (P, 2) array."""
    if isinstance(n_robots, bool) or not isinstance(n_robots, (int, np.integer)) or n_robots < 2:
        raise PairInputError(f'need at least 2 robots to form a pair, got {n_robots!r}')
    i, j = np.triu_indices(int(n_robots), k=1)
    return np.stack([i, j], axis=1).astype(np.intp)


def pair_position(pairs: IntArray, i: int, j: int) -> int:
    """Return the index p of pair ``(i, j)`` (either order) in ``pairs``."""
    lo, hi = min(i, j), max(i, j)
    hits = np.flatnonzero((pairs[:, 0] == lo) & (pairs[:, 1] == hi))
    if hits.size == 0:
        raise PairInputError(f'no pair ({i}, {j}) among the {len(pairs)} pairs')
    return int(hits[0])


def as_pose_array(poses: ArrayLike) -> FloatArray:
    """Validate poses as a float (T, N, 3) copy ((N, 3) gains T = 1); a non-finite pose becomes all NaN."""
    arr = np.array(poses, dtype=float)
    if arr.ndim == 2:
        arr = arr[np.newaxis]
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise PairInputError(f'poses must have shape (T, N, 3) or (N, 3) of (x, y, heading), '
                               f'got {np.shape(poses)}')
    if arr.shape[1] < 2:
        raise PairInputError(f'poses hold {arr.shape[1]} robot(s); a pair needs at least 2')
    arr[~np.all(np.isfinite(arr), axis=2)] = np.nan   # one bad component: the whole pose is unseen
    return arr


def _checked_pairs(pairs: ArrayLike | None, n_robots: int) -> IntArray:
    """Validate a (P, 2) pair list against ``n_robots`` (None: all pairs)."""
    if pairs is None:
        return pair_indices(n_robots)
    arr = np.asarray(pairs)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0 or not np.issubdtype(arr.dtype, np.integer):
        raise PairInputError(f'pairs must be a non-empty (P, 2) integer array, got shape {arr.shape}')
    if arr.min() < 0 or arr.max() >= n_robots or np.any(arr[:, 0] == arr[:, 1]):
        raise PairInputError(f'pairs must hold two different robot indices in 0..{n_robots - 1}')
    return arr.astype(np.intp)


def pair_coordinates(poses: ArrayLike, pairs: ArrayLike | None = None) -> PairCoordinates:
    """Return r, theta, phi of every pair in every frame of poses (T, N, 3) (NaN where unseen)."""
    arr = as_pose_array(poses)
    idx = _checked_pairs(pairs, arr.shape[1])
    a = arr[:, idx[:, 0]]          # (T, P, 3) robot i
    b = arr[:, idx[:, 1]]          # (T, P, 3) robot j
    dx = b[..., 0] - a[..., 0]
    dy = b[..., 1] - a[..., 1]
    heading = a[..., 2]
    cos_h, sin_h = np.cos(heading), np.sin(heading)
    along_normal = dx * cos_h + dy * sin_h       # body y of robot i
    along_axis = dx * sin_h - dy * cos_h         # body x of robot i: (sin h, -cos h)
    r = np.hypot(dx, dy)
    theta = wrap_2pi(np.arctan2(along_normal, along_axis))
    phi = wrap_2pi(b[..., 2] - heading)
    return PairCoordinates(r, theta, phi, idx)


def one_pair(pose_i: ArrayLike, pose_j: ArrayLike) -> tuple[float, float, float]:
    """(r m, theta, phi rad) of robot j seen from robot i, for one frame (``pair_coordinates`` of one pair)."""
    c = pair_coordinates(np.stack([np.asarray(pose_i, dtype=float), np.asarray(pose_j, dtype=float)])[np.newaxis])
    return float(c.r[0, 0]), float(c.theta[0, 0]), float(c.phi[0, 0])


def place_pair(pose1: tuple[float, float, float], r: float, theta: float,
               phi: float) -> tuple[float, float, float]:
    """Pose (x, y, heading) of robot j with pair coordinates (r m, theta, phi rad) relative to robot i's ``pose1``.

    The inverse of ``pair_coordinates`` for one pair; the heading comes out in [-pi, pi).
    """
    angle = pose1[2] - math.pi / 2.0 + theta
    return (pose1[0] + r * math.cos(angle), pose1[1] + r * math.sin(angle), wrap_pi(pose1[2] + phi))


def pair_centres(poses: ArrayLike, pairs: ArrayLike | None = None) -> FloatArray:
    """Return the centre of mass (mean of the two body centres) of each pair: (T, P, 2), NaN if unseen."""
    arr = as_pose_array(poses)
    idx = _checked_pairs(pairs, arr.shape[1])
    return 0.5 * (arr[:, idx[:, 0], :2] + arr[:, idx[:, 1], :2])


def circular_mean(cos_sum: ArrayLike, sin_sum: ArrayLike, count: ArrayLike) -> FloatArray:
    """Circular mean in [0, 2 pi) from angle sums; NaN where count is 0 or the angles cancel out."""
    c = np.asarray(cos_sum, dtype=float)
    s = np.asarray(sin_sum, dtype=float)
    n = np.asarray(count, dtype=float)
    resultant = np.hypot(c, s)
    defined = (n > 0) & (resultant > 1e-9 * np.maximum(n, 1.0))
    return np.where(defined, wrap_2pi(np.arctan2(s, c)), np.nan)
