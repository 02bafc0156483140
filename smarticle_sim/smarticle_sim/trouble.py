"""Trouble detection: turn a world state into a SimTrouble error instead of simulating garbage."""

from __future__ import annotations

import math

import numpy as np

from .settings import PhysicsConfig
from .errors import SimTrouble


def check_state(time: float, positions: np.ndarray, tilt: np.ndarray, speed: np.ndarray,
                arm_angles: np.ndarray, physics: PhysicsConfig, body_height: float) -> None:
    """Raise SimTrouble for the first robot with NaN/inf state, off the plate, flipped or too fast.

    positions (N, 3) body centres in m; tilt (N,) rad; speed (N,) m/s; arm_angles (N, 2) rad.
    """
    finite = np.isfinite(positions).all(axis=1) & np.isfinite(tilt) & np.isfinite(speed) \
        & np.isfinite(arm_angles).all(axis=1)
    if not finite.all():
        k = int(np.flatnonzero(~finite)[0])
        values = np.concatenate([positions[k], arm_angles[k], [tilt[k], speed[k]]])
        bad = float(values[~np.isfinite(values)][0])
        raise SimTrouble(k, time, 'state (position, arm angle, tilt or speed)', bad, 'not finite')
    half = physics.plate_size / 2.0
    off = np.abs(positions[:, :2]).max(axis=1)
    if (off > half).any():
        k = int(np.argmax(off))
        raise SimTrouble(k, time, 'distance of the body centre from the plate axes (m)', float(off[k]),
                         f'the plate ends at {half} m: the body left the plate', physical=True)
    z = positions[:, 2]
    low, high = -body_height, 2.0 * body_height
    outside = (z < low) | (z > high)
    if outside.any():
        k = int(np.flatnonzero(outside)[0])
        raise SimTrouble(k, time, 'body height z (m)', float(z[k]), f'allowed {low:.3f} .. {high:.3f} m')
    if (tilt > physics.max_tilt).any():
        k = int(np.argmax(tilt))
        raise SimTrouble(k, time, 'body tilt (deg)', math.degrees(float(tilt[k])),
                         f'limit {math.degrees(physics.max_tilt):g} deg: the robot tipped over')
    if (speed > physics.max_speed).any():
        k = int(np.argmax(speed))
        raise SimTrouble(k, time, 'body speed (m/s)', float(speed[k]), f'limit {physics.max_speed:g} m/s')


def check_penetration(time: float, robot: int, depth: float, physics: PhysicsConfig, deep_checks: int = 0) -> int:
    """Count a trouble check's deepest contact overlap; raise SimTrouble when it is tunnelling.

    ``deep_checks`` is the number of checks in a row so far with an overlap beyond
    ``physics.max_penetration``; the updated count is returned for the next call. A non-finite depth, or
    an overlap that has lasted ``physics.penetration_checks`` checks (a one-check spike that the solver
    pushes out is not a tunnel), raises SimTrouble naming ``robot``.
    """
    deep_checks = deep_checks + 1 if depth > physics.max_penetration else 0
    if not math.isfinite(depth) or deep_checks >= physics.penetration_checks:
        held = f' for {physics.penetration_checks} checks in a row' if physics.penetration_checks > 1 else ''
        raise SimTrouble(robot, time, 'contact penetration depth (m)', depth,
                         f'limit {physics.max_penetration:g} m{held}: bodies are tunnelling')
    return deep_checks
