"""ROS node `tracker`: overhead camera frames -> /smarticles/poses and /smarticle_<k>/pose.

Subscribes ``/overhead_camera/image_raw`` and ``/overhead_camera/camera_info``; every frame gives
exactly one PoseArray (index = robot id) stamped with the frame's stamp: a robot whose tag was not
found, or was rejected, gets the unseen pose (``topics.UNSEEN_Z``: finite, so RViz accepts the message;
never an old pose), and so does every robot of a frame the tracker cannot use (unsupported encoding,
wrong size for the calibration, no calibration). Problems are logged (throttled) and counted on
/diagnostics; the node keeps running. It also latches ``/smarticle_<k>/robot_description`` (the URDF of
``preset``) and, where tf2_msgs is installed, publishes each frame's TF (arena -> ``smarticle_<k>/body`` ->
arm links, the arms from ``/smarticle_<k>/joint_states``). See docs/tracking.md and docs/bringup.md.
"""

from __future__ import annotations

import math
import functools
import time
from typing import Any

import numpy as np
import rclpy
from geometry_msgs.msg import PoseArray, PoseStamped
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from smarticle_common import topics
from smarticle_common.facts import RobotSpecError, robot_preset
from smarticle_common.messages import pose_message
from smarticle_common.node import ERROR, OK, DiagnosticsPublisher, read_config, run_node
from smarticle_common.params import ParameterError
from smarticle_common.robot_tf import RobotModelPublisher

from .errors import CameraCalibrationError, FrameEncodingError, FrameSizeError, TrackerError
from .parameters import TRACKER_NODE, TRACKER_PARAMS, tracker_calibration, tracker_config
from .tracker import TagTracker, image_from_buffer


