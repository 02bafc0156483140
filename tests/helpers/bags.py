"""Sample messages and bags for the smarticle_bags tests (CDR made by the independent rosbags serializer)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rosbags.typesys import Stores, get_typestore

from smarticle_bags.writer import BagWriter, WriterOptions

STORE = get_typestore(Stores.ROS2_JAZZY)

T0 = 1_700_000_000_000_000_000
POSES = '/smarticles/poses'
JOINTS = '/smarticle_0/joint_states'


def _header(i: int, frame: str = '') -> object:
    """Return a rosbags std_msgs/Header stamped ``i`` seconds."""
    types = STORE.types
    return types['std_msgs/msg/Header'](stamp=types['builtin_interfaces/msg/Time'](sec=i, nanosec=0),
                                        frame_id=frame)


def pose_array(i: int, robots: int = 3) -> bytes:
    """Return a CDR PoseArray at step ``i``: robot k at (k + i/100, -k, heading k*0.5 rad)."""
    types = STORE.types
    poses = [types['geometry_msgs/msg/Pose'](
        position=types['geometry_msgs/msg/Point'](x=k + i / 100, y=-float(k), z=0.0),
        orientation=types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(k * 0.25),
                                                          w=math.cos(k * 0.25)))
        for k in range(robots)]
    msg = types['geometry_msgs/msg/PoseArray'](header=_header(i, 'arena'), poses=poses)
    return bytes(STORE.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray'))


def joint_state(i: int) -> bytes:
    """Return a CDR JointState of arms arm1, arm2 at step ``i``."""
    msg = STORE.types['sensor_msgs/msg/JointState'](
        header=_header(i), name=['arm1', 'arm2'], position=np.array([0.01 * i, -0.01 * i]),
        velocity=np.array([1.0, -1.0]), effort=np.array([], dtype=np.float64))
    return bytes(STORE.serialize_cdr(msg, 'sensor_msgs/msg/JointState'))


def make_bag(folder: Path, count: int = 50, options: WriterOptions | None = None,
             step: int = 10_000_000) -> dict[str, list[tuple[int, bytes]]]:
    """Write a bag of ``count`` poses and joint states (``step`` ns apart); return what was written."""
    written: dict[str, list[tuple[int, bytes]]] = {POSES: [], JOINTS: []}
    with BagWriter(folder, options or WriterOptions(chunk_size=2000)) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        writer.add_topic(JOINTS, 'sensor_msgs/msg/JointState')
        for i in range(count):
            for topic, data in ((POSES, pose_array(i)), (JOINTS, joint_state(i))):
                t = T0 + i * step + (1 if topic == JOINTS else 0)
                writer.write(topic, data, t)
                written[topic].append((t, data))
    return written


def make_sim_bag(folder: Path, seconds: float, step: float = 0.05) -> int:
    """Write a bag of poses as a recorder with use_sim_time does (log times from 0, the time base stated);
    return its message count."""
    from smarticle_bags.timebase import TimeBase, custom_data

    count = round(seconds / step) + 1
    with BagWriter(folder, WriterOptions(chunk_size=4000), custom_data=custom_data(TimeBase.SIM)) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        for i in range(count):
            writer.write(POSES, pose_array(i), round(i * step * 1_000_000_000))
    return count
