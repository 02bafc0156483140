"""The robot model on ROS from the sim bridge: /smarticle_<k>/robot_description and the TF it publishes.

Over DDS with two robots in lock-step: the probe reads each robot's latched description and the poses and
arm angles; the transforms the bridge builds from them (``robot_tf.transform_messages``, the function the
node calls every publish period) follow the robots and their arms. /tf itself is read where tf2_msgs is
installed (any ROS install); elsewhere that test is skipped and the bridge reports /tf off.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from smarticle_common import topics
from smarticle_common.facts import robot_preset
from smarticle_common.robot_model import urdf
from smarticle_common.robot_tf import TF_TOPIC, tf_message_class, transform_messages
from smarticle_sim.testing import SimWorld

pytestmark = pytest.mark.integration


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


def test_descriptions_and_frames_of_two_robots_follow_poses_and_arms(sim_world: SimWorld) -> None:
    spec = robot_preset('small')
    descriptions: dict[int, str] = {}
    String = topics.message_class(topics.spec_of('robot_description').type)
    latched = topics.qos_profile(topics.spec_of('robot_description').qos)
    for k in range(2):
        sim_world.probe.create_subscription(String, topics.topic('robot_description', k),
                                            lambda msg, k=k: descriptions.__setitem__(k, msg.data), latched)
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


def test_tf_from_the_bridge_matches_the_poses_and_arm_angles(sim_world: SimWorld) -> None:
    TFMessage = tf_message_class()
    if TFMessage is None:
        pytest.skip('tf2_msgs is not installed (it comes with a ROS install, not with PyPI): /tf is off here')
    received: dict[int, list[Any]] = {}

    def on_tf(msg: Any) -> None:
        for t in msg.transforms:
            received.setdefault(t.header.stamp.sec * 10**9 + t.header.stamp.nanosec, []).append(t)

    sim_world.probe.create_subscription(TFMessage, TF_TOPIC, on_tf, topics.qos_profile(topics.Qos.COMMAND))
    sim_world.start(scene='pair', joint_states=True, params={'start_at': 0.2})
    sim_world.step_to(2.0)
    sim_world.spin(0.5)
    spec = robot_preset('small')
    common = sorted(set(received) & set(sim_world.data.poses) & set(sim_world.joint_states(0))
                    & set(sim_world.joint_states(1)))
    assert len(common) >= 10, f'{len(received)} /tf samples, {len(common)} with poses and arm angles'
    for stamp in (common[0], common[-1]):
        arms = np.array([sim_world.joint_states(k)[stamp] for k in range(2)])
        check_frames(received[stamp], sim_world.data.poses[stamp], arms, spec.body_height / 2.0)
