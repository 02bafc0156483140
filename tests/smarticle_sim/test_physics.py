"""The physics: bodies, servos, FSR faces, ground truth, determinism and trouble detection."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pybullet
import pytest
from smarticle_common.gait import GaitConfig
from smarticle_common.topics import FSR_FACES

from smarticle_sim.errors import ConfigError, SceneError, SimError, SimTrouble
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene
from smarticle_common.facts import SMALL
from smarticle_sim.settings import SimConfig
from smarticle_sim.trouble import check_state
from smarticle_sim.physics import ARM_JOINTS, FsrReading, Physics
from smarticle_sim.runner import Runner

def lone_robot(heading: float = math.pi / 2, alpha1: float = 0.0, alpha2: float = 0.0,
               gait: GaitConfig | None = None) -> Scene:
    """One robot at the plate centre (heading pi/2: body frame = arena frame)."""
    return Scene((RobotPlacement(0.0, 0.0, heading, alpha1, alpha2, gait),), name='lone')


def test_bodies_have_the_specified_masses_and_sizes(config: SimConfig) -> None:
    with Runner.with_gaits(config, lone_robot()) as run:
        world = run.physics
        c, body = world.client, world.body_ids[0]
        masses = [c.getDynamicsInfo(body, link)[0] for link in (-1, 0, 1)]
        assert sum(masses) == pytest.approx(SMALL.total_mass)
        lo, hi = np.array(c.getAABB(body, -1))
        assert hi - lo == pytest.approx([SMALL.body_width, SMALL.body_depth, SMALL.body_height], abs=2e-3)
        assert lo[2] == pytest.approx(0.0, abs=1e-3)    # the body rests on the plate top (z = 0)
        for link, sign in ((0, -1), (1, 1)):
            lo, hi = np.array(c.getAABB(body, link))
            assert hi[0] - lo[0] == pytest.approx(SMALL.arm_length, abs=2e-3)
            centre_x = sign * (lo[0] + hi[0]) / 2
            assert centre_x == pytest.approx((SMALL.body_width + SMALL.arm_length) / 2, abs=1e-3)
            assert lo[2] == pytest.approx(SMALL.arm_clearance, abs=1e-3)


def test_bullet_gets_the_link_frictions_of_the_config(config: SimConfig) -> None:
    """Bullet multiplies the two links' values: arm-arm, arm-body and body-plate come out as configured."""
    config = config.with_physics(friction_arm_arm=1.5)
    with Runner.with_gaits(config, lone_robot()) as run:
        world = run.physics
        c, body = world.client, world.body_ids[0]
        friction = {link: c.getDynamicsInfo(body, link)[1] for link in (-1, *ARM_JOINTS)}
        plate = c.getDynamicsInfo(world.plate_id, -1)[1]
        arm = friction[ARM_JOINTS[0]]
        assert friction[ARM_JOINTS[1]] == pytest.approx(arm)
        assert arm * arm == pytest.approx(1.5, rel=1e-5)
        assert arm * friction[-1] == pytest.approx(config.physics.friction_robot_robot, rel=1e-5)
        assert friction[-1] * plate == pytest.approx(config.physics.friction_body_plate, rel=1e-5)


def test_joint_angle_is_alpha_and_heading_is_the_normal(config: SimConfig) -> None:
    """alpha_i > 0 turns arm i's tip toward the body normal; the pose heading is that normal."""
    heading = 0.4
    with Runner.with_gaits(config, lone_robot(heading, math.pi / 2, math.pi / 2)) as run:
        world = run.physics
        c, body = world.client, world.body_ids[0]
        x, y, h = world.poses()[0]
        assert h == pytest.approx(heading, abs=1e-6)
        normal = np.array([math.cos(heading), math.sin(heading)])
        for link in ARM_JOINTS:
            tip_dir = np.array(c.getLinkState(body, link)[0][:2]) - (x, y)
            assert tip_dir @ normal == pytest.approx(SMALL.arm_length / 2, abs=1e-4)
        assert world.arm_angles()[0] == pytest.approx([math.pi / 2, math.pi / 2])


def test_servo_tracks_target_at_speed_limit(config: SimConfig) -> None:
    with Runner.with_gaits(config, lone_robot()) as run:
        world = run.physics
        world.command(0, (1.0, -1.0), speed=5.0)
        run.run(world.ticks_for(0.1))
        moved = world.arm_angles()[0]
        assert moved == pytest.approx([0.5, -0.5], abs=0.05)           # 5 rad/s for 0.1 s
        assert np.abs(world.arm_velocities()[0]) == pytest.approx([5.0, 5.0], rel=0.05)
        run.run(world.ticks_for(0.3))
        assert world.arm_angles()[0] == pytest.approx([1.0, -1.0], abs=0.01)
        world.command(0, (0.0, 0.0), speed=100.0)             # capped at the servo's top speed
        run.run(1)
        assert np.abs(world.arm_velocities()[0]).max() <= SMALL.servo_speed * 1.02


