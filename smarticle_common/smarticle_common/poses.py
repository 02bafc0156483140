"""Planar pose conversions, defined once: heading <-> quaternion, a Bullet body's heading and tilt, tag corners.

A planar pose is ``(x, y, heading)``: the body centre (m) and the angle (rad) of the body normal (the
robot's heading, ``docs/gliders.md``). On the wire (``geometry_msgs/Pose``) the heading is the yaw of the
orientation quaternion. In PyBullet a robot's base frame has its x axis along the body (joint 1 to
joint 2), so the heading is the base yaw plus pi/2. Each robot's tag is centred on its body, its top
edge toward the body normal: ``tag_corners`` and ``poses_from_corners`` go between the two (the sim's
camera draws tags with the first, the tracker reads poses with the second).
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


def quaternion_headings(qx: np.ndarray, qy: np.ndarray, qz: np.ndarray, qw: np.ndarray) -> np.ndarray:
    """``quaternion_heading`` over arrays of quaternion components."""
    heading: np.ndarray = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return heading


def body_heading(qx: float, qy: float, qz: float, qw: float) -> float:
    """Heading of the body normal in [-pi, pi) from a robot base's (x, y, z, w) quaternion."""
    return (quaternion_heading(qx, qy, qz, qw) + _HALF_PI + math.pi) % _TWO_PI - math.pi


def body_headings_and_tilts(quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Headings of the body normals in [-pi, pi) and tilts from vertical (rad) from (N, 4) xyzw quaternions."""
    qx, qy, qz, qw = quat.T
    yaw = quaternion_headings(qx, qy, qz, qw)
    heading = (yaw + _HALF_PI + math.pi) % _TWO_PI - math.pi
    cos_tilt = np.clip(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0)
    return heading, np.arccos(cos_tilt)


def tag_corners(poses: np.ndarray, tag_size: float) -> np.ndarray:
    """Arena corners (N, 4, 2) of tags on robots at ``poses`` (N, 3), in ArUco order (TL, TR, BR, BL)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    half = tag_size / 2.0
    heading = poses[:, 2]
    ex = np.stack([np.sin(heading), -np.cos(heading)], axis=1)     # body x axis = tag right
    ey = np.stack([np.cos(heading), np.sin(heading)], axis=1)      # body normal = tag up
    signs = np.array([[-1.0, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]])
    return (poses[:, None, :2] + half * (signs[None, :, 0:1] * ex[:, None, :]
                                         + signs[None, :, 1:2] * ey[:, None, :]))


def poses_from_corners(corners: np.ndarray) -> np.ndarray:
    """Planar poses (M, 3) from arena tag corners (M, 4, 2): centre = mean, heading from the edges."""
    c = np.asarray(corners, dtype=float).reshape(-1, 4, 2)
    tl, tr, br, bl = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
    up = (tl - bl) + (tr - br)
    right = (tr - tl) + (br - bl)
    normal_from_right = np.stack([-right[:, 1], right[:, 0]], axis=1)
    n = (up / np.linalg.norm(up, axis=1, keepdims=True)
         + normal_from_right / np.linalg.norm(normal_from_right, axis=1, keepdims=True))
    heading = np.arctan2(n[:, 1], n[:, 0])
    return np.column_stack([c.mean(axis=1), heading])
