"""The physics knobs (docs/sim_calibration.md, docs/history/physics_study.md): defaults, refusals, values in Bullet."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pybullet
import pytest

from smarticle_common.gait import GaitConfig
from smarticle_sim.config_builder import build_config
from smarticle_sim.diagnostics import Diagnostics
from smarticle_sim.errors import ConfigError
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene
from smarticle_sim.settings import BULLET_SOLVER_RESIDUAL_THRESHOLD, NotConvergedWarning, PhysicsConfig, SimConfig
from smarticle_sim.physics import ARM_JOINTS
from smarticle_sim.runner import Runner


def lone_robot() -> Scene:
    """One robot at the plate centre."""
    return Scene((RobotPlacement(0.0, 0.0, math.pi / 2),), name='lone')


def test_defaults_are_the_converged_model_of_the_calibration() -> None:
    ph = PhysicsConfig()
    assert ph.time_step == pytest.approx(1.0 / 960.0) and ph.solver_iterations == 10
    assert ph.servo_bandwidth == 200.0 and ph.servo_gain() == pytest.approx(200.0 / 960.0)
    assert ph.fsr_window == pytest.approx(1.0 / 480.0) and ph.fsr_steps == 2
    assert ph.restitution == 0.80 and ph.contact_erp == 0.1 and ph.restitution_body_plate == 0.0
    assert ph.restitution_velocity_threshold == 0.01
    assert ph.friction_arm_arm is None and ph.friction_robot_robot == ph.friction_body_plate == 0.3
    assert ph.ccd_swept_sphere_radius == 0.0 and ph.tilt_inertia_scale == 1.0
    assert not Diagnostics().active and SimConfig().diagnostics == Diagnostics()   # the shipped model
    old = PhysicsConfig(servo_bandwidth=None)
    assert old.servo_gain() == old.position_gain          # the per-step gain of the old servo loop


def test_servo_bandwidth_fixes_the_approach_whatever_the_step() -> None:
    for steps in (240, 480, 960):
        ph = PhysicsConfig(time_step=1.0 / steps, control_tick=1.0 / 60.0, servo_bandwidth=72.0)
        assert ph.servo_gain() / ph.time_step == pytest.approx(72.0)
    assert PhysicsConfig(servo_bandwidth=1e6).servo_gain() == 1.0   # capped: arrive within one step


@pytest.mark.parametrize('field', ['servo_bandwidth', 'tilt_inertia_scale', 'yaw_inertia_scale'])
def test_non_positive_knobs_refused(field: str) -> None:
    with pytest.raises(ConfigError, match=field):
        (Diagnostics if field == 'yaw_inertia_scale' else PhysicsConfig)(**{field: 0.0})


def test_large_packs_get_more_solver_iterations(config: SimConfig, gait90: GaitConfig) -> None:
    """Above ``large_pack_robots`` robots Bullet is stepped with ``large_pack_iterations`` (never fewer)."""
    ph = PhysicsConfig()
    assert (ph.large_pack_robots, ph.large_pack_iterations) == (7, 20)
    assert [ph.iterations_for(n) for n in (1, 2, 7, 8, 50)] == [10, 10, 10, 20, 20]
    assert PhysicsConfig(solver_iterations=30).iterations_for(50) == 30
    assert PhysicsConfig(large_pack_robots=100).iterations_for(50) == 10
    for n, expected in ((7, 10), (8, 20)):
        with Runner.with_gaits(config, dense_scene(config.robot, gait90, n, seed=1)) as run:
            assert run.physics.client.getPhysicsEngineParameters()['numSolverIterations'] == expected
    with pytest.raises(ConfigError, match='large_pack_iterations'):
        PhysicsConfig(large_pack_iterations=0)


def test_restitution_body_plate_above_one_refused() -> None:
    with pytest.raises(ConfigError, match='restitution_body_plate'):
        PhysicsConfig(restitution_body_plate=1.5)


def test_bullet_gets_the_restitutions_and_the_tilt_inertia(config: SimConfig) -> None:
    """Bullet multiplies the links' restitutions: robot-robot 0.85, body-plate 0; roll / pitch inertia x 100."""
    plain = config.with_physics(restitution=0.85, tilt_inertia_scale=1.0)
    tuned = config.with_physics(restitution=0.85, restitution_body_plate=0.0, tilt_inertia_scale=100.0)
    with Runner.with_gaits(plain, lone_robot()) as run:
        world = run.physics
        inertia = world.client.getDynamicsInfo(world.body_ids[0], -1)[2]
    with Runner.with_gaits(tuned, lone_robot()) as run:
        world = run.physics
        c, body = world.client, world.body_ids[0]
        restitution = {link: c.getDynamicsInfo(body, link)[5] for link in (-1, *ARM_JOINTS)}
        assert restitution[-1] * restitution[ARM_JOINTS[0]] == pytest.approx(0.85, rel=1e-5)
        assert restitution[-1] * c.getDynamicsInfo(world.plate_id, -1)[5] == pytest.approx(0.0, abs=1e-9)
        scaled = c.getDynamicsInfo(body, -1)[2]
        assert scaled == pytest.approx([100.0 * inertia[0], 100.0 * inertia[1], inertia[2]], rel=1e-5)


