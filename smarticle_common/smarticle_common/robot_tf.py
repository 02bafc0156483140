"""The robot model on ROS: ``/smarticle_<k>/robot_description`` and TF (``/tf``) for every robot of a run.

``robot_transforms`` turns poses and arm angles into the transforms of every robot (``arena ->
smarticle_<k>/body -> smarticle_<k>/arm1_link, smarticle_<k>/arm2_link``, from ``robot_model.robot_frames``);
``transform_messages`` gives them as geometry_msgs/TransformStamped (the live view sends the same transforms
to Foxglove).
``RobotModelPublisher`` is what a node (the sim bridge, the tracker) holds: it latches each robot's URDF on
``/smarticle_<k>/robot_description`` (std_msgs/String, transient local like robot_state_publisher; RViz's
RobotModel display takes the topic and the TF prefix ``smarticle_<k>``) and publishes the transforms on
``/tf`` as tf2_msgs/TFMessage when tf2_msgs is importable (a ROS install has it; on a pip-only install the
set-up generates it into the virtual environment, tools/ros_interfaces). Without tf2_msgs it says
once in the log, and in every status of the node's /diagnostics (``status()``), that /tf is off.

No rclpy import: the publisher is handed a node. Metres, radians; a robot whose pose is not finite (not seen
by the tracker) gets no transform in that sample.
"""

from __future__ import annotations

import math
from typing import Any

from geometry_msgs.msg import TransformStamped

from . import topics
from .facts import RobotSpec
from .robot_model import Transform, robot_frames, urdf

#: The TF topic and its message type (tf2_msgs: a ROS install's, or generated at set-up; not on PyPI).
TF_TOPIC = '/tf'
TF_TYPE = 'tf2_msgs/msg/TFMessage'


def tf_message_class() -> type | None:
    """tf2_msgs/msg/TFMessage, or None when tf2_msgs is not installed."""
    try:
        return topics.message_class(TF_TYPE)
    except ImportError:
        return None


def body_position(spec: RobotSpec, x: float, y: float) -> tuple[float, float, float]:
    """Position of the body frame (the body box's centre) of a robot at planar position (x, y) on the plate."""
    return (x, y, spec.body_height / 2.0)


def robot_transforms(poses: Any, arm_angles: Any, spec: RobotSpec) -> list[Transform]:
    """Transforms of every robot: row k of ``poses`` is (x m, y m, heading rad), row k of ``arm_angles``
    (alpha1, alpha2) rad; a robot with a non-finite pose is left out, non-finite arm angles count as 0."""
    if len(arm_angles) != len(poses):
        raise ValueError(f'{len(poses)} poses but {len(arm_angles)} rows of arm angles')
    out: list[Transform] = []
    for k, (pose, alphas) in enumerate(zip(poses, arm_angles, strict=True)):
        x, y, heading = (float(v) for v in pose)
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(heading)):
            continue
        arms = tuple(float(a) if math.isfinite(float(a)) else 0.0 for a in alphas)
        if len(arms) != 2:
            raise ValueError(f'robot {k}: two arm angles expected, got {len(arms)}')
        orientation = (0.0, 0.0, math.sin(heading / 2.0), math.cos(heading / 2.0))
        out += robot_frames(k, body_position(spec, x, y), orientation, (arms[0], arms[1]), spec)
    return out


def transform_messages(poses: Any, arm_angles: Any, spec: RobotSpec, stamp: Any) -> list[TransformStamped]:
    """geometry_msgs/TransformStamped of ``robot_transforms(poses, arm_angles, spec)``, stamped ``stamp``."""
    out: list[TransformStamped] = []
    for t in robot_transforms(poses, arm_angles, spec):
        msg = TransformStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = t.parent
        msg.child_frame_id = t.child
        msg.transform.translation.x, msg.transform.translation.y, msg.transform.translation.z = t.translation
        (msg.transform.rotation.x, msg.transform.rotation.y, msg.transform.rotation.z,
         msg.transform.rotation.w) = t.rotation
        out.append(msg)
    return out


class RobotModelPublisher:
    """Robot descriptions (latched, one per robot) and /tf (when tf2_msgs is installed) of ``n`` robots."""

    def __init__(self, node: Any, n_robots: int, spec: RobotSpec) -> None:
        """Create the publishers on ``node`` and latch every robot's description now."""
        self.node, self.spec = node, spec
        String = topics.message_class(topics.spec_of('robot_description').type)
        qos = topics.qos_profile(topics.spec_of('robot_description').qos)
        description = String(data=urdf(spec))
        self.description_pubs = []
        for k in range(n_robots):
            pub = node.create_publisher(String, topics.topic('robot_description', k), qos)
            pub.publish(description)
            self.description_pubs.append(pub)
        self.TFMessage = tf_message_class()
        self.tf_pub = None
        if self.TFMessage is None:
            node.get_logger().warning(f'{TF_TOPIC} is off: tf2_msgs is not installed (a ROS install has it; '
                                      f'on a pip-only install the set-up builds it: see its output); '
                                      f'/smarticle_<k>/robot_description is published')
        else:
            self.tf_pub = node.create_publisher(self.TFMessage, TF_TOPIC, topics.qos_profile(topics.Qos.COMMAND))

    def status(self) -> dict[str, str]:
        """Key/value for the node's /diagnostics: whether /tf is published."""
        return {'tf': 'on' if self.tf_pub is not None else 'off (tf2_msgs not installed)'}

    def publish(self, stamp: Any, poses: Any, arm_angles: Any) -> list[TransformStamped]:
        """Publish the transforms of one sample on /tf (if on and subscribed); return what was sent."""
        if self.TFMessage is None or self.tf_pub is None or self.tf_pub.get_subscription_count() == 0:
            return []        # nobody listens: nothing built (a new subscriber gets the next sample)
        transforms = transform_messages(poses, arm_angles, self.spec, stamp)
        if transforms:
            self.tf_pub.publish(self.TFMessage(transforms=transforms))
        return transforms
