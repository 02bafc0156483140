"""Quantities that reports, status rows and the physics study share, each defined once (no statistics, no
store): the quadrants of a pair start's theta and the antiparallel band of its phi."""

from __future__ import annotations


def theta_quadrants(theta_deg: float) -> str | None:
    """The pair of quadrants a P4 start's theta (deg, any turn) lies in: '1, 4' in front of robot 1
    (-90 < theta < 90), '2, 3' behind it (90 < theta < 270), None on the line between (theta 90 or 270)."""
    theta = float(theta_deg) % 360.0
    if theta in (90.0, 270.0):
        return None
    return '1, 4' if theta < 90.0 or theta > 270.0 else '2, 3'


def antiparallel_band(phi_deg: float) -> bool:
    """True when a P4 start's phi (deg, any turn) is in the antiparallel band 90 <= phi <= 270."""
    return 90.0 <= float(phi_deg) % 360.0 <= 270.0
