"""The robot description and TF frames: sizes from facts.py, frames that agree with the URDF's joints and
with the live view's independent drawing of the same robot (smarticle_bringup.scene)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from smarticle_bringup.scene import RobotDims, robot_cubes
from smarticle_common.facts import PRESETS, RobotSpec
from smarticle_common.poses import heading_quaternion
from smarticle_common.robot_model import Transform, robot_frames, urdf


def rotation(q: tuple[float, float, float, float]) -> np.ndarray:
    """Rotation matrix of quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def compose(chain: list[Transform]) -> tuple[np.ndarray, np.ndarray]:
    """Position and rotation of the last child in the first parent's frame."""
    position, rot = np.zeros(3), np.eye(3)
    for t in chain:
        position = position + rot @ np.array(t.translation)
        rot = rot @ rotation(t.rotation)
    return position, rot


@pytest.mark.parametrize('spec', PRESETS.values(), ids=list(PRESETS))
def test_the_urdf_has_the_body_and_two_arms_of_the_preset(spec: RobotSpec) -> None:
    root = ET.fromstring(urdf(spec))
    boxes = {link.get('name'): [float(v) for v in link.find('visual/geometry/box').get('size').split()]
             for link in root.iter('link')}
    assert boxes == {'body': pytest.approx([spec.body_width, spec.body_depth, spec.body_height]),
                     'arm1_link': pytest.approx([spec.arm_length, spec.arm_thickness, spec.arm_height]),
                     'arm2_link': pytest.approx([spec.arm_length, spec.arm_thickness, spec.arm_height])}
    joints = {j.get('name'): j for j in root.iter('joint')}
    assert set(joints) == {'arm1', 'arm2'}      # the joint-state names
    for name, sign in (('arm1', -1.0), ('arm2', 1.0)):
        joint = joints[name]
        assert joint.get('type') == 'revolute' and joint.find('parent').get('link') == 'body'
        assert float(joint.find('origin').get('xyz').split()[0]) == pytest.approx(sign * spec.body_width / 2)
        assert float(joint.find('limit').get('velocity')) == pytest.approx(spec.servo_speed)
    masses = sum(float(m.get('value')) for m in root.iter('mass'))
    assert masses == pytest.approx(spec.total_mass)


@pytest.mark.parametrize('alphas', [(0.0, 0.0), (math.radians(90), math.radians(90)), (-0.7, 1.1)])
def test_frames_follow_the_urdf_joints(alphas: tuple[float, float]) -> None:
    """The transform of each arm equals the URDF joint's origin turned by the angle about the joint's axis."""
    spec = PRESETS['small']
    frames = robot_frames(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), alphas, spec)
    root = ET.fromstring(urdf(spec))
    for index, joint in enumerate(sorted(root.iter('joint'), key=lambda j: j.get('name'))):
        yaw = float(joint.find('origin').get('rpy').split()[2])
        axis_z = float(joint.find('axis').get('xyz').split()[2])
        expected = yaw + axis_z * alphas[index]
        got = frames[1 + index].rotation
        angle = math.atan2(2 * got[3] * got[2], 1 - 2 * got[2] ** 2)
        assert (math.cos(angle), math.sin(angle)) == pytest.approx((math.cos(expected), math.sin(expected)), abs=1e-9)
        assert frames[1 + index].translation == pytest.approx(
            [float(v) for v in joint.find('origin').get('xyz').split()])


@pytest.mark.parametrize('pose, alphas', [((0.10, -0.05, 0.3), (math.radians(90), math.radians(90))),
                                          ((-0.2, 0.15, -2.0), (-0.4, 0.9)), ((0.0, 0.0, 0.0), (0.0, 0.0))])
def test_the_arms_land_where_the_live_view_draws_them(pose: tuple[float, float, float],
                                                      alphas: tuple[float, float]) -> None:
    spec = PRESETS['small']
    x, y, heading = pose
    frames = robot_frames(3, (x, y, 0.0), heading_quaternion(heading), alphas, spec)
    assert [f.child for f in frames] == ['smarticle_3/body', 'smarticle_3/arm1_link', 'smarticle_3/arm2_link']
    assert frames[0].parent == 'arena' and frames[1].parent == frames[2].parent == 'smarticle_3/body'
    dims = RobotDims(spec.body_width, spec.body_depth, spec.arm_length, spec.arm_thickness)
    cubes = robot_cubes(pose, alphas, dims, (1.0, 1.0, 1.0, 1.0))
    for index in (0, 1):
        origin, rot = compose([frames[0], frames[1 + index]])
        centre = origin + rot @ np.array([spec.arm_length / 2, 0.0, 0.0])
        assert centre[:2] == pytest.approx(cubes[1 + index].centre[:2], abs=1e-9)
        assert math.cos(cubes[1 + index].yaw - math.atan2(rot[1, 0], rot[0, 0])) == pytest.approx(1.0)
    body_origin, body_rot = compose(frames[:1])
    assert body_origin[:2] == pytest.approx([x, y])
    assert math.atan2(body_rot[1, 1], body_rot[0, 1]) == pytest.approx(
        math.atan2(math.sin(heading), math.cos(heading)))                # body y = the heading


def test_nonsense_is_refused() -> None:
    with pytest.raises(ValueError, match='finite'):
        robot_frames(0, (math.nan, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0), PRESETS['small'])


def test_the_module_prints_a_preset_urdf(capsys: pytest.CaptureFixture[str]) -> None:
    from smarticle_common.robot_model import main

    assert main(['feedback']) == 0
    assert ET.fromstring(capsys.readouterr().out).get('name') == 'smarticle_feedback'
    assert main(['nope']) == 2 and 'unknown' in capsys.readouterr().err
