"""The robot description (URDF) of a robot preset and the TF frames of a robot, without ROS.

``urdf(spec)`` renders a URDF of one smarticle from its ``RobotSpec`` (facts.py): a body box and two arm
boxes on two revolute joints named as the joint states name them (``arm1``, ``arm2``), so RViz's
RobotModel and Foxglove's 3D panel can draw it from ``/robot_description`` and TF. ``robot_frames``
computes the transforms of robot k from its pose and arm angles: ``arena -> smarticle_<k>/body ->
smarticle_<k>/arm1_link, smarticle_<k>/arm2_link``.

Frames follow docs/gait.md: the body frame has x along the body from joint 1 to joint 2 and y along the
body normal (the heading; the pose's yaw is the heading, so the body frame is the pose turned by -90
degrees), origin at the body's centre; arm 1 hangs on the -x end, arm 2 on the +x end; alpha = 0 is an
arm in line with the body and alpha > 0 turns its tip toward +y. Each arm link's frame sits on its joint
with x along the arm, toward the tip. Metres, radians, quaternions as (x, y, z, w).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from .facts import RobotSpec

Vector = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]

#: Joint (and joint state) names and the links they move, in order.
JOINTS = (('arm1', 'arm1_link'), ('arm2', 'arm2_link'))
BODY_LINK = 'body'
ARENA_FRAME = 'arena'
#: Joint limits of the URDF (rad): the gait's largest amplitude, 120 degrees, either way.
JOINT_LIMIT = math.radians(120.0)


@dataclass(frozen=True)
class Transform:
    """One TF transform: the child frame's origin and orientation in the parent frame."""

    parent: str
    child: str
    translation: Vector
    rotation: Quaternion


def frame(robot: int, link: str) -> str:
    """The TF frame of ``link`` of robot ``robot``: ``smarticle_<k>/<link>``."""
    return f'smarticle_{robot}/{link}'


def yaw_quaternion(angle: float) -> Quaternion:
    """The rotation by ``angle`` (rad) about z."""
    return (0.0, 0.0, math.sin(angle / 2.0), math.cos(angle / 2.0))


def multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """The rotation ``a`` followed, in ``a``'s frame, by ``b`` (Hamilton product a * b)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def arm_height_offset(spec: RobotSpec) -> float:
    """Height of the arms' centre above the body's centre (m): both stand on the plate, the arms
    ``arm_clearance`` above it."""
    return spec.arm_clearance + spec.arm_height / 2.0 - spec.body_height / 2.0


def _joint_pose(spec: RobotSpec, index: int) -> tuple[Vector, float]:
    """Joint ``index``'s origin in the body frame and the yaw of its link at alpha = 0."""
    sign = -1.0 if index == 0 else 1.0
    return (sign * spec.body_width / 2.0, 0.0, arm_height_offset(spec)), (math.pi if index == 0 else 0.0)


def _arm_yaw(index: int, alpha: float) -> float:
    """Yaw of arm ``index``'s link in the body frame at angle ``alpha`` (tip toward +y for alpha > 0)."""
    return math.pi - alpha if index == 0 else alpha


def robot_frames(robot: int, position: Vector, orientation: Quaternion, alphas: tuple[float, float],
                 spec: RobotSpec) -> list[Transform]:
    """TF of robot ``robot``: arena -> body (from the pose, whose yaw is the heading) -> both arm links."""
    if not all(math.isfinite(v) for v in (*position, *orientation, *alphas)):
        raise ValueError(f'robot {robot}: pose and arm angles must be finite, got {position}, {orientation}, '
                         f'{alphas}')
    body = multiply(orientation, yaw_quaternion(-math.pi / 2.0))
    frames = [Transform(ARENA_FRAME, frame(robot, BODY_LINK), position, body)]
    for index, (_, link) in enumerate(JOINTS):
        origin, _ = _joint_pose(spec, index)
        frames.append(Transform(frame(robot, BODY_LINK), frame(robot, link), origin,
                                yaw_quaternion(_arm_yaw(index, alphas[index]))))
    return frames


