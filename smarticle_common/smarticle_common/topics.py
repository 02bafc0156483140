"""The topic contract of the smarticle stack: names, message types, frames, units and QoS.

Hardware nodes, the simulation bridge, the feedback controller, the tracker, the glider monitor and
the bag tools all take their topic names and types from here; ``docs/topics.md`` shows the same table
(``python -m smarticle_common.topics`` prints it, and a test keeps the two equal).

This module imports no ROS code at import time, so pure cores and offline tools can use the names.
``message_class`` and ``qos_profile`` import the ROS packages only when called.
"""

from __future__ import annotations

import importlib
import re
import sys
from dataclasses import dataclass
from enum import Enum
from typing import Any

from .errors import CommonError

#: Joint names used in ``joint_commands`` and ``joint_states`` (arm 1 at the body's -x end).
JOINT_NAMES: tuple[str, str] = ('arm1', 'arm2')

#: FSR face names used in ``fsr`` (front = the face on the body-normal side when the arm is straight).
FSR_FACES: tuple[str, str, str, str] = ('arm1_front', 'arm1_back', 'arm2_front', 'arm2_back')

#: Frame of planar poses: the arena plate, origin at its centre, z up.
ARENA_FRAME = 'arena'

#: Namespace of robot ``k``.
ROBOT_NAMESPACE = 'smarticle_{k}'

#: Largest robot id the contract accepts (ids are 0 .. MAX_ROBOT_ID).
MAX_ROBOT_ID = 999

#: An unseen robot in ``/smarticles/poses`` (and its ``/smarticle_<k>/pose``): position (0, 0, UNSEEN_Z),
#: identity orientation. Every value is finite and the quaternion normalised, so RViz and Foxglove accept
#: the message (RViz refuses a PoseArray with a NaN anywhere); a seen robot always has z = 0, so z =
#: UNSEEN_Z (one metre under the plate) can only mean "not seen in this sample", never a stale pose.
UNSEEN_Z = -1.0


class Qos(Enum):
    """Named QoS kinds of the stack (see ``qos_profile``)."""

    SENSOR = 'sensor'      # best effort, keep last 10: high-rate measurements
    COMMAND = 'command'    # reliable, keep last 10: commands and events that must arrive
    LATCHED = 'latched'    # reliable, transient local, keep last 1: state a late joiner needs
    CLOCK = 'clock'        # best effort, keep last 1: rosgraph /clock as rclpy expects it
    IMAGE = 'image'        # reliable, keep last 2: large frames (one lost UDP fragment loses a best-effort frame)


@dataclass(frozen=True)
class TopicSpec:
    """One row of the contract: a topic name (``{k}`` = robot id), its type, QoS, units and meaning."""

    key: str
    name: str
    type: str
    qos: Qos
    frame: str
    units: str
    source: str
    meaning: str

    @property
    def per_robot(self) -> bool:
        """True when the name contains the robot id."""
        return '{k}' in self.name

    def resolve(self, robot_id: int | None = None) -> str:
        """Return the absolute topic name, for robot ``robot_id`` if the topic is per robot."""
        if self.per_robot:
            return self.name.format(k=validate_robot_id(robot_id))
        return self.name


class ContractError(CommonError):
    """A name, id or type that is not part of the topic contract."""


def validate_robot_id(robot_id: Any) -> int:
    """Return ``robot_id`` as an int or raise ContractError if it is not a valid robot id."""
    if isinstance(robot_id, bool) or not isinstance(robot_id, int):
        raise ContractError(f'robot id must be an integer 0..{MAX_ROBOT_ID}, got {robot_id!r}')
    if not 0 <= robot_id <= MAX_ROBOT_ID:
        raise ContractError(f'robot id must be in 0..{MAX_ROBOT_ID}, got {robot_id}')
    return robot_id


_R = '/smarticle_{k}'
_NAMESPACE = re.compile(r'^/smarticle_(\d+)$')


