"""Planar poses to and from ROS messages (``geometry_msgs/Pose`` and ``PoseArray``), and stamps to and from
integer nanoseconds, defined once.

Message classes only, no rclpy: the nodes, the demo and the bag readers share these. An unseen robot
(a NaN row of a pose array) goes on the wire as the contract's unseen pose (``topics.UNSEEN_Z``: finite,
so RViz accepts it) and comes back as a NaN row.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Pose

from .poses import heading_quaternion, quaternion_heading
from .topics import UNSEEN_Z


def stamp_ns(stamp: Any) -> int:
    """Integer nanoseconds of a ``builtin_interfaces/Time`` (as rclpy's ``Time.from_msg``, without its objects)."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def stamp_msg(ns: int) -> TimeMsg:
    """The ``builtin_interfaces/Time`` of ``ns`` >= 0 integer nanoseconds (as rclpy's ``Time.to_msg``)."""
    sec, nanosec = divmod(ns, 1_000_000_000)
    return TimeMsg(sec=sec, nanosec=nanosec)


def unseen_pose() -> Pose:
    """The pose of a robot not seen: position (0, 0, UNSEEN_Z), identity orientation."""
    pose = Pose()
    pose.position.z = UNSEEN_Z
    pose.orientation.w = 1.0
    return pose


def is_unseen(pose: Any) -> bool:
    """True if a geometry_msgs/Pose is the unseen pose (or, from an old producer, has a non-finite value)."""
    p, q = pose.position, pose.orientation
    if p.z == UNSEEN_Z:
        return True
    return not all(math.isfinite(v) for v in (p.x, p.y, p.z, q.x, q.y, q.z, q.w))


def pose_message(xyh: Any) -> Pose:
    """geometry_msgs/Pose of a planar pose (x m, y m, heading rad); any non-finite value gives the unseen pose."""
    x, y, heading = (float(v) for v in xyh)
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(heading)):
        return unseen_pose()
    pose = Pose()
    pose.position.x, pose.position.y = x, y
    _, _, pose.orientation.z, pose.orientation.w = heading_quaternion(heading)
    return pose


def planar_pose(pose: Any) -> tuple[float, float, float]:
    """(x, y, heading) of a geometry_msgs/Pose; NaN, NaN, NaN for the unseen pose."""
    if is_unseen(pose):
        return (math.nan, math.nan, math.nan)
    p, q = pose.position, pose.orientation
    return (p.x, p.y, quaternion_heading(q.x, q.y, q.z, q.w))


def planar_poses(msg: Any) -> np.ndarray:
    """(N, 3) x, y, heading of a PoseArray; an unseen robot gives a NaN row."""
    out = np.full((len(msg.poses), 3), np.nan)
    for k, pose in enumerate(msg.poses):
        out[k] = planar_pose(pose)
    return out
