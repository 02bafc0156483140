"""ROS node `glider_monitor`: live bound pairs from /smarticles/poses, for operators and RViz/Foxglove.

Subscribes ``/smarticles/poses`` (index = robot id; the unseen pose of ``topics.UNSEEN_Z`` = not seen;
yaw = heading of the body normal) and, with ``show_arms``, ``/smarticle_<k>/joint_states``. Feeds
``GliderMonitor`` (all maths there) and publishes, every ``publish_period`` of message time,
``/smarticles/gliders`` (one DiagnosticStatus per pair bound now, its ``label`` the run's words so far:
'bound', then 'C1 bound pair', 'C1 glider', ...) and ``/smarticles/markers`` (robot
outlines and glider bonds, from ``markers.scene_markers``). Faults go to ``/diagnostics``. See docs/tracking.md.
"""

from __future__ import annotations

import functools
import math
import time
from typing import Any

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point
from rclpy.node import Node
from rclpy.time import Time
from smarticle_common import topics
from smarticle_common.launching import report_line
from smarticle_common.messages import planar_poses
from smarticle_common.node import OK, DiagnosticsPublisher, read_config, run_node
from smarticle_common.params import ParameterError
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from .errors import GliderError
from .glider_monitor import BoundPair, GliderMonitor
from .markers import MarkerShape, scene_markers
from .parameters import MONITOR_NODE, MONITOR_PARAMS, monitor_settings

_KINDS = {'line_list': Marker.LINE_LIST, 'text': Marker.TEXT_VIEW_FACING}


def glider_status(pair: BoundPair, body_length: float, width: float | None = None) -> DiagnosticStatus:
    """One DiagnosticStatus describing a pair bound now (SI values, plus BL, W and degrees for people)."""
    w = body_length if width is None else width
    values = {
        'i': str(pair.i), 'j': str(pair.j), 'class': pair.glider_class.value, 'kind': pair.kind.value,
        'label': pair.label,
        'r': f'{pair.r:.5f}', 'r_bl': f'{pair.r / body_length:.3f}',
        'theta': f'{pair.theta:.4f}', 'theta_deg': f'{math.degrees(pair.theta):.1f}',
        'phi': f'{pair.phi:.4f}', 'phi_deg': f'{math.degrees(pair.phi):.1f}',
        'phi_mean_deg': f'{math.degrees(pair.phi_mean):.1f}',
        'age': f'{pair.age:.3f}', 'age_periods': str(pair.age_periods),
        'start_time': f'{pair.start_time:.3f}', 'is_glider': str(pair.is_glider).lower(),
        'bound_pair': str(pair.is_bound_pair).lower(),
        'distance': f'{pair.distance:.5f}', 'travel_w': f'{pair.distance / w:.3f}',
        'travel_w_per_100': f'{pair.travel_w_per_100:.3f}', 'travels': str(pair.is_glider).lower(),
        'isolation': f'{pair.isolation:.3f}', 'isolated': str(pair.isolated).lower()}
    return DiagnosticStatus(
        level=DiagnosticStatus.OK, name=f'pair {pair.i}-{pair.j}', hardware_id=f'smarticles {pair.i} {pair.j}',
        message=f'{pair.label}, bound {pair.age_periods} periods, travel {pair.distance / w:.2f} W',
        values=[KeyValue(key=k, value=v) for k, v in values.items()])


def marker_message(shape: MarkerShape, header: Any) -> Marker:
    """visualization_msgs/Marker of one MarkerShape."""
    marker = Marker(header=header, ns=shape.ns, id=shape.id)
    if shape.kind == 'delete_all':
        marker.action = Marker.DELETEALL
        return marker
    marker.type = _KINDS[shape.kind]
    marker.action = Marker.ADD
    marker.pose.orientation.w = 1.0
    marker.color = ColorRGBA(r=shape.rgba[0], g=shape.rgba[1], b=shape.rgba[2], a=shape.rgba[3])
    if shape.kind == 'text':
        x, y = shape.points[0]
        marker.pose.position.x, marker.pose.position.y, marker.pose.position.z = x, y, 0.03
        marker.scale.z = shape.width
        marker.text = shape.text
    else:
        marker.scale.x = shape.width
        marker.points = [Point(x=x, y=y, z=0.03) for x, y in shape.points]
    return marker