def robot_namespace(robot_id: int) -> str:
    """The namespace of robot ``robot_id``'s nodes (``/smarticle_<k>``, the prefix of its topics)."""
    return _R.format(k=validate_robot_id(robot_id))


def robot_of_namespace(namespace: str) -> int | None:
    """The robot id of a ``/smarticle_<k>`` namespace, or None for any other namespace."""
    match = _NAMESPACE.match(namespace)
    return validate_robot_id(int(match.group(1))) if match else None

TOPICS: tuple[TopicSpec, ...] = (
    TopicSpec('joint_commands', _R + '/joint_commands', 'sensor_msgs/msg/JointState', Qos.COMMAND,
              '', 'rad, rad/s', 'gait node',
              'arm targets (position) and speed limit (velocity, >0) for joints arm1, arm2; '
              'sent on change plus a heartbeat'),
    TopicSpec('joint_states', _R + '/joint_states', 'sensor_msgs/msg/JointState', Qos.SENSOR,
              '', 'rad, rad/s', 'servo bridge or sim bridge',
              'arm angles (servo slew model on hardware, measured in sim) and velocities'),
    TopicSpec('fsr', _R + '/fsr', 'sensor_msgs/msg/JointState', Qos.SENSOR,
              '', 'N', 'servo bridge or sim bridge',
              'one stamped sample of the four FSR faces: name = faces, effort = normal force'),
    TopicSpec('halt', _R + '/halt', 'std_msgs/msg/Header', Qos.COMMAND,
              '', 's (stamp)', 'feedback controller',
              'hold the arms now; the gait resumes from there at the next period; '
              'stamp = time of the triggering sample'),
    TopicSpec('decision', _R + '/feedback_decision', 'std_msgs/msg/Header', Qos.COMMAND,
              '', 's (stamp)', 'feedback controller (lock-step only)',
              'the decision on one FSR sample: stamp = the sample\'s stamp, frame_id = the face that halted '
              'the arms, empty for no halt; in lock-step the gait answers /clock only once it has it'),
    TopicSpec('pose', _R + '/pose', 'geometry_msgs/msg/PoseStamped', Qos.SENSOR,
              ARENA_FRAME, 'm, quaternion', 'tracker or sim bridge',
              'planar pose of this robot: body centre, yaw = heading of the body normal'),
    TopicSpec('robot_description', _R + '/robot_description', 'std_msgs/msg/String', Qos.LATCHED,
              '', 'm, kg (URDF)', 'sim bridge or tracker',
              'URDF of this robot\'s preset: links body, arm1_link, arm2_link on joints arm1, arm2; TF frames are '
              'smarticle_<k>/<link> (RViz RobotModel: this topic, TF prefix smarticle_<k>)'),
    TopicSpec('start', '/smarticles/start', 'std_msgs/msg/Header', Qos.LATCHED,
              '', 's (stamp)', 'operator or test',
              'synchronised gait start: every gait node starts its period at header.stamp'),
    TopicSpec('image_raw', '/overhead_camera/image_raw', 'sensor_msgs/msg/Image', Qos.IMAGE,
              'overhead_camera', 'pixels', 'camera driver or sim (only when subscribed)',
              'overhead view of the arena'),
    TopicSpec('camera_info', '/overhead_camera/camera_info', 'sensor_msgs/msg/CameraInfo', Qos.SENSOR,
              'overhead_camera', 'pixels', 'camera driver or sim', 'intrinsics of the overhead camera'),
    TopicSpec('poses', '/smarticles/poses', 'geometry_msgs/msg/PoseArray', Qos.SENSOR,
              ARENA_FRAME, 'm, quaternion', 'tracker, or sim without camera',
              'planar poses of all robots, index = robot id; a robot not seen is at (0, 0, -1) with identity '
              'orientation (UNSEEN_Z)'),
    TopicSpec('gliders', '/smarticles/gliders', 'diagnostic_msgs/msg/DiagnosticArray', Qos.COMMAND,
              '', 'm, rad, s', 'glider monitor',
              'one status per pair bound now: ids, r, theta, phi, class C1/C2, age, label (bound, bound pair, '
              'glider), travel'),
    TopicSpec('markers', '/smarticles/markers', 'visualization_msgs/msg/MarkerArray', Qos.COMMAND,
              ARENA_FRAME, 'm', 'glider monitor', 'robot outlines and glider bonds for RViz / Foxglove'),
    TopicSpec('diagnostics', '/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', Qos.COMMAND,
              '', '', 'every node', 'faults and counters (serial errors, bad messages, trouble)'),
    TopicSpec('clock', '/clock', 'rosgraph_msgs/msg/Clock', Qos.CLOCK,
              '', 's', 'sim bridge', 'simulation time for use_sim_time'),
    TopicSpec('run_until', '/sim_bridge/run_until', 'std_msgs/msg/Header', Qos.LATCHED,
              '', 's (stamp)', 'a test (smarticle_sim.testing)',
              'lock-step sim bridge with hold:=true: run up to this sim time, then wait for a later one'),
)