def _box(size: Vector, xyz: Vector, mass: float, material: str, rgba: str) -> str:
    sx, sy, sz = size
    ixx, iyy, izz = (mass * (sy * sy + sz * sz) / 12.0, mass * (sx * sx + sz * sz) / 12.0,
                     mass * (sx * sx + sy * sy) / 12.0)
    origin = f'<origin xyz="{xyz[0]:.12g} {xyz[1]:.12g} {xyz[2]:.12g}" rpy="0 0 0"/>'
    geometry = f'<geometry><box size="{sx:.12g} {sy:.12g} {sz:.12g}"/></geometry>'
    return (f'    <visual>{origin}{geometry}<material name="{material}"><color rgba="{rgba}"/>'
            f'</material></visual>\n    <collision>{origin}{geometry}</collision>\n'
            f'    <inertial>{origin}<mass value="{mass:.12g}"/><inertia ixx="{ixx:.12g}" ixy="0" ixz="0" '
            f'iyy="{iyy:.12g}" iyz="0" izz="{izz:.12g}"/></inertial>\n')


def urdf(spec: RobotSpec) -> str:
    """The URDF of one robot of preset ``spec``: link ``body`` and links ``arm1_link`` / ``arm2_link`` on the
    revolute joints ``arm1`` / ``arm2`` (the joint-state names), sizes and masses from ``spec``."""
    body_mass = spec.total_mass - 2.0 * spec.arm_mass
    lines = [f'<?xml version="1.0"?>\n<robot name={quoteattr("smarticle_" + spec.name)}>\n',
             f'  <link name="{BODY_LINK}">\n',
             _box((spec.body_width, spec.body_depth, spec.body_height), (0.0, 0.0, 0.0), body_mass,
                  'body_colour', '0.2 0.4 0.8 1'), '  </link>\n']
    for index, (joint, link) in enumerate(JOINTS):
        origin, yaw = _joint_pose(spec, index)
        axis = '0 0 -1' if index == 0 else '0 0 1'      # alpha > 0 turns either tip toward +y
        lines += [f'  <link name="{link}">\n',
                  _box((spec.arm_length, spec.arm_thickness, spec.arm_height), (spec.arm_length / 2.0, 0.0, 0.0),
                       spec.arm_mass, 'arm_colour', '0.9 0.6 0.1 1'),
                  '  </link>\n',
                  f'  <joint name="{joint}" type="revolute">\n    <parent link="{BODY_LINK}"/>\n'
                  f'    <child link="{link}"/>\n'
                  f'    <origin xyz="{origin[0]:.12g} {origin[1]:.12g} {origin[2]:.12g}" rpy="0 0 {yaw:.12g}"/>\n'
                  f'    <axis xyz="{axis}"/>\n'
                  f'    <limit lower="{-JOINT_LIMIT:.12g}" upper="{JOINT_LIMIT:.12g}" '
                  f'effort="{spec.servo_torque:.12g}" velocity="{spec.servo_speed:.12g}"/>\n  </joint>\n']
    lines.append('</robot>\n')
    return ''.join(lines)


def main(argv: list[str] | None = None) -> int:
    """``python -m smarticle_common.robot_model [PRESET]``: print the URDF of a preset (default small)."""
    import sys

    from .facts import PRESETS, RobotSpecError, robot_preset

    args = sys.argv[1:] if argv is None else argv
    if args and args[0] in ('-h', '--help'):
        print(f'usage: python -m smarticle_common.robot_model [{"|".join(PRESETS)}]: print the URDF of a preset')
        return 0
    try:
        spec = robot_preset(args[0] if args else 'small')
    except RobotSpecError as err:
        print(f'smarticle_common.robot_model: {err}', file=sys.stderr)
        return 2
    print(urdf(spec), end='')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