def test_round_arm_ends_keep_the_arm_and_round_its_end_edges(config: SimConfig) -> None:
    """'round' arms: a box of length L - t between two vertical cylinders of diameter t; mass and inertia kept."""
    spec = config.robot
    shapes, inertia = {}, {}   # per arm_ends: the arm's collision shapes, its (mass, inertia diagonal)
    for ends in ('square', 'round'):
        with Runner.with_gaits(config.with_diagnostics(arm_ends=ends), lone_robot()) as run:
            world = run.physics
            c, body = world.client, world.body_ids[0]
            shapes[ends] = c.getCollisionShapeData(body, ARM_JOINTS[0])
            info = c.getDynamicsInfo(body, ARM_JOINTS[0])
            inertia[ends] = (info[0], info[2])
    assert [s[2] for s in shapes['square']] == [3]                          # GEOM_BOX
    assert [s[2] for s in shapes['round']] == [3, 4, 4]                     # box + two GEOM_CYLINDERs
    box, cap1, cap2 = shapes['round']
    assert box[3][0] == pytest.approx(spec.arm_length - spec.arm_thickness)
    assert box[3][1] == pytest.approx(spec.arm_thickness) and box[3][2] == pytest.approx(spec.arm_height)
    for cap in (cap1, cap2):
        assert cap[3][0] == pytest.approx(spec.arm_height) and cap[3][1] == pytest.approx(spec.arm_thickness / 2)
    # the caps sit at the box's ends, so the arm spans its full length
    assert abs(cap2[5][0] - cap1[5][0]) == pytest.approx(spec.arm_length - spec.arm_thickness)
    assert inertia['round'][0] == inertia['square'][0] == spec.arm_mass
    assert inertia['round'][1] == pytest.approx(inertia['square'][1], rel=1e-9)


def test_unknown_arm_ends_refused() -> None:
    with pytest.raises(ConfigError, match='arm_ends'):
        Diagnostics(arm_ends='oval')