def test_gait_core_drives_the_arms(config: SimConfig, gait90: GaitConfig) -> None:
    a = gait90.alpha_max
    with Runner.with_gaits(config, lone_robot(alpha1=a, alpha2=a, gait=gait90)) as run:
        world = run.physics
        run.gaits.start(0.0)
        run.run(world.ticks_for(0.4))            # quarter 0: arm 1 from +a to -a
        assert world.arm_angles()[0] == pytest.approx([-a, a], abs=0.02)
        run.run(world.ticks_for(0.4))            # quarter 1: arm 2 from +a to -a
        assert world.arm_angles()[0] == pytest.approx([-a, -a], abs=0.02)
        assert run.gaits.halt(0)
        held = world.arm_angles()[0].copy()
        run.run(world.ticks_for(0.3))
        assert world.arm_angles()[0] == pytest.approx(held, abs=0.02)


def test_arms_never_touch_the_plate(gait90: GaitConfig) -> None:
    """Even with arm-plate collisions enabled, a running gait leaves the arms clear of the plate."""
    config = SimConfig().with_physics(arm_plate_collision=True)
    scene = dense_scene(config.robot, gait90, 3, seed=2)
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        run.gaits.start(0.0)
        for _ in range(world.ticks_for(3.2)):
            run.tick()
            for body in world.body_ids:
                for link in ARM_JOINTS:
                    touching = world.client.getContactPoints(bodyA=body, bodyB=world.plate_id,
                                                             linkIndexA=link)
                    assert not touching
                    assert world.client.getAABB(body, link)[0][2] > 0.0


@pytest.mark.parametrize('arm, side', [(0, 1), (0, -1), (1, 1), (1, -1)])
def test_fsr_push_shows_on_one_face_only(config: SimConfig, arm: int, side: int) -> None:
    """A fixed block beside one arm: turning the arm into it loads that face and no other."""
    heavy = replace(config, robot=replace(SMALL, total_mass=5.0))   # friction then holds the body still
    with Runner.with_gaits(heavy, lone_robot()) as run:
        world = run.physics
        c = world.client
        x_sign = -1.0 if arm == 0 else 1.0
        centre = [x_sign * (SMALL.body_width / 2 + 0.035), side * 0.009, SMALL.body_height / 2]
        block = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[0.006, 0.004, 0.01])
        c.createMultiBody(0.0, block, -1, centre)
        targets = [0.0, 0.0]
        targets[arm] = side * 0.6                  # alpha > 0 turns toward +y: the front face leads
        world.command(0, (targets[0], targets[1]))
        run.run(world.ticks_for(0.3))
        forces = world.fsr([0])[0]
        face = 2 * arm + (0 if side > 0 else 1)
        assert forces[face] > 0.5, dict(zip(FSR_FACES, forces, strict=True))
        assert np.delete(forces, face) == pytest.approx(0.0, abs=1e-9)
        assert world.fsr([]).shape == (0, 4)


@pytest.mark.parametrize('dt_inv, window_steps', [(480, 1), (960, 2), (1920, 4)])
def test_fsr_reading_averages_over_the_fsr_window(gait90: GaitConfig, dt_inv: int, window_steps: int) -> None:
    """The FSR reading is the force of the last fsr_window (1/480 s) of steps, whatever the time step."""
    config = SimConfig().with_physics(time_step=1.0 / dt_inv)
    assert config.physics.fsr_steps == window_steps
    with Runner.with_gaits(config, dense_scene(config.robot, gait90, 7, seed=1)) as run:
        world = run.physics
        reading = FsrReading(world, [0, 1, 2])
        raw: list[np.ndarray] = []
        compared = loaded = 0

        def on_step(_: Runner) -> None:
            nonlocal compared, loaded
            got = reading.step()
            raw.append(world.fsr([0, 1, 2]))
            if len(raw) >= window_steps:
                assert got == pytest.approx(np.mean(raw[-window_steps:], axis=0), abs=1e-12)
                compared += 1
                loaded += bool(got.any())

        run.step_hooks.append(on_step)
        run.gaits.start(0.0)
        run.run(world.ticks_for(1.6))
        assert compared > 100 and loaded > 0   # the robots collided, so the readings were not all zero
    with pytest.raises(ConfigError, match='fsr_window'):
        SimConfig().with_physics(fsr_window=0.0)


def test_robot_contacts_and_penetration(config: SimConfig, gait90: GaitConfig) -> None:
    scene = dense_scene(config.robot, gait90, 7, seed=1)
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        run.gaits.start(0.0)
        seen = np.zeros((7, 7), dtype=bool)
        for _ in range(world.ticks_for(1.6)):
            run.tick()
            touching = world.robot_contacts()
            assert (touching == touching.T).all() and not touching.diagonal().any()
            seen |= touching
        assert seen.any()
        assert world.max_penetration()[1] < config.physics.max_penetration