BY_KEY: dict[str, TopicSpec] = {spec.key: spec for spec in TOPICS}


def topic(key: str, robot_id: int | None = None) -> str:
    """Return the resolved topic name of contract entry ``key`` (for ``robot_id`` if per robot)."""
    return spec_of(key).resolve(robot_id)


def spec_of(key: str) -> TopicSpec:
    """Return the contract entry ``key`` or raise ContractError naming the known keys."""
    try:
        return BY_KEY[key]
    except KeyError:
        raise ContractError(f'unknown topic key {key!r}; known: {", ".join(BY_KEY)}') from None


_ROBOT_TOPIC = re.compile(r'^/smarticle_(\d+)/(\w+)$')


def parse_robot_topic(name: str) -> tuple[int, str] | None:
    """Return (robot id, key) for a per-robot topic name, or None if it is not one."""
    match = _ROBOT_TOPIC.match(name)
    if match is None or match.group(2) not in BY_KEY:
        return None
    return int(match.group(1)), match.group(2)


def message_class(type_name: str) -> type:
    """Import and return the message class for a type such as ``sensor_msgs/msg/JointState``."""
    parts = type_name.split('/')
    if len(parts) != 3 or parts[1] != 'msg':
        raise ContractError(f'message type must look like pkg/msg/Name, got {type_name!r}')
    module = importlib.import_module(f'{parts[0]}.msg')
    return getattr(module, parts[2])


def qos_profile(kind: Qos) -> Any:
    """Return the rclpy QoSProfile of a named QoS kind."""
    from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile,
                           ReliabilityPolicy)

    if kind is Qos.SENSOR:
        return QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST,
                          reliability=ReliabilityPolicy.BEST_EFFORT,
                          durability=DurabilityPolicy.VOLATILE)
    if kind is Qos.COMMAND:
        return QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
    if kind is Qos.IMAGE:
        return QoSProfile(depth=2, history=HistoryPolicy.KEEP_LAST,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
    if kind is Qos.LATCHED:
        return QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
    return QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.VOLATILE)


def markdown_table() -> str:
    """Return the contract as the Markdown table shown in docs/topics.md."""
    rows = ['| topic | type | QoS | frame | units | from | meaning |',
            '| --- | --- | --- | --- | --- | --- | --- |']
    for spec in TOPICS:
        rows.append(f'| `{spec.name.replace("{k}", "<k>")}` | `{spec.type}` | {spec.qos.value} | '
                    f'{spec.frame or "-"} | {spec.units or "-"} | {spec.source} | {spec.meaning} |')
    return '\n'.join(rows) + '\n'


if __name__ == '__main__':
    sys.stdout.write(markdown_table())
