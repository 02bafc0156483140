"""Footprints, overlap tests, pair coordinates and the seeded scene builders."""

from __future__ import annotations

import math

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig

from smarticle_sim.errors import SceneError
from smarticle_common.facts import SMALL
from smarticle_common.pairs import one_pair
from smarticle_sim.geometry import Rect, rect_corners, rects_overlap, robot_rects
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene, pair_scene, random_scene


def test_rect_overlap_separating_axis() -> None:
    a = Rect(0.0, 0.0, 1.0, 0.1, 0.0)
    assert rects_overlap(a, Rect(0.5, 0.0, 1.0, 0.1, math.pi / 2))
    assert not rects_overlap(a, Rect(0.0, 0.3, 1.0, 0.1, 0.0))
    assert rects_overlap(a, Rect(0.0, 0.3, 1.0, 0.1, 0.0), gap=0.2)
    # diamond near a corner: the axis-aligned boxes overlap but the rectangles do not
    assert not rects_overlap(Rect(0, 0, 1, 1, 0), Rect(1.75, 1.75, 0.5, 0.5, math.pi / 4))


def test_arm_tips_follow_the_gait_convention() -> None:
    """alpha > 0 turns both arm tips toward the body normal (+y at heading pi/2)."""
    body, arm1, arm2 = robot_rects(SMALL, 0.0, 0.0, math.pi / 2, math.pi / 2, math.pi / 2)
    assert body.hx == pytest.approx(SMALL.body_width / 2)
    for arm, x_joint in ((arm1, -SMALL.body_width / 2), (arm2, SMALL.body_width / 2)):
        assert arm.cx == pytest.approx(x_joint)
        assert arm.cy == pytest.approx(SMALL.arm_length / 2)
    _, arm1, arm2 = robot_rects(SMALL, 0.0, 0.0, math.pi / 2, 0.0, 0.0)
    assert arm1.cx == pytest.approx(-(SMALL.body_width + SMALL.arm_length) / 2)
    assert rect_corners(arm2)[:, 0].max() == pytest.approx(SMALL.body_width / 2 + SMALL.arm_length)


def test_dense_scene_is_seeded_packed_and_in_phase(gait90: GaitConfig) -> None:
    a = dense_scene(SMALL, gait90, 7, seed=3)
    assert a == dense_scene(SMALL, gait90, 7, seed=3)
    assert a != dense_scene(SMALL, gait90, 7, seed=4)
    a.validate(SMALL, 0.6)
    assert {r.gait for r in a.robots} == {gait90}
    centres = np.array([(r.x, r.y) for r in a.robots])
    assert np.linalg.norm(centres, axis=1).max() < 3 * SMALL.body_length   # compressed


def test_dense_scene_phase_jitter_is_seeded_and_bounded(gait90: GaitConfig) -> None:
    a = dense_scene(SMALL, gait90, 7, seed=3, phase_jitter=0.1)
    assert a == dense_scene(SMALL, gait90, 7, seed=3, phase_jitter=0.1)
    a.validate(SMALL, 0.6)
    phases = np.array([r.gait.phase for r in a.robots])   # type: ignore[union-attr]
    offsets = (phases + 0.5) % 1.0 - 0.5
    assert np.all(np.abs(offsets) <= 0.1) and len(set(phases.tolist())) == 7
    plain = dense_scene(SMALL, gait90, 7, seed=3)
    assert [r.heading for r in a.robots] == [r.heading for r in plain.robots]   # same headings per seed
    with pytest.raises(SceneError, match='phase_jitter'):
        dense_scene(SMALL, gait90, 7, seed=3, phase_jitter=0.7)


def test_pair_scene_places_robot_two(gait90: GaitConfig) -> None:
    scene = pair_scene(SMALL, gait90, 1.6, math.radians(270), math.radians(180), phases=(0.0, 0.25))
    r1, r2 = scene.robots
    r, theta, phi = one_pair((r1.x, r1.y, r1.heading), (r2.x, r2.y, r2.heading))
    assert np.allclose((r / SMALL.body_length, theta, phi), (1.6, math.radians(270), math.pi))
    assert (r1.gait.phase, r2.gait.phase) == (0.0, 0.25)   # type: ignore[union-attr]
    assert (r2.alpha1, r2.alpha2) == pytest.approx((-math.pi / 2, math.pi / 2))   # phase 0.25 starts at c1


def test_overlapping_placements_refused(gait90: GaitConfig) -> None:
    with pytest.raises(SceneError, match='overlap'):
        pair_scene(SMALL, gait90, 1.3, math.pi / 2, math.pi)   # antiparallel U shapes facing each other
    scene = Scene((RobotPlacement(0.0, 0.0, 0.0), RobotPlacement(0.02, 0.0, 1.0)))
    with pytest.raises(SceneError, match='robots 0 .* and 1 .* overlap'):
        scene.validate(SMALL, 0.6)
    with pytest.raises(SceneError, match='off the 0.6 m plate'):
        Scene((RobotPlacement(0.29, 0.0, 0.0),)).validate(SMALL, 0.6)


