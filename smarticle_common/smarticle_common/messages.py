"""Planar poses to and from ROS messages (``geometry_msgs/Pose`` and ``PoseArray``), defined once.

Message classes only, no rclpy: the nodes, the demo and the bag readers share these.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from geometry_msgs.msg import Pose

from .poses import heading_quaternion, quaternion_heading


def pose_message(xyh: Any) -> Pose:
    """geometry_msgs/Pose of a planar pose (x m, y m, heading rad); a NaN heading gives a NaN orientation."""
    pose = Pose()
    x, y, heading = (float(v) for v in xyh)
    pose.position.x, pose.position.y = x, y
    _, _, pose.orientation.z, pose.orientation.w = heading_quaternion(heading)
    return pose


def planar_pose(pose: Any) -> tuple[float, float, float]:
    """(x, y, heading) of a geometry_msgs/Pose."""
    p, q = pose.position, pose.orientation
    return (p.x, p.y, quaternion_heading(q.x, q.y, q.z, q.w))


def planar_poses(msg: Any) -> np.ndarray:
    """(N, 3) x, y, heading of a PoseArray; a non-finite position or orientation gives a NaN row."""
    out = np.full((len(msg.poses), 3), np.nan)
    for k, pose in enumerate(msg.poses):
        row = planar_pose(pose)
        if all(math.isfinite(v) for v in row):
            out[k] = row
    return out
