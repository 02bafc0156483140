"""Planar pose conversions, defined once: heading <-> quaternion, and a Bullet body's heading and tilt.

A planar pose is ``(x, y, heading)``: the body centre (m) and the angle (rad) of the body normal (the
robot's heading, ``docs/gliders.md``). On the wire (``geometry_msgs/Pose``) the heading is the yaw of the
orientation quaternion. In PyBullet a robot's base frame has its x axis along the body (joint 1 to
joint 2), so the heading is the base yaw plus pi/2.
"""

from __future__ import annotations

import math

import numpy as np

_HALF_PI = math.pi / 2.0
_TWO_PI = 2.0 * math.pi


def heading_quaternion(heading: float) -> tuple[float, float, float, float]:
    """The (x, y, z, w) quaternion of a rotation by ``heading`` rad about z."""
    return (0.0, 0.0, math.sin(heading / 2.0), math.cos(heading / 2.0))


def quaternion_heading(qx: float, qy: float, qz: float, qw: float) -> float:
    """The yaw (rotation about z, rad, [-pi, pi]) of an (x, y, z, w) quaternion."""
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def body_heading(qx: float, qy: float, qz: float, qw: float) -> float:
    """Heading of the body normal in [-pi, pi) from a robot base's (x, y, z, w) quaternion."""
    return (quaternion_heading(qx, qy, qz, qw) + _HALF_PI + math.pi) % _TWO_PI - math.pi


def body_headings_and_tilts(quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Headings of the body normals in [-pi, pi) and tilts from vertical (rad) from (N, 4) xyzw quaternions."""
    qx, qy, qz, qw = quat.T
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    heading = (yaw + _HALF_PI + math.pi) % _TWO_PI - math.pi
    cos_tilt = np.clip(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0)
    return heading, np.arccos(cos_tilt)
