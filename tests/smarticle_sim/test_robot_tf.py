"""The robot model on ROS from the sim bridge: /smarticle_<k>/robot_description and the TF it publishes.

Over DDS with two robots in lock-step. The first test reads each robot's latched description and checks the
transforms ``robot_tf.transform_messages`` builds from the poses and arm angles (the function the node calls
every publish period). The second reads /tf itself, as a Jazzy node would: the bridge's /tf publisher has
Jazzy's tf2_msgs/msg/TFMessage type and type hash, and every sample's frames (arena -> smarticle_<k>/body ->
arm links) sit where the poses and joint states of the same stamp and the joints of the received description
put them, and move with them. tf2_msgs comes with a ROS install, or is generated into .venv at set-up
(tools/ros_interfaces); where neither happened the /tf test is skipped with the set-up's reason.
"""

from __future__ import annotations

import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from smarticle_common import topics
from smarticle_common.facts import robot_preset
from smarticle_common.robot_model import JOINTS, urdf
from smarticle_common.robot_tf import TF_TOPIC, tf_message_class, transform_messages
from smarticle_sim.testing import SimWorld

pytestmark = pytest.mark.integration

#: RIHS01 type hash of ROS 2 Jazzy's tf2_msgs/msg/TFMessage (its type description's hash, as in Jazzy's
#: share/tf2_msgs/msg/TFMessage.json); the test also checks it against rosbags' own Jazzy type store.
JAZZY_TF_TYPE_HASH = 'RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087'


def _yaw(q: Any) -> float:
    return 2.0 * math.atan2(q.z, q.w)


def _angle_gap(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2.0 * math.pi))


def _stamp_msg(stamp_ns: int) -> Any:
    msg = topics.message_class('builtin_interfaces/msg/Time')()
    msg.sec, msg.nanosec = divmod(stamp_ns, 10**9)
    return msg


def check_frames(transforms: list[Any], poses: np.ndarray, arms: np.ndarray, body_z: float) -> None:
    """Each robot's three transforms sit where its pose and arm angles put them."""
    by_child = {t.child_frame_id: t for t in transforms}
    assert len(by_child) == 3 * len(poses)
    for k, ((x, y, heading), (alpha1, alpha2)) in enumerate(zip(poses, arms, strict=True)):
        body = by_child[f'smarticle_{k}/body']
        assert body.header.frame_id == topics.ARENA_FRAME
        t = body.transform.translation
        assert (t.x, t.y, t.z) == pytest.approx((x, y, body_z), abs=1e-9)
        assert _angle_gap(_yaw(body.transform.rotation), heading - math.pi / 2.0) < 1e-6
        arm1, arm2 = by_child[f'smarticle_{k}/arm1_link'], by_child[f'smarticle_{k}/arm2_link']
        assert arm1.header.frame_id == arm2.header.frame_id == f'smarticle_{k}/body'
        assert _angle_gap(_yaw(arm1.transform.rotation), math.pi - alpha1) < 1e-6
        assert _angle_gap(_yaw(arm2.transform.rotation), alpha2) < 1e-6
        assert arm1.transform.translation.x < 0.0 < arm2.transform.translation.x


def subscribe_descriptions(sim_world: SimWorld, robots: int) -> dict[int, str]:
    """Subscribe the probe to each robot's latched ``robot_description``; the dict fills as they arrive."""
    descriptions: dict[int, str] = {}
    String = topics.message_class(topics.spec_of('robot_description').type)
    latched = topics.qos_profile(topics.spec_of('robot_description').qos)
    for k in range(robots):
        sim_world.probe.create_subscription(String, topics.topic('robot_description', k),
                                            lambda msg, k=k: descriptions.__setitem__(k, msg.data), latched)
    return descriptions


def test_descriptions_and_frames_of_two_robots_follow_poses_and_arms(sim_world: SimWorld) -> None:
    spec = robot_preset('small')
    descriptions = subscribe_descriptions(sim_world, 2)
    sim_world.start(scene='pair', joint_states=True, params={'start_at': 0.2})
    sim_world.step_to(2.0)
    assert sim_world.spin_until(lambda: len(descriptions) == 2, 10.0), f'descriptions received: {list(descriptions)}'
    assert descriptions[0] == descriptions[1] == urdf(spec)
    assert sim_world.data.bridge.get('tf') == ('on' if tf_message_class() else 'off (tf2_msgs not installed)')

    stamps = sorted(set(sim_world.data.poses) & set(sim_world.joint_states(0)) & set(sim_world.joint_states(1)))
    assert len(stamps) >= 20, 'too few samples with poses and both robots\' arm angles'
    samples = []
    for stamp in (stamps[0], stamps[-1]):
        poses = sim_world.data.poses[stamp]
        arms = np.array([sim_world.joint_states(k)[stamp] for k in range(2)])
        transforms = transform_messages(poses, arms, spec, _stamp_msg(stamp))
        check_frames(transforms, poses, arms, spec.body_height / 2.0)
        assert all(t.header.stamp.sec * 10**9 + t.header.stamp.nanosec == stamp for t in transforms)
        samples.append((poses, arms, transforms))
    (poses0, arms0, first), (poses1, arms1, last) = samples
    # the gait moved both robots and their arms between the first and the last sample, and the frames with them
    assert np.abs(arms1 - arms0).max(axis=1).min() > math.radians(10.0)
    assert np.all(np.hypot(*(poses1[:, :2] - poses0[:, :2]).T) > 1e-4)
    moved = [math.hypot(a.transform.translation.x - b.transform.translation.x,
                        a.transform.translation.y - b.transform.translation.y)
             for a, b in zip(first, last, strict=True) if a.child_frame_id.endswith('/body')]
    assert min(moved) > 1e-4


