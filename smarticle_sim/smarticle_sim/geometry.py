"""Planar geometry of smarticles: footprints as oriented rectangles and overlap tests.

Pair coordinates (r, theta, phi) and their inverse ``place_pair`` are ``smarticle_common.pairs``.

Conventions (``docs/sim_core.md``): a robot's pose is (x, y, heading) in the arena frame, where
heading is the angle of its body normal (body +y) from the arena x axis; the body x axis (joint 1 to
joint 2) then points at ``heading - pi/2``. Arm angles follow ``smarticle_common.gait``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from smarticle_common.facts import RobotSpec


class Rect(NamedTuple):
    """An oriented rectangle: centre, half extents along its own axes, angle of its first axis."""

    cx: float
    cy: float
    hx: float
    hy: float
    angle: float


def robot_rects(spec: RobotSpec, x: float, y: float, heading: float,
                alpha1: float, alpha2: float) -> tuple[Rect, Rect, Rect]:
    """Footprint of one robot as (body, arm 1, arm 2) rectangles in the arena frame."""
    yaw = heading - math.pi / 2.0
    ex = (math.cos(yaw), math.sin(yaw))
    half_w, half_l = spec.body_width / 2.0, spec.arm_length / 2.0
    body = Rect(x, y, half_w, spec.body_depth / 2.0, yaw)
    j1 = (x - ex[0] * half_w, y - ex[1] * half_w)
    j2 = (x + ex[0] * half_w, y + ex[1] * half_w)
    d1 = yaw + math.pi - alpha1          # arm 1 points along -x, tip toward +y for alpha1 > 0
    d2 = yaw + alpha2
    arm1 = Rect(j1[0] + half_l * math.cos(d1), j1[1] + half_l * math.sin(d1), half_l,
                spec.arm_thickness / 2.0, d1)
    arm2 = Rect(j2[0] + half_l * math.cos(d2), j2[1] + half_l * math.sin(d2), half_l,
                spec.arm_thickness / 2.0, d2)
    return body, arm1, arm2


def rect_corners(rect: Rect) -> np.ndarray:
    """The four corners of ``rect`` as a (4, 2) array."""
    c, s = math.cos(rect.angle), math.sin(rect.angle)
    u = np.array([c, s]) * rect.hx
    v = np.array([-s, c]) * rect.hy
    centre = np.array([rect.cx, rect.cy])
    return np.stack([centre + u + v, centre - u + v, centre - u - v, centre + u - v])


def rects_overlap(a: Rect, b: Rect, gap: float = 0.0) -> bool:
    """True if two oriented rectangles overlap or come closer than ``gap`` (separating-axis test)."""
    ca, cb = rect_corners(a), rect_corners(b)
    for angle in (a.angle, b.angle):
        axes = np.array([[math.cos(angle), math.sin(angle)], [-math.sin(angle), math.cos(angle)]])
        pa, pb = ca @ axes.T, cb @ axes.T
        separated = (pa.max(axis=0) + gap <= pb.min(axis=0)) | (pb.max(axis=0) + gap <= pa.min(axis=0))
        if separated.any():
            return False
    return True


def robots_overlap(first: tuple[Rect, ...], second: tuple[Rect, ...], gap: float = 0.0) -> bool:
    """True if any rectangle of one robot overlaps any rectangle of the other."""
    return any(rects_overlap(a, b, gap) for a in first for b in second)
