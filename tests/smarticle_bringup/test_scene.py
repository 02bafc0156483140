"""The live view's core: robots, arms, trails and gliders as scene entities (no ROS, no Foxglove)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_bringup.scene import SceneBuilder, glider_reports, robot_cubes
from smarticle_tracking.gliders import GliderClass
from smarticle_tracking.markers import CLASS_COLOURS, ROBOT_COLOUR, RobotDims


def test_body_and_arms_are_cubes_at_the_body_ends() -> None:
    dims = RobotDims()
    body, arm1, arm2 = robot_cubes([0.1, 0.2, math.pi / 2], [0.0, 0.0], dims, ROBOT_COLOUR)
    assert body.centre[:2] == pytest.approx((0.1, 0.2)) and body.yaw == pytest.approx(0.0)   # normal along +y
    assert body.size[:2] == pytest.approx((dims.body_width, dims.body_depth))
    reach = dims.body_width / 2 + dims.arm_length / 2            # straight arms continue the body
    assert arm1.centre[:2] == pytest.approx((0.1 - reach, 0.2)) and arm2.centre[:2] == pytest.approx((0.1 + reach, 0.2))
    _, bent, _ = robot_cubes([0.0, 0.0, math.pi / 2], [math.pi / 2, 0.0], dims, ROBOT_COLOUR)
    assert bent.centre[1] > 0.0              # a positive angle turns the tip toward the body normal
    assert len(robot_cubes([0.0, 0.0, 0.0], None, dims, ROBOT_COLOUR)) == 1      # arms unknown: body only


def test_the_scene_draws_seen_robots_trails_and_gliders_and_deletes_what_is_gone() -> None:
    builder = SceneBuilder(trail_spacing=0.001)
    reports = glider_reports([{'i': '0', 'j': '1', 'class': 'C2', 'age': '12.8', 'age_periods': '8'}])
    assert reports[0].glider_class is GliderClass.C2
    for step in range(5):
        builder.set_poses([[0.01 * step, 0.0, 0.0], [0.05, 0.01 * step, 1.0], [np.nan] * 3])
    builder.set_arms(0, [0.3, -0.3])
    builder.set_gliders(reports)
    update = builder.update()
    ids = {e.id: e for e in update.entities}
    assert set(ids) == {'robot_0', 'robot_1', 'trail_0', 'trail_1', 'glider_0_1'} and update.deletions == ()
    assert len(ids['robot_0'].cubes) == 3 and len(ids['robot_1'].cubes) == 1
    assert ids['robot_0'].cubes[0].rgba == CLASS_COLOURS[GliderClass.C2]          # coloured by its glider
    assert len(ids['trail_0'].lines[0].points) == 5
    assert ids['glider_0_1'].labels[0].text == 'C2 12.8 s (8 periods)'
    assert all(e.frame == 'arena' for e in update.entities)
    builder.set_poses([[0.05, 0.0, 0.0], [np.nan] * 3, [np.nan] * 3])           # robot 1 not seen now
    builder.set_gliders([])
    gone = builder.update().deletions
    assert gone == ('glider_0_1', 'robot_1')


def test_a_malformed_glider_report_is_refused() -> None:
    with pytest.raises(ValueError, match='malformed'):
        glider_reports([{'i': '0', 'class': 'C9'}])


def test_the_outline_of_each_robot_preset() -> None:
    """The live view draws the robot it is told (view parameter ``preset``): the feedback robot is larger."""
    from smarticle_bringup.scene import dims_of
    from smarticle_common.facts import FEEDBACK, SMALL

    assert dims_of('small').body_width == SMALL.body_width and dims_of('small') == SceneBuilder().dims
    big = dims_of('feedback')
    assert (big.body_width, big.body_depth, big.arm_length) == (FEEDBACK.body_width, FEEDBACK.body_depth,
                                                                FEEDBACK.arm_length)
    with pytest.raises(ValueError, match='feedback, small'):
        dims_of('huge')