class GliderMonitorNode(Node):
    """Thin ROS shell around GliderMonitor and scene_markers."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node; ``node_options`` go to rclpy's Node (a composing host's ``cli_args``)."""
        super().__init__(MONITOR_NODE, **node_options)
        self.settings = read_config(self, MONITOR_PARAMS, monitor_settings)
        self.monitor = GliderMonitor(self.settings.glider, self.settings.t0, self.settings.history)
        qos = {key: topics.qos_profile(topics.spec_of(key).qos) for key in topics.BY_KEY}
        self.gliders_pub = self.create_publisher(DiagnosticArray, topics.topic('gliders'), qos['gliders'])
        self.markers_pub = self.create_publisher(MarkerArray, topics.topic('markers'), qos['markers'])
        self.diagnostics = DiagnosticsPublisher(self, MONITOR_NODE)
        self.create_subscription(topics.message_class(topics.spec_of('poses').type), topics.topic('poses'),
                                 self.on_poses, qos['poses'])
        self.arms = np.full((0, 2), np.nan)
        self.counts: dict[str, int] = {}
        self.last_logged: dict[str, float] = {}
        self.last_report = -math.inf
        self._bound: tuple[BoundPair, ...] | None = ()   # the bound pairs as of the last frame (None: not built)
        self.create_timer(1.0, self.publish_diagnostics, clock=rclpy.clock.Clock())

    def _count(self, key: str, text: str) -> None:
        """Count a fault and log it (at most every 2 s per kind of fault)."""
        self.counts[key] = self.counts.get(key, 0) + 1
        now = time.monotonic()
        if now - self.last_logged.get(key, -math.inf) >= 2.0:
            self.last_logged[key] = now
            self.get_logger().warning(text)

    def _watch_arms(self, n_robots: int) -> None:
        """Subscribe to the joint states of robots not yet watched (the team size is known from the poses)."""
        start = len(self.arms)
        if not self.settings.show_arms or n_robots <= start:
            return
        self.arms = np.vstack([self.arms, np.full((n_robots - start, 2), np.nan)])
        joint_type = topics.message_class(topics.spec_of('joint_states').type)
        qos = topics.qos_profile(topics.spec_of('joint_states').qos)
        for k in range(start, n_robots):
            self.create_subscription(joint_type, topics.topic('joint_states', k),
                                     functools.partial(self.on_joint_state, k), qos)

    def on_joint_state(self, robot: int, msg: Any) -> None:
        """Keep the latest arm angles of ``robot`` (joint names arm1, arm2)."""
        angles = dict(zip(msg.name, msg.position, strict=False))
        self.arms[robot] = [angles.get(name, math.nan) for name in topics.JOINT_NAMES]

    def on_poses(self, msg: Any) -> None:
        """Feed one frame to the monitor and report at the publish period."""
        stamp = Time.from_msg(msg.header.stamp).nanoseconds * 1e-9
        poses = planar_poses(msg)
        if len(poses) < 2:
            self._count('bad_frames', f'/smarticles/poses holds {len(poses)} robot(s): need at least 2')
            return
        self._watch_arms(len(poses))
        try:
            self.monitor.add(stamp, poses)
        except GliderError as err:   # time went backwards (replay, sim restart) or the team changed
            self._count('restarts', f'glider monitor restarted: {err}')
            self.monitor.reset()
            self.monitor.add(stamp, poses)
        self._bound = None   # built when a report or the diagnostics need them, not on every frame
        period = self.settings.publish_period
        if stamp - self.last_report >= period or stamp < self.last_report:
            self.last_report = stamp
            self.report(msg.header, poses)

    @property
    def bound(self) -> tuple[BoundPair, ...]:
        """The pairs bound as of the last frame."""
        if self._bound is None:
            self._bound = self.monitor.bound_pairs()
        return self._bound

    def report(self, header: Any, poses: np.ndarray) -> None:
        """Publish the bound pairs and the markers of this frame, each only to someone listening (a new
        subscriber gets the next report)."""
        bl = self.settings.glider.body_length
        if self.gliders_pub.get_subscription_count() > 0:
            array = DiagnosticArray(header=header)
            array.status = [glider_status(pair, bl, self.settings.glider.width) for pair in self.bound]
            self.gliders_pub.publish(array)
        if self.markers_pub.get_subscription_count() == 0:
            return
        arms = self.arms[:len(poses)] if self.settings.show_arms else None
        shapes = scene_markers(poses, self.bound, arms, self.settings.dims, bl)
        marker_header = type(header)(stamp=header.stamp, frame_id=topics.ARENA_FRAME)
        self.markers_pub.publish(MarkerArray(markers=[marker_message(s, marker_header) for s in shapes]))

    def publish_diagnostics(self) -> None:
        """Publish the node's status and counters on /diagnostics."""
        self.diagnostics.publish(OK, f'{len(self.bound)} bound pair(s)', self.counts)

    def destroy_node(self) -> None:
        """Log the run's glider report (one line, for the launcher), then destroy the node."""
        w = self.settings.glider.width
        pairs = '; '.join(f'{p.i}-{p.j} {p.label}, bound {p.age_periods} periods, travel {p.distance / w:.2f} W'
                          for p in self.monitor.finish())
        self.get_logger().info(report_line(f'glider report: {pairs or "no bound pair"}'))
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_tracking glider_monitor`."""
    raise SystemExit(run_node(GliderMonitorNode, MONITOR_NODE, args, startup_errors=(ParameterError,)))

if __name__ == '__main__':
    main()
