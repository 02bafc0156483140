"""The tracker and glider monitor nodes in their own processes, and the camera pipeline end to end over DDS."""

from __future__ import annotations

import array
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from smarticle_common import topics
from smarticle_sim.camera import CameraConfig, OverheadCamera
from smarticle_bringup.sim_camera import sim_calibration
from smarticle_tracking.homography import save_calibration

from tests.helpers.glider_scenes import pair_scene, periods
from tests.helpers.ros import spin_until

pytestmark = pytest.mark.integration


def _deep_best_effort() -> Any:
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)


def _reliable() -> Any:
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


def _stamp_ns(header: Any) -> int:
    return header.stamp.sec * 10**9 + header.stamp.nanosec


def _pose_array(poses: np.ndarray, t: float) -> Any:
    from geometry_msgs.msg import PoseArray
    from smarticle_common.messages import pose_message

    msg = PoseArray()
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), round((t - int(t)) * 1e9)
    msg.header.frame_id = topics.ARENA_FRAME
    msg.poses = [pose_message(row) for row in poses]      # a NaN row goes out as the unseen pose
    return msg


def _xy(msg: Any) -> np.ndarray:
    """x, y, heading of every pose, as published (no unseen handling: the tests check the wire)."""
    return np.array([[p.position.x, p.position.y, 2 * math.atan2(p.orientation.z, p.orientation.w)]
                     for p in msg.poses])


def _unseen(msg: Any) -> np.ndarray:
    """Per robot: whether the pose is the contract's unseen pose (finite: RViz accepts the message)."""
    return np.array([p.position.z == topics.UNSEEN_Z and p.orientation.w == 1.0 and
                     np.all(np.isfinite([p.position.x, p.position.y, p.orientation.z])) for p in msg.poses])