def test_same_seed_same_trajectory(config: SimConfig, gait90: GaitConfig) -> None:
    def trajectory(seed: int) -> np.ndarray:
        with Runner.with_gaits(config, dense_scene(config.robot, gait90, 7, seed=seed)) as run:
            world = run.physics
            run.gaits.start(0.0)
            out = []
            for _ in range(world.ticks_for(1.6)):
                run.tick()
                out.append(np.concatenate([world.poses().ravel(), world.arm_angles().ravel()]))
            return np.array(out)

    first = trajectory(4)
    assert np.array_equal(first, trajectory(4))        # bitwise
    assert not np.array_equal(first, trajectory(5))


def test_unknown_robot_and_bad_commands_refused(config: SimConfig) -> None:
    with Runner.with_gaits(config, lone_robot()) as run:
        world = run.physics
        with pytest.raises(SceneError, match='unknown robot 3'):
            world.command(3, (0.0, 0.0))
        with pytest.raises(SimError, match='finite'):
            world.command(0, (math.nan, 0.0))
        with pytest.raises(SimError, match='speed'):
            world.command(0, (0.0, 0.0), speed=-1.0)


def test_overlapping_scene_not_simulated(config: SimConfig) -> None:
    scene = Scene((RobotPlacement(0.0, 0.0, 0.0), RobotPlacement(0.01, 0.01, 0.0)))
    with pytest.raises(SceneError, match='overlap'):
        Physics(config, scene)


def test_trouble_on_injected_nan(config: SimConfig) -> None:
    with Runner.with_gaits(config, Scene((RobotPlacement(-0.1, 0.0, 0.0), RobotPlacement(0.1, 0.0, 0.0)))) as run:
        world = run.physics
        run.run(6)
        world.client.resetBaseVelocity(world.body_ids[1], [math.nan, 0.0, 0.0], [0.0, 0.0, 0.0])
        with pytest.raises(SimTrouble) as info:
            run.run(12)
        assert info.value.robot == 1 and 'not finite' in str(info.value)
        assert 'robot 1 at t =' in str(info.value)


def test_trouble_on_lasting_penetration_not_on_a_spike(config: SimConfig, monkeypatch: pytest.MonkeyPatch) -> None:
    """A contact deeper than the bound at one check is a spike the solver pushes out; at 3 in a row, trouble."""
    scene = Scene((RobotPlacement(-0.1, 0.0, math.pi / 2), RobotPlacement(0.1, 0.0, math.pi / 2)))
    every = config.physics.trouble_every
    deep = config.physics.max_penetration * 1.5
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        depths = iter([deep, 0.0, deep, deep, 0.0, deep, deep, deep])
        monkeypatch.setattr(world, 'max_penetration', lambda: (1, next(depths)))
        run.run(5 * every)                     # deep at checks 1, 3, 4: never 3 in a row
        with pytest.raises(SimTrouble, match=r'robot 1 .* penetration depth .* 3 checks in a row: bodies are '
                                             r'tunnelling'):
            run.run(3 * every)


def test_trouble_check_names_robot_time_quantity(config: SimConfig) -> None:
    positions = np.zeros((3, 3))
    positions[2, 0] = 0.5
    with pytest.raises(SimTrouble, match=r'robot 2 at t = 1\.5000 s: distance .* left the plate.*physical end'
                       ) as left:
        check_state(1.5, positions, np.zeros(3), np.zeros(3), np.zeros((3, 2)), config.physics, 0.027)
    assert left.value.physical
    with pytest.raises(SimTrouble, match='robot 0 .* tilt.*lower the time step') as tipped:
        check_state(0.0, np.zeros((3, 3)), np.array([1.0, 0, 0]), np.zeros(3), np.zeros((3, 2)),
                    config.physics, 0.027)
    assert not tipped.value.physical
    with pytest.raises(SimTrouble, match='robot 1 .* speed'):
        check_state(0.0, np.zeros((3, 3)), np.zeros(3), np.array([0, 9.0, 0]), np.zeros((3, 2)),
                    config.physics, 0.027)


def test_trouble_on_absurd_time_step(gait90: GaitConfig) -> None:
    # SimConfig refuses such a step (test_settings), so the fault is injected into Bullet after the build
    config = SimConfig().with_physics(trouble_every=1)
    with Runner.with_gaits(config, dense_scene(config.robot, gait90, 7, seed=1)) as run:
        world = run.physics
        world.client.setPhysicsEngineParameter(fixedTimeStep=0.1)
        run.gaits.start(0.0)
        with pytest.raises(SimTrouble):
            run.run(world.ticks_for(16.0))