def test_soft_contacts_give_bullet_the_spring_and_the_damping_of_the_restitution(config: SimConfig) -> None:
    """contact_stiffness k: each robot link 2k and half the pair's damping, whose spring-dashpot rebound is e."""
    assert config.physics.soft_contact(config.robot.total_mass) is None   # rigid contacts by default
    soft = config.with_physics(contact_stiffness=2000.0, restitution=0.85, time_step=1 / 12000)
    mass = soft.robot.total_mass
    link_k, link_c, plate_c = soft.physics.soft_contact(mass)
    pair_k, pair_c = 1.0 / (2.0 / link_k), 2.0 * link_c      # Bullet: stiffnesses in series, dampings added
    assert pair_k == pytest.approx(2000.0)
    zeta = pair_c / (2.0 * math.sqrt(pair_k * mass / 2.0))
    assert math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta ** 2)) == pytest.approx(0.85, rel=1e-9)
    assert link_c + plate_c == pytest.approx(2.0 * math.sqrt(link_k * mass))   # body on the plate: critical
    with Runner.with_gaits(soft, lone_robot()) as run:
        c, body = run.physics.client, run.physics.body_ids[0]
        for link in (-1, *ARM_JOINTS):
            info = c.getDynamicsInfo(body, link)
            assert (info[9], info[8], info[5]) == pytest.approx((link_k, link_c, 0.0))   # no restitution impulse
        assert c.getDynamicsInfo(run.physics.plate_id, -1)[8] == pytest.approx(plate_c)
        run.run(run.ticks_for(0.5))
        state = run.physics.state()
        assert state.positions[0, 2] == pytest.approx(config.robot.body_height / 2.0, abs=2e-4)   # on the plate
        assert state.speed[0] < 0.05


def test_soft_contacts_at_a_coarse_step_warn_with_the_field_named(config: SimConfig) -> None:
    with pytest.warns(NotConvergedWarning, match='PhysicsConfig.contact_stiffness'):
        config.with_physics(contact_stiffness=2000.0)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        config.with_physics(contact_stiffness=2000.0, time_step=1 / 12000)
    with pytest.raises(ConfigError, match='contact_stiffness'):
        PhysicsConfig(contact_stiffness=0.0)


def test_solver_residual_threshold_reaches_bullet(config: SimConfig, gait90: GaitConfig) -> None:
    """None leaves Bullet's own threshold (1e-7): the same trajectory as setting it; a loose one stops the
    solver early and moves the robots; a negative or zero one is refused with the field named."""
    def poses_after(threshold: float | None):
        with Runner.with_gaits(config.with_physics(solver_residual_threshold=threshold),
                               dense_scene(config.robot, gait90, 2, seed=1)) as run:
            run.run(run.ticks_for(0.8))
            return run.physics.poses()

    unset = poses_after(None)
    assert (poses_after(BULLET_SOLVER_RESIDUAL_THRESHOLD) == unset).all()
    assert abs(poses_after(1.0) - unset).max() > 1e-6
    for bad in (0.0, -1e-5):
        with pytest.raises(ConfigError, match='solver_residual_threshold'):
            PhysicsConfig(solver_residual_threshold=bad)


def test_bullet_gets_the_yaw_inertia_and_only_it(config: SimConfig) -> None:
    """``yaw_inertia_scale`` scales the body's inertia about the plate normal; roll, pitch and mass stay."""
    with Runner.with_gaits(config, lone_robot()) as run:
        world = run.physics
        mass, _, inertia = world.client.getDynamicsInfo(world.body_ids[0], -1)[:3]
    with Runner.with_gaits(config.with_diagnostics(yaw_inertia_scale=0.129), lone_robot()) as run:
        world = run.physics
        light_mass, _, light = world.client.getDynamicsInfo(world.body_ids[0], -1)[:3]
        run.run(60)
        moved = world.poses()[0].copy()
    with Runner.with_gaits(config, lone_robot()) as run:
        run.run(60)
        assert not np.array_equal(run.physics.poses()[0], moved)   # the light body turns differently
    assert light_mass == mass
    assert light[:2] == pytest.approx(inertia[:2], rel=1e-6)
    assert light[2] == pytest.approx(0.129 * inertia[2], rel=1e-6)