def test_random_scene_non_overlapping_and_seeded(gait90: GaitConfig) -> None:
    scene = random_scene(SMALL, gait90, 10, seed=5, random_phases=True)
    scene.validate(SMALL, 0.6)
    assert scene == random_scene(SMALL, gait90, 10, seed=5, random_phases=True)
    assert len({r.gait.phase for r in scene.robots}) == 10   # type: ignore[union-attr]
    with pytest.raises(SceneError, match='could not place'):
        random_scene(SMALL, gait90, 30, seed=1, region=0.15, max_tries=300)


def test_a_start_taken_from_a_running_trial_restores_every_robots_state() -> None:
    from smarticle_sim.physics import Physics
    from smarticle_sim.runner import Runner
    from smarticle_sim.scenes import RobotState, dense_scene, state_scene
    from smarticle_sim.config_builder import build_config

    config = build_config('feedback')
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    with Runner.with_gaits(config, dense_scene(config.robot, gait, 3, seed=4)) as runner:
        assert runner.gaits is not None
        runner.gaits.start(0.0)
        runner.run(runner.ticks_for(2.3 * gait.period))     # early in a quarter: the arms are moving
        taken = runner.physics.placements()
    assert any(abs(v) > 0.1 for p in taken for v in p.state.arm_velocities)    # type: ignore[union-attr]
    mean = tuple(np.mean([(p.x, p.y) for p in taken], axis=0))
    with Physics(config, state_scene(taken, [gait] * 3, centre=mean)) as physics:
        again = physics.placements()
    for a, b in zip(taken, again, strict=True):
        assert a.state is not None and b.state is not None
        # PyBullet renormalises the quaternion it is given: equal to rounding (1e-12), not to the bit
        assert (a.alpha1, a.alpha2, a.heading) == pytest.approx((b.alpha1, b.alpha2, b.heading), abs=1e-12)
        assert a.state.values() == pytest.approx(b.state.values(), abs=1e-12)
        assert (a.x, a.y) == pytest.approx((b.x, b.y), abs=1e-15)   # moved by the mean and back
    assert RobotState.from_values(taken[0].state.values()) == taken[0].state    # type: ignore[union-attr]
    with pytest.raises(SceneError, match='13 finite numbers'):
        RobotState.from_values([0.0] * 12)
    with pytest.raises(SceneError, match='has no state'):
        state_scene([RobotPlacement(0.0, 0.0, 0.0)], [gait])


def test_a_restored_scene_may_overlap_by_its_tolerance_and_no_more() -> None:
    from smarticle_sim.scenes import RobotState, state_scene
    from smarticle_sim.config_builder import build_config

    spec = build_config('feedback').robot
    rest = RobotState(spec.body_height / 2.0, (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0))
    # two robots side by side along their bodies' depth, their bodies overlapping by `depth` m
    def pair(depth: float) -> list[RobotPlacement]:
        dy = spec.body_depth - depth
        return [RobotPlacement(0.0, 0.0, math.pi / 2, state=rest), RobotPlacement(0.0, dy, math.pi / 2, state=rest)]

    state_scene(pair(0.001), [None, None]).validate(spec, 1.0)        # 1 mm: a contact of the old trial
    with pytest.raises(SceneError, match='overlap'):
        state_scene(pair(0.004), [None, None]).validate(spec, 1.0)     # 4 mm: more than the 2 mm default
    with pytest.raises(SceneError, match='overlap'):
        state_scene(pair(0.001), [None, None], overlap_tolerance=0.0).validate(spec, 1.0)
    for bad in (-0.001, 0.05, math.nan):
        with pytest.raises(SceneError, match='overlap_tolerance'):
            state_scene(pair(0.001), [None, None], overlap_tolerance=bad)


def test_pair_scene_gives_robot_two_its_own_amplitude(gait90: GaitConfig) -> None:
    """``alpha_max2``: robot 2's gait (and so its start shape) has its own amplitude; robot 1 keeps the gait's."""
    scene = pair_scene(SMALL, gait90, 1.6, math.radians(270), math.radians(180), alpha_max2=math.radians(85))
    first, second = scene.robots
    assert first.gait is not None and second.gait is not None
    assert first.gait.alpha_max == gait90.alpha_max and second.gait.alpha_max == pytest.approx(math.radians(85))
    assert (second.alpha1, second.alpha2) == pytest.approx((math.radians(85), math.radians(85)))
    assert (first.alpha1, first.alpha2) == pytest.approx((gait90.alpha_max, gait90.alpha_max))