class TrackerNode(Node):
    """Thin ROS shell around TagTracker."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node; ``node_options`` go to rclpy's Node (a composing host's ``cli_args``)."""
        super().__init__(TRACKER_NODE, **node_options)
        self.config, values = read_config(self, TRACKER_PARAMS, lambda v: (tracker_config(v), v))
        self.tracker: TagTracker | None = None
        self.calibration_problem = ''
        try:
            self.tracker = TagTracker(self.config, tracker_calibration(values))
        except CameraCalibrationError as err:   # keep running: frames are answered with missing poses
            self.calibration_problem = str(err)
            self.get_logger().error(f'no usable calibration, every robot will be reported missing: {err}')
        qos = {key: topics.qos_profile(topics.spec_of(key).qos) for key in topics.BY_KEY}
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        n = self.config.n_robots
        self.poses_pub = self.create_publisher(PoseArray, topics.topic('poses'), qos['poses'])
        self.pose_pubs = [self.create_publisher(PoseStamped, topics.topic('pose', k), qos['pose'],
                                                event_callbacks=quiet) for k in range(n)]
        self.diagnostics = DiagnosticsPublisher(self, TRACKER_NODE, 'overhead_camera')
        try:
            spec = robot_preset(values['preset'])
        except RobotSpecError as err:
            raise ParameterError(f'node {TRACKER_NODE}: {err}') from None
        self.robot_model = RobotModelPublisher(self, n, spec)   # descriptions and /tf
        #: Latest arm angles (rad) of each robot from its joint states (0 until one arrives), for TF.
        self.arms = np.zeros((n, 2))
        if self.robot_model.tf_pub is not None:
            joint_type = topics.message_class(topics.spec_of('joint_states').type)
            for k in range(n):
                self.create_subscription(joint_type, topics.topic('joint_states', k),
                                         functools.partial(self.on_joint_state, k), qos['joint_states'])
        image_type = topics.message_class(topics.spec_of('image_raw').type)
        info_type = topics.message_class(topics.spec_of('camera_info').type)
        image_qos = qos['image_raw'] if values['image_reliable'] else topics.qos_profile(topics.Qos.SENSOR)
        self.create_subscription(image_type, topics.topic('image_raw'), self.on_image, image_qos)
        self.create_subscription(info_type, topics.topic('camera_info'), self.on_camera_info, qos['camera_info'])
        self.camera_matrix: np.ndarray | None = None
        self.dist_coeffs: np.ndarray | None = None
        self.counts: dict[str, int] = {'frames': 0}
        self.last_logged: dict[str, float] = {}
        self.seen_total = 0
        self.create_timer(1.0, self.publish_diagnostics, clock=rclpy.clock.Clock())
        self.get_logger().info(f'tracking {n} robots (tags {list(self.config.tag_ids)}, {self.config.dictionary}, '
                               f'{self.config.tag_size * 1000:.1f} mm)')

    def _count(self, key: str, text: str, error: bool = False) -> None:
        """Count a problem and log it (at most every 2 s per kind of problem)."""
        self.counts[key] = self.counts.get(key, 0) + 1
        now = time.monotonic()
        if now - self.last_logged.get(key, -math.inf) >= 2.0:
            self.last_logged[key] = now
            (self.get_logger().error if error else self.get_logger().warning)(text)

    def _count_logged(self, key: str, text: str) -> None:
        """Log a per-frame problem already counted by the core (at most every 2 s per kind)."""
        now = time.monotonic()
        if now - self.last_logged.get(key, -math.inf) >= 2.0:
            self.last_logged[key] = now
            self.get_logger().warning(text)

    def on_camera_info(self, msg: Any) -> None:
        """Keep the intrinsics (used to undistort corners when the distortion is not zero)."""
        k = np.asarray(msg.k, dtype=float)
        d = np.asarray(msg.d, dtype=float)
        if k.size == 9 and np.all(np.isfinite(k)) and k[0] > 0:
            self.camera_matrix = k.reshape(3, 3)
            self.dist_coeffs = d if d.size and np.any(d != 0.0) else None

    def on_joint_state(self, robot: int, msg: Any) -> None:
        """Keep robot ``robot``'s arm angles for its TF (missing or non-finite angles leave the last ones)."""
        angles = dict(zip(msg.name, msg.position, strict=False))
        for j, name in enumerate(topics.JOINT_NAMES):
            value = angles.get(name)
            if value is not None and math.isfinite(value):
                self.arms[robot, j] = value

    def on_image(self, msg: Any) -> None:
        """Track one frame and publish its poses (missing ones as the unseen pose)."""
        self.counts['frames'] += 1
        n = self.config.n_robots
        poses = np.full((n, 3), np.nan)
        if self.tracker is None:
            self._count('frames_without_calibration', f'frame dropped: {self.calibration_problem}', error=True)
        else:
            try:
                grey = image_from_buffer(msg.encoding, msg.height, msg.width, msg.step, msg.data)
                result = self.tracker.track(grey, self.camera_matrix, self.dist_coeffs)
            except FrameEncodingError as err:
                self._count('unsupported_frames', f'frame not usable: {err}')
            except FrameSizeError as err:
                self._count('wrong_size_frames', f'frame not usable: {err}')
            except TrackerError as err:
                self._count('bad_frames', f'frame not usable: {err}')
            else:
                poses = result.poses
                self.seen_total += int(result.seen.sum())
                for key, count in result.counts.items():
                    self.counts[key] = self.counts.get(key, 0) + count
                for key, problem in result.problems:
                    self._count_logged(key, problem)
        self.publish_poses(msg.header.stamp, poses)

    def publish_poses(self, stamp: Any, poses: np.ndarray) -> None:
        """Publish the PoseArray and each robot's PoseStamped (only for subscribed robots)."""
        array = PoseArray()
        array.header.stamp = stamp
        array.header.frame_id = topics.ARENA_FRAME
        array.poses = [pose_message(row) for row in poses]
        self.poses_pub.publish(array)
        for k, pub in enumerate(self.pose_pubs):
            if pub.get_subscription_count() > 0:
                pub.publish(PoseStamped(header=array.header, pose=array.poses[k]))
        self.robot_model.publish(stamp, poses, self.arms)

    def publish_diagnostics(self) -> None:
        """Publish status and counters on /diagnostics."""
        frames = self.counts['frames']
        message = self.calibration_problem or f'{frames} frames'
        rate = self.seen_total / max(frames * self.config.n_robots, 1)
        self.diagnostics.publish(ERROR if self.tracker is None else OK, message,
                                 {**self.counts, 'detection_rate': f'{rate:.4f}', **self.robot_model.status()})


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_tracking tracker`."""
    raise SystemExit(run_node(TrackerNode, TRACKER_NODE, args, startup_errors=(ParameterError,)))

if __name__ == '__main__':
    main()
