"""ROS node `smarticle-view`: the live view of a run, served to Foxglove over its WebSocket protocol.

Subscribes ``/smarticles/poses`` (the unseen pose = not drawn), ``/smarticles/gliders`` and, once the
team size is known from the poses, ``/smarticle_<k>/joint_states``; every ``1 / rate`` wall seconds it
turns what it has into scene entities (``scene.SceneBuilder``: bodies and arms as cubes, trails, gliders
coloured by class with their age) and logs one ``foxglove.SceneUpdate`` on the channel
``/smarticles/scene`` of a Foxglove WebSocket server (``foxglove-sdk``) at ``ws://host:port``, with the
robots' frames (arena -> ``smarticle_<k>/body`` -> arm links, ``robot_tf.robot_transforms``) as one
``foxglove.FrameTransforms`` on the channel ``/tf``. Open it
in Foxglove with "Open connection" -> Foxglove WebSocket -> ``ws://localhost:8765`` and the layout
``smarticle_bringup/config/foxglove_layout.json``; the fixed (display) frame is ``arena``.
See docs/bringup.md.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

import rclpy
from rclpy.node import Node
from smarticle_common import topics
from smarticle_common.facts import PRESETS, RobotSpecError, robot_preset
from smarticle_common.messages import planar_poses
from smarticle_common.node import DiagnosticsPublisher, OK, WARN, read_config, run_node
from smarticle_common.params import ParameterError, ParamSpec
from smarticle_common.robot_model import Transform
from smarticle_common.robot_tf import robot_transforms

from .scene import Entity, SceneBuilder, dims_of, glider_reports

NODE_NAME = 'view'
#: The Foxglove channel the scene goes to.
SCENE_TOPIC = '/smarticles/scene'
#: The Foxglove channel the robots' frames go to.
TF_CHANNEL = '/tf'

PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('host', '127.0.0.1', 'address the WebSocket server listens on (0.0.0.0: every interface)'),
    ParamSpec('port', 8765, 'WebSocket port (0 = any free port, logged at start)', 0, 65535),
    ParamSpec('rate', 10.0, 'scene updates per wall second', 0.5, 100.0),
    ParamSpec('trail_length', 200, 'points kept in each robot trail', 2, 100000),
    ParamSpec('trail_spacing', 0.002, 'a robot moves this far (m) before its trail gets a new point', 0.0, 1.0),
    ParamSpec('show_arms', True, 'subscribe to /smarticle_<k>/joint_states and draw the arms'),
    ParamSpec('preset', 'small', f'robot preset whose outline is drawn: {", ".join(sorted(PRESETS))}'),
)


def _rgba(fox: Any, rgba: tuple[float, float, float, float]) -> Any:
    r, g, b, a = rgba
    return fox.Color(r=r, g=g, b=b, a=a)


def _pose(fox: Any, x: float, y: float, z: float, yaw: float = 0.0) -> Any:
    return fox.Pose(position=fox.Vector3(x=x, y=y, z=z),
                    orientation=fox.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0)))


def frame_transforms(fox: Any, transforms: list[Transform], stamp_ns: int) -> Any:
    """foxglove.messages.FrameTransforms of the robots' transforms."""
    stamp = fox.Timestamp(sec=stamp_ns // 10**9, nsec=stamp_ns % 10**9)
    return fox.FrameTransforms(transforms=[
        fox.FrameTransform(timestamp=stamp, parent_frame_id=t.parent, child_frame_id=t.child,
                           translation=fox.Vector3(x=t.translation[0], y=t.translation[1], z=t.translation[2]),
                           rotation=fox.Quaternion(x=t.rotation[0], y=t.rotation[1], z=t.rotation[2],
                                                   w=t.rotation[3])) for t in transforms])


def entity_message(fox: Any, entity: Entity, stamp_ns: int) -> Any:
    """foxglove.messages.SceneEntity of one scene entity."""
    stamp = fox.Timestamp(sec=stamp_ns // 10**9, nsec=stamp_ns % 10**9)
    return fox.SceneEntity(
        timestamp=stamp, frame_id=entity.frame, id=entity.id,
        cubes=[fox.CubePrimitive(pose=_pose(fox, *c.centre, c.yaw), size=fox.Vector3(x=c.size[0], y=c.size[1],
                                                                                      z=c.size[2]),
                                 color=_rgba(fox, c.rgba)) for c in entity.cubes],
        lines=[fox.LinePrimitive(type=fox.LinePrimitiveLineType.LineStrip, thickness=line.thickness,
                                 points=[fox.Point3(x=p[0], y=p[1], z=p[2]) for p in line.points],
                                 color=_rgba(fox, line.rgba)) for line in entity.lines],
        texts=[fox.TextPrimitive(pose=_pose(fox, *t.position), billboard=True, font_size=t.size, text=t.text,
                                 color=_rgba(fox, t.rgba)) for t in entity.labels])


class ViewNode(Node):
    """Thin ROS shell around scene.SceneBuilder and a Foxglove WebSocket server."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node, start the WebSocket server; ``node_options`` go to rclpy's Node."""
        import foxglove
        import foxglove.messages as fox
        from foxglove.channels import FrameTransformsChannel, SceneUpdateChannel

        super().__init__(NODE_NAME, **node_options)
        values = read_config(self, PARAMS, dict)
        self.fox = fox
        try:
            dims = dims_of(values['preset'])
            self.spec = robot_preset(values['preset'])
        except (ValueError, RobotSpecError) as err:
            raise ParameterError(f'node {NODE_NAME}: {err}') from None
        self.builder = SceneBuilder(dims=dims, trail_length=values['trail_length'],
                                    trail_spacing=values['trail_spacing'])
        self.show_arms: bool = values['show_arms']
        self.watched = 0
        self.bad_reports = 0
        try:
            self.server = foxglove.start_server(name='smarticles', host=values['host'], port=values['port'])
        except RuntimeError as err:
            raise ParameterError(f'node {NODE_NAME}: cannot serve on {values["host"]}:{values["port"]}: {err}') \
                from None
        self.channel = SceneUpdateChannel(SCENE_TOPIC)
        self.tf_channel = FrameTransformsChannel(TF_CHANNEL)
        #: Latest poses (NaN rows: not seen) and arm angles (rad, 0 until heard) of the robots, for the frames.
        self.poses = np.zeros((0, 3))
        self.arms = np.zeros((0, 2))
        qos = {key: topics.qos_profile(topics.spec_of(key).qos) for key in ('poses', 'gliders', 'joint_states')}
        self.create_subscription(topics.message_class(topics.spec_of('poses').type), topics.topic('poses'),
                                 self.on_poses, qos['poses'])
        self.create_subscription(topics.message_class(topics.spec_of('gliders').type), topics.topic('gliders'),
                                 self.on_gliders, qos['gliders'])
        self.joint_qos = qos['joint_states']
        self.diagnostics = DiagnosticsPublisher(self, NODE_NAME)
        self.create_timer(1.0 / values['rate'], self.on_timer, clock=rclpy.clock.Clock())
        self.create_timer(1.0, self.publish_diagnostics, clock=rclpy.clock.Clock())
        self.get_logger().info(f'serving the live view on ws://{values["host"]}:{self.server.port} '
                               f'(channel {SCENE_TOPIC}, frame {topics.ARENA_FRAME})')

    def on_poses(self, msg: Any) -> None:
        """Keep the poses (unseen robots are NaN rows) and watch the arms of newly seen robot ids."""
        poses = planar_poses(msg)
        self.builder.set_poses(poses)
        self.poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        if len(self.arms) < len(self.poses):
            self.arms = np.vstack([self.arms, np.zeros((len(self.poses) - len(self.arms), 2))])
        if self.show_arms and len(poses) > self.watched:
            joint_type = topics.message_class(topics.spec_of('joint_states').type)
            for k in range(self.watched, len(poses)):
                self.create_subscription(joint_type, topics.topic('joint_states', k),
                                         functools.partial(self.on_joint_state, k), self.joint_qos)
            self.watched = len(poses)

    def on_joint_state(self, robot: int, msg: Any) -> None:
        """Keep robot ``robot``'s arm angles."""
        angles = dict(zip(msg.name, msg.position, strict=False))
        arms = [angles.get(name, math.nan) for name in topics.JOINT_NAMES]
        self.builder.set_arms(robot, arms)
        if robot < len(self.arms):
            self.arms[robot] = [a if math.isfinite(a) else 0.0 for a in arms]

    def on_gliders(self, msg: Any) -> None:
        """Keep the bound pairs of the latest glider report (a malformed one is counted and skipped)."""
        try:
            self.builder.set_gliders(glider_reports({kv.key: kv.value for kv in s.values} for s in msg.status))
        except ValueError as err:
            self.bad_reports += 1
            self.get_logger().warning(str(err), throttle_duration_sec=2.0)

    def on_timer(self) -> None:
        """Send the current scene to every connected Foxglove client."""
        update = self.builder.update()
        stamp = self.get_clock().now().nanoseconds
        fox = self.fox
        self.channel.log(fox.SceneUpdate(
            deletions=[fox.SceneEntityDeletion(type=fox.SceneEntityDeletionType.MatchingId, id=i)
                       for i in update.deletions],
            entities=[entity_message(fox, e, stamp) for e in update.entities]))
        transforms = robot_transforms(self.poses, self.arms[:len(self.poses)], self.spec)
        if transforms:
            self.tf_channel.log(frame_transforms(fox, transforms, stamp))

    def publish_diagnostics(self) -> None:
        """Status and counters on /diagnostics."""
        self.diagnostics.publish(WARN if self.bad_reports else OK, f'serving on port {self.server.port}',
                                 {'robots': self.watched, 'bad_glider_reports': self.bad_reports})

    def destroy_node(self) -> None:
        """Stop the WebSocket server, then destroy the node."""
        self.server.stop()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point of `smarticle-view` (`ros2 run smarticle_bringup smarticle-view`)."""
    raise SystemExit(run_node(ViewNode, NODE_NAME, args, startup_errors=(ParameterError,)))


if __name__ == '__main__':
    main()