def joints_of(description: str) -> dict[str, tuple[str, str, tuple[float, float, float], float, float]]:
    """Joints of a URDF: name -> (parent link, child link, origin xyz m, origin yaw rad, z of the axis)."""
    out = {}
    for joint in ET.fromstring(description).iter('joint'):
        origin, axis = joint.find('origin'), joint.find('axis')
        assert origin is not None and axis is not None and joint.get('type') == 'revolute'
        xyz = tuple(float(v) for v in origin.get('xyz', '0 0 0').split())
        roll, pitch, yaw = (float(v) for v in origin.get('rpy', '0 0 0').split())
        axis_xyz = [float(v) for v in axis.get('xyz', '').split()]
        assert roll == pitch == 0.0 and axis_xyz[:2] == [0.0, 0.0] and abs(axis_xyz[2]) == 1.0
        parent, child = joint.find('parent'), joint.find('child')
        assert parent is not None and child is not None
        out[joint.get('name', '')] = (parent.get('link', ''), child.get('link', ''), (xyz[0], xyz[1], xyz[2]),
                                      yaw, axis_xyz[2])
    return out


def check_joints(transforms: list[Any], description: str, robot: int, alphas: np.ndarray) -> None:
    """Robot ``robot``'s arm frames are its description's joints turned by the arm angles (what RViz draws
    with the TF prefix smarticle_<k>): same parent, origin, and yaw = origin yaw + axis * angle."""
    by_child = {t.child_frame_id: t for t in transforms}
    joints = joints_of(description)
    assert sorted(joints) == sorted(name for name, _ in JOINTS)
    for (name, _), alpha in zip(JOINTS, alphas, strict=True):
        parent, child, xyz, yaw, axis_z = joints[name]
        t = by_child[f'smarticle_{robot}/{child}']
        assert t.header.frame_id == f'smarticle_{robot}/{parent}'
        v = t.transform.translation
        assert (v.x, v.y, v.z) == pytest.approx(xyz, abs=1e-9)
        assert _angle_gap(_yaw(t.transform.rotation), yaw + axis_z * alpha) < 1e-6


def _unavailable_reason() -> str:
    """Why tf2_msgs does not import here: the set-up's one line when its tf2_msgs build failed."""
    marker = Path(sys.prefix) / '.tf2_msgs-unavailable'
    if marker.exists():
        return marker.read_text().strip()
    return 'tf2_msgs is not installed (a ROS install has it; the set-up, tools/bootstrap.sh, generates it)'


def test_tf_from_the_bridge_matches_the_poses_and_arm_angles(sim_world: SimWorld) -> None:
    TFMessage = tf_message_class()
    if TFMessage is None:
        pytest.skip(_unavailable_reason())
    from rosbags.typesys import Stores, get_typestore

    received: dict[int, list[Any]] = {}

    def on_tf(msg: Any) -> None:
        for t in msg.transforms:
            received.setdefault(t.header.stamp.sec * 10**9 + t.header.stamp.nanosec, []).append(t)

    descriptions = subscribe_descriptions(sim_world, 2)
    sim_world.probe.create_subscription(TFMessage, TF_TOPIC, on_tf, topics.qos_profile(topics.Qos.COMMAND))
    sim_world.start(scene='pair', joint_states=True, params={'start_at': 0.2})
    sim_world.step_to(2.0)
    sim_world.spin(0.5)
    assert sim_world.spin_until(lambda: len(descriptions) == 2, 10.0), f'descriptions received: {list(descriptions)}'

    # the type on the wire is Jazzy's: a Jazzy node (RViz, tf2_ros, ros2 bag) matches the bridge's /tf
    publishers = sim_world.probe.get_publishers_info_by_topic(TF_TOPIC)
    assert [(p.node_name, p.topic_type) for p in publishers] == [('sim_bridge', 'tf2_msgs/msg/TFMessage')]
    assert str(publishers[0].topic_type_hash) == JAZZY_TF_TYPE_HASH
    assert get_typestore(Stores.ROS2_JAZZY).hash_rihs01('tf2_msgs/msg/TFMessage') == JAZZY_TF_TYPE_HASH

    spec = robot_preset('small')
    common = sorted(set(received) & set(sim_world.data.poses) & set(sim_world.joint_states(0))
                    & set(sim_world.joint_states(1)))
    assert len(common) >= 20, f'{len(received)} /tf samples, {len(common)} with poses and arm angles'
    for stamp in common:
        poses = sim_world.data.poses[stamp]
        arms = np.array([sim_world.joint_states(k)[stamp] for k in range(2)])
        check_frames(received[stamp], poses, arms, spec.body_height / 2.0)
        for k in range(2):
            check_joints(received[stamp], descriptions[k], k, arms[k])

    # over the run the gait moved both robots and turned every arm, and the frames with them
    frames = [{t.child_frame_id: t.transform for t in received[stamp]} for stamp in common]
    for k in range(2):
        x0, y0 = frames[0][f'smarticle_{k}/body'].translation.x, frames[0][f'smarticle_{k}/body'].translation.y
        assert max(math.hypot(f[f'smarticle_{k}/body'].translation.x - x0,
                              f[f'smarticle_{k}/body'].translation.y - y0) for f in frames) > 1e-4
        for _, link in JOINTS:
            yaw0 = _yaw(frames[0][f'smarticle_{k}/{link}'].rotation)
            turn = max(_angle_gap(_yaw(f[f'smarticle_{k}/{link}'].rotation), yaw0) for f in frames)
            assert turn > math.radians(30.0), f'smarticle_{k}/{link} turned at most {math.degrees(turn):.1f} deg'