def test_bullet_gets_the_authors_masses_and_inertias(config: SimConfig) -> None:
    """``mass_model`` 'authors': 24.8 g body, arms of 3.19 and 0.345 g, every link the inertia of a 100 kg/m^3 box."""
    authors = config.with_diagnostics(mass_model='authors')
    with Runner.with_gaits(authors, lone_robot()) as run:
        info = [run.physics.client.getDynamicsInfo(run.physics.body_ids[0], link)[:3] for link in (-1, *ARM_JOINTS)]
    (body_mass, _, body_inertia), (arm1_mass, _, arm1_inertia), (arm2_mass, _, arm2_inertia) = info
    assert body_mass == pytest.approx(0.0248) and arm1_mass == pytest.approx(0.00319)
    assert arm2_mass == pytest.approx(100.0 * 0.05 * 0.003 * 0.023)            # its 100 kg/m^3 box: 0.345 g
    w, d, h = config.robot.body_width, config.robot.body_depth, config.robot.body_height
    box = 100.0 * w * d * h                                                    # 3.2 g
    assert body_inertia == pytest.approx([box * (d * d + h * h) / 12, box * (w * w + h * h) / 12,
                                          box * (w * w + d * d) / 12], rel=1e-6)
    assert arm1_inertia == pytest.approx(arm2_inertia, rel=1e-6)                # the same box, unscaled by the mass
    assert arm1_inertia[2] == pytest.approx(arm2_mass * (0.05 ** 2 + 0.003 ** 2) / 12, rel=1e-6)


def test_mass_model_refused_where_it_means_nothing(config: SimConfig) -> None:
    with pytest.raises(ConfigError, match='mass_model'):
        Diagnostics(mass_model='measured')
    with pytest.raises(ConfigError, match="mass_model 'authors'"):
        build_config('feedback', diagnostics={'mass_model': 'authors'})


def creep(config: SimConfig, push: float, seconds: float = 0.5) -> tuple[float, float]:
    """A lone robot (arms still) pushed sideways by ``push`` x its weight x the plate's mu: how far it went (m),
    and Bullet's body-plate friction coefficient in that world."""
    from smarticle_sim.physics import Physics
    with Physics(config, lone_robot()) as world:
        world.step(world.ticks_for(0.2) * world.steps_per_tick)           # settle on the plate
        start = world.body_xy()[0].copy()
        force = push * config.physics.friction_body_plate * config.robot.total_mass * config.physics.gravity
        for _ in range(round(seconds / config.physics.time_step)):
            world.client.applyExternalForce(world.body_ids[0], -1, (force, 0.0, 0.0), (0.0, 0.0, 0.0),
                                            pybullet.LINK_FRAME)
            world.step(1)
        return float(np.linalg.norm(world.body_xy()[0] - start)), world.plate_friction(0)


def test_a_plate_without_static_friction_lets_a_small_push_creep(config: SimConfig) -> None:
    """``plate_friction_slip``: a push of 0.3 mu m g holds still on Coulomb's plate and creeps on the regularised one
    at about 0.3 of the slip speed (viscous below it); a push above mu m g slides on both."""
    held, mu = creep(config, 0.3)
    assert held < 1e-4 and mu == pytest.approx(0.3)
    slip = 0.02
    regularised = config.with_diagnostics(plate_friction_slip=slip)
    crept, bullet_mu = creep(regularised, 0.3)
    assert bullet_mu == 0.0                                                 # Bullet's own friction is off there
    assert crept == pytest.approx(0.3 * slip * 0.5, rel=0.25)               # v = push x slip, for 0.5 s
    assert creep(config, 1.5)[0] > 0.01 and creep(regularised, 1.5)[0] > 0.01


def test_plate_friction_slip_refused_or_warned() -> None:
    with pytest.raises(ConfigError, match='plate_friction_slip'):
        Diagnostics(plate_friction_slip=0.0)
    with pytest.raises(ConfigError, match='plate_friction_slip'):
        SimConfig().with_diagnostics(plate_friction_slip=0.01).with_noise(friction_sd=0.06)
    with pytest.warns(NotConvergedWarning, match='plate_friction_slip'):
        SimConfig().with_diagnostics(plate_friction_slip=0.001)