def test_glider_monitor_reports_a_constructed_glider(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseArray
    from visualization_msgs.msg import Marker, MarkerArray

    monitor = nodes.start('glider_monitor', '--ros-args', '-p', 'publish_period:=0.0', '-p', 'min_periods:=3',
                          '-p', 'start_at:=0.0',
                          '-p', 'show_arms:=false')
    node = ros_node('glider_probe')
    reports: list[Any] = []
    markers: list[Any] = []
    node.create_subscription(DiagnosticArray, topics.topic('gliders'), reports.append, _reliable())
    node.create_subscription(MarkerArray, topics.topic('markers'), markers.append, _reliable())
    pub = node.create_publisher(PoseArray, topics.topic('poses'), topics.qos_profile(topics.Qos.SENSOR))
    assert spin_until(node, lambda: pub.get_subscription_count() >= 1 and
                      node.count_publishers(topics.topic('gliders')) >= 1, 20.0), nodes.output(monitor)
    times, poses = pair_scene(periods(6, 1, 5), phi=math.radians(175.0), velocity=(0.002, 0.0))   # 5 W / 100 T
    poses[:, 2] = np.nan                              # robot 2 is never seen
    for t, frame in zip(times, poses, strict=True):
        pub.publish(_pose_array(frame, float(t)))
        spin_until(node, lambda: False, 0.03)
    last_ns = round(float(times[-1]) * 1e9)
    for _ in range(20):      # best effort: repeat the last frame (same stamp) until its report is back
        if spin_until(node, lambda: any(_stamp_ns(r.header) == last_ns for r in reports), 0.5):
            break
        pub.publish(_pose_array(poses[-1], float(times[-1])))
    last = next(r for r in reversed(reports) if _stamp_ns(r.header) == last_ns)
    assert len(reports) >= len(times) // 2, nodes.output(monitor)
    assert [s.name for s in last.status] == ['pair 0-1']
    values = {kv.key: kv.value for kv in last.status[0].values}
    assert values['class'] == 'C1' and values['age_periods'] == '5' and values['is_glider'] == 'true'
    assert (values['label'], values['travels']) == ('C1 glider', 'true')
    assert float(values['travel_w']) == pytest.approx(0.002 * 4 * 1.6 / 0.054, abs=1e-3)
    assert last.status[0].message.startswith('C1 glider, bound 5 periods')
    early = next(r for r in reports if r.status)      # the first bound period: not yet a bound pair
    assert {kv.key: kv.value for kv in early.status[0].values}['label'] == 'bound'
    assert float(values['r']) == pytest.approx(0.08, abs=1e-6)
    assert float(values['phi_deg']) == pytest.approx(175.0, abs=0.1)
    assert all(not r.status for r in reports if _stamp_ns(r.header) < 1.6e9)   # period 0 is unbound
    final = markers[-1].markers
    assert final[0].action == Marker.DELETEALL
    assert sorted(m.id for m in final if m.ns == 'robots') == [0, 1]
    bond = [m for m in final if m.ns == 'gliders']
    assert len(bond) == 1 and bond[0].type == Marker.LINE_LIST and bond[0].header.frame_id == 'arena'
    assert monitor.poll() is None


def test_tracker_node_answers_every_frame_and_survives_bad_ones(nodes, ros_node, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from geometry_msgs.msg import PoseArray, PoseStamped
    from sensor_msgs.msg import Image

    tracker = nodes.start('tracker')
    lost = nodes.start('tracker', '--ros-args', '-r', '__node:=tracker_without_calibration',
                       '-r', '/smarticles/poses:=/lost/poses', '-r', '/smarticle_0/pose:=/lost/pose0',
                       '-p', 'tag_ids:=[0]', '-p', f'calibration_file:={tmp_path / "missing.yaml"}')
    node = ros_node('tracker_probe')
    got: dict[int, np.ndarray] = {}
    got_lost: list[Any] = []
    raw: dict[int, Any] = {}
    single: list[Any] = []
    def on_poses(msg: Any) -> None:
        got[_stamp_ns(msg.header)] = _xy(msg)
        raw[_stamp_ns(msg.header)] = msg
    node.create_subscription(PoseArray, topics.topic('poses'), on_poses, _deep_best_effort())
    node.create_subscription(PoseArray, '/lost/poses', got_lost.append, _deep_best_effort())
    node.create_subscription(PoseStamped, topics.topic('pose', 2), single.append, _deep_best_effort())
    pub = node.create_publisher(Image, topics.topic('image_raw'), _reliable())
    assert spin_until(node, lambda: pub.get_subscription_count() >= 2 and
                      node.count_publishers(topics.topic('poses')) >= 1, 20.0), nodes.output(tracker)
    spin_until(node, lambda: False, 0.5)
    camera = OverheadCamera(CameraConfig())
    truth = np.array([[0.0, 0.0, 0.3], [0.1, 0.0, 2.0], [-0.1, 0.05, -1.0], [0.0, 0.12, 1.0],
                      [0.1, -0.1, 0.0], [-0.1, -0.1, 3.0], [0.2, 0.1, -2.5]])
    frames = [('good', camera.render(truth), 'mono8'),
              ('empty', camera.render(np.full((1, 3), np.nan)), 'mono8'),
              ('16bit', np.zeros((1080, 1920 * 2), dtype=np.uint8), '16UC1'),
              ('small', np.zeros((480, 640), dtype=np.uint8), 'mono8')]
    for n, (_, frame, encoding) in enumerate(frames):
        msg = Image(height=frame.shape[0], width=frame.shape[1] // (2 if encoding == '16UC1' else 1),
                    encoding=encoding, step=frame.shape[1], data=array.array('B', frame.tobytes()))
        msg.header.stamp.sec = n + 1
        pub.publish(msg)
        spin_until(node, lambda: False, 0.2)
    assert spin_until(node, lambda: len(got) == 4 and len(got_lost) >= 1, 20.0), nodes.output(tracker)
    good = got[10**9]
    assert np.max(np.hypot(*(good[:, :2] - truth[:, :2]).T)) < 1e-3
    assert np.allclose(np.cos(good[:, 2] - truth[:, 2]), 1.0, atol=1e-3)
    assert not np.any(_unseen(raw[10**9]))
    for stamp in (2, 3, 4):
        assert np.all(_unseen(raw[stamp * 10**9])), stamp
    assert all(np.all(_unseen(m)) for m in got_lost)
    assert single and single[0].pose.position.x == pytest.approx(-0.1, abs=1e-3)
    log = nodes.output(tracker)
    assert "unsupported image encoding '16UC1'" in log and 'recalibrate' in log
    assert 'does not exist' in nodes.output(lost)
    assert tracker.poll() is None and lost.poll() is None


def test_sim_camera_tracker_and_monitor_find_the_glider(nodes, ros_node, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """sim_bridge (pair scene, camera on) -> tracker -> glider_monitor, against the sim's ground truth."""
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseArray

    # Lock-step runs faster than real time and the image topic keeps the last 2 frames, so the tracker must
    # keep up with the sim: 640x480 at 5 frames per sim second leaves it room on a loaded 2-core machine.
    width, height = 640, 480
    # 0.3 m across the 480 px side: tags span 29 px (at 0.6 m, 14 px tags are missed in some poses)
    calibration = save_calibration(tmp_path / 'cal.yaml', sim_calibration(width, height, view=0.3))
    node = ros_node('pipeline_probe')
    truth: dict[int, np.ndarray] = {}
    tracked: dict[int, np.ndarray] = {}
    reports: list[Any] = []
    node.create_subscription(PoseArray, '/ground_truth/poses',
                             lambda m: truth.__setitem__(_stamp_ns(m.header), _xy(m)), _deep_best_effort())
    node.create_subscription(PoseArray, topics.topic('poses'),
                             lambda m: tracked.__setitem__(_stamp_ns(m.header), _xy(m)), _deep_best_effort())
    node.create_subscription(DiagnosticArray, topics.topic('gliders'), reports.append, _reliable())
    tracker = nodes.start('tracker', '--ros-args', '-p', f'calibration_file:={calibration}', '-p', 'tag_ids:=[0, 1]')
    monitor = nodes.start('glider_monitor', '--ros-args', '-p', 'use_sim_time:=true', '-p', 'publish_period:=0.0')
    assert spin_until(node, lambda: node.count_subscribers(topics.topic('image_raw')) >= 1
                      and node.count_subscribers(topics.topic('poses')) >= 2
                      and node.count_publishers(topics.topic('gliders')) >= 1, 20.0), nodes.output(tracker)
    for k in range(2):
        nodes.start('gait', '--ros-args', '-p', f'robot_id:={k}', '-p', 'lockstep:=true', '-p', 'use_sim_time:=true')
    bridge = nodes.start('sim_bridge', '--ros-args', '-p', 'scene:=pair', '-p', 'duration:=6.0',
                         '-p', 'camera_rate:=5.0', '-p', f'camera_width:={width}', '-p', f'camera_height:={height}',
                         '-p', 'camera_view:=0.3',
                         '-p', 'wait_for_subscribers:=1', '-p', 'wait_for_camera_subscribers:=1',
                         '-r', '/smarticles/poses:=/ground_truth/poses')
    assert spin_until(node, lambda: bridge.poll() is not None and len(reports) >= 5, 60.0), nodes.output(bridge)
    assert bridge.returncode == 0, nodes.output(bridge)
    spin_until(node, lambda: False, 1.0)
    assert len(tracked) >= 10, nodes.output(tracker)
    common = sorted(set(tracked) & set(truth))
    assert len(common) >= 10
    errors = np.concatenate([np.hypot(*(tracked[s][:, :2] - truth[s][:, :2]).T) for s in common])
    assert np.all(np.isfinite(errors)) and np.median(errors) < 1e-3 and np.max(errors) < 3e-3
    assert all(r.status for r in reports), 'the pair starts bound (r = 1.3 BL) and stays bound'
    checked = [r for r in reports if _stamp_ns(r.header) in truth]
    assert len(checked) >= 5
    for report in checked:
        assert [s.name for s in report.status] == ['pair 0-1']
        values = {kv.key: kv.value for kv in report.status[0].values}
        gt = truth[_stamp_ns(report.header)]
        r_true = math.hypot(*(gt[1, :2] - gt[0, :2]))
        assert float(values['r']) == pytest.approx(r_true, abs=2e-3)
        assert values['class'] == 'C1'
    assert tracker.poll() is None and monitor.poll() is None


def test_tracker_latches_the_robot_descriptions_and_says_whether_tf_is_on(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseArray
    from sensor_msgs.msg import Image
    from smarticle_common.facts import robot_preset
    from smarticle_common.robot_model import urdf
    from smarticle_common.robot_tf import TF_TOPIC, tf_message_class

    tracker = nodes.start('tracker', '--ros-args', '-p', 'tag_ids:=[0, 1]', '-p', 'preset:=feedback')
    node = ros_node('tracker_model_probe')
    String = topics.message_class(topics.spec_of('robot_description').type)
    latched = topics.qos_profile(topics.spec_of('robot_description').qos)
    descriptions: dict[int, str] = {}
    for k in range(2):
        node.create_subscription(String, topics.topic('robot_description', k),
                                 lambda msg, k=k: descriptions.__setitem__(k, msg.data), latched)
    status: dict[str, str] = {}
    node.create_subscription(DiagnosticArray, '/diagnostics', lambda msg: status.update(
        {v.key: v.value for s in msg.status if s.name == 'tracker' for v in s.values}), _reliable())
    TFMessage = tf_message_class()
    tf: list[Any] = []
    if TFMessage is not None:
        node.create_subscription(TFMessage, TF_TOPIC, tf.append, _reliable())
    poses: list[Any] = []
    node.create_subscription(PoseArray, topics.topic('poses'), poses.append, _deep_best_effort())
    assert spin_until(node, lambda: len(descriptions) == 2 and 'tf' in status, 20.0), nodes.output(tracker)
    assert descriptions[0] == descriptions[1] == urdf(robot_preset('feedback'))
    assert status['tf'] == ('on' if TFMessage is not None else 'off (tf2_msgs not installed)')
    log = nodes.output(tracker)
    assert log.count('/tf is off') == (0 if TFMessage is not None else 1), log
    if TFMessage is None:   # the rest checks the /tf of a tracked frame
        pytest.skip('tf2_msgs is not installed (a ROS install has it; the set-up generates it): /tf is off')
    pub = node.create_publisher(Image, topics.topic('image_raw'), _reliable())
    assert spin_until(node, lambda: pub.get_subscription_count() >= 1 and node.count_subscribers(TF_TOPIC) >= 1
                      and node.count_publishers(TF_TOPIC) >= 1, 20.0)
    truth = np.array([[0.05, -0.02, 0.7], [-0.1, 0.08, -2.0]])
    frame = OverheadCamera(CameraConfig()).render(truth)
    msg = Image(height=frame.shape[0], width=frame.shape[1], encoding='mono8', step=frame.shape[1],
                data=array.array('B', frame.tobytes()))
    msg.header.stamp.sec = 1
    pub.publish(msg)
    assert spin_until(node, lambda: bool(tf), 20.0), nodes.output(tracker)
    bodies = {t.child_frame_id: t for t in tf[0].transforms if t.child_frame_id.endswith('/body')}
    for k, (x, y, _) in enumerate(truth):
        t = bodies[f'smarticle_{k}/body'].transform.translation
        assert math.hypot(t.x - x, t.y - y) < 1e-3
