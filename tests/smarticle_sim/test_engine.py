"""The one engine interface: the Runner steps MuJoCo as it steps Bullet, with FSR forces, feedback, noise and
trouble checks."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig
from smarticle_feedback.controller import ImpactController
from smarticle_feedback.parameters import config_from_values, default_values

from smarticle_experiments.p6 import COLLIDING_START
from smarticle_sim.batch import run_trial
from smarticle_sim.config_builder import build_config
from smarticle_sim.engine import Engine
from smarticle_sim.engines import engine_factory
from smarticle_sim.errors import ConfigError, SceneError
from smarticle_sim.mujoco_engine import MujocoPhysics, MujocoSettings, run_mujoco
from smarticle_sim.physics import Physics
from smarticle_sim.runner import Controller, FeedbackController, GaitController, Runner
from smarticle_sim.scenes import Scene, pair_scene
from smarticle_sim.settings import NoiseConfig, SimConfig


def colliding_pair() -> tuple[SimConfig, GaitConfig, Scene]:
    """P6's start where the feedback robots collide at once (seed 0: the start itself)."""
    config = build_config('feedback')
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    r, theta, phi, phases = COLLIDING_START
    scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases=phases, seed=0)
    return config, gait, scene


def feedback_trial(engine: str, feedback: bool, periods: float = 3.0) -> tuple[list, np.ndarray]:
    """The colliding pair with (or without) each robot's impact controller: (halts, poses)."""
    config, gait, scene = colliding_pair()
    found: list[FeedbackController] = []

    def add(_: Engine, gaits: GaitController) -> list[Controller]:
        if not feedback:
            return []
        values = config_from_values(default_values())
        policies = {k: ImpactController(replace(values, period=gait.period, phase=p))
                    for k, p in enumerate(COLLIDING_START[3])}
        for policy in policies.values():
            policy.start(0.0)
        found.append(FeedbackController(gaits, policies))
        return list(found)

    rec = run_trial(config, scene, periods, sample_every=3, controllers=add, engine=engine_factory(engine))
    assert rec.trouble == ''
    return (found[0].halts if found else []), rec.poses


@pytest.mark.parametrize('engine', ['bullet', 'mujoco'])
def test_the_feedback_halts_a_colliding_pair_in_either_engine(engine: str) -> None:
    halts, poses = feedback_trial(engine, True)
    assert halts, f'{engine}: the colliding start must halt a robot'
    assert {robot for _, robot, _ in halts} <= {0, 1}
    assert all(face for _, _, face in halts)
    open_halts, open_poses = feedback_trial(engine, False)
    assert open_halts == []
    assert not np.array_equal(poses, open_poses), 'halting changes the pair'


def test_mujoco_fsr_forces_are_zero_without_contact_and_on_the_touched_face() -> None:
    """Step the colliding pair servo update by servo update: an arm without a contact point reads 0 on both
    faces; an arm touched on one side only (the contact point's side of the arm, from geometry) reads a
    force on that face's FSR and none on the other."""
    config, _, scene = colliding_pair()
    runner = Runner.with_gaits(config, scene, engine=engine_factory('mujoco'))
    physics = runner.physics
    assert isinstance(physics, MujocoPhysics)
    model, data = physics.model, physics.data
    arm_geoms = {(k, j): model.geom(f'robot{k}_arm{j}_geom').id for k in range(2) for j in (0, 1)}
    half_thickness = config.robot.arm_thickness / 2.0
    counts = {'touched': 0, 'untouched': 0}

    def check(_: Runner) -> None:   # after every servo update
        fsr = physics.fsr()
        for (k, j), geom in arm_geoms.items():
            points = [i for i in range(data.ncon) if geom in (data.contact.geom1[i], data.contact.geom2[i])]
            if not points:
                assert fsr[k, 2 * j] == 0.0 and fsr[k, 2 * j + 1] == 0.0
                counts['untouched'] += 1
                continue
            link = model.body(f'robot{k}_link{j}').id
            front = data.xmat[link].reshape(3, 3)[:, 1]
            offsets = [(data.contact.pos[i] - data.xipos[link]) @ front for i in points]
            if len(points) == 1 and abs(offsets[0]) > 0.5 * half_thickness and fsr[k, 2 * j:2 * j + 2].any():
                face = 0 if offsets[0] > 0 else 1     # 0: front, 1: back
                assert fsr[k, 2 * j + face] > 0.0 and fsr[k, 2 * j + 1 - face] == 0.0, (k, j, fsr[k])
                counts['touched'] += 1

    runner.step_hooks.append(check)
    runner.gaits.start(0.0)   # type: ignore[union-attr]
    runner.run(runner.ticks_for(2.0 * 1.6))
    touched, untouched = counts['touched'], counts['untouched']
    assert touched >= 5 and untouched > touched


def test_the_same_seed_gives_the_same_mujoco_trajectory_with_noise() -> None:
    """All three noise sources on: a seed repeats bit for bit, another seed differs, and noise changes the run."""
    config, _, scene = colliding_pair()
    noisy = config.with_noise(NoiseConfig(friction_sd=0.2))

    def run(cfg: SimConfig, seed: int) -> np.ndarray:
        return run_trial(cfg, replace(scene, seed=seed), 2.0, sample_every=3,
                         engine=engine_factory('mujoco')).poses

    first, again, other = run(noisy, 1), run(noisy, 1), run(noisy, 2)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)
    assert not np.array_equal(first, run(config, 1))


def test_the_friction_field_sets_each_body_s_plate_friction_in_mujoco() -> None:
    config, _, scene = colliding_pair()
    with MujocoPhysics(config.with_noise(NoiseConfig(friction_sd=0.2)), scene) as physics:
        pairs = [physics.model.pair(f'robot{k}_body_plate').id for k in range(2)]
        mu = physics.model.pair_friction[pairs, 0]
        field = physics.friction_field
        assert field is not None
        expected = field.factor(physics.body_xy()) * max(config.physics.friction_body_plate,
                                                         config.physics.friction_robot_robot)
        assert mu == pytest.approx(expected)
        assert mu[0] != mu[1]


def test_mujoco_has_bullet_s_trouble_checks(config: SimConfig, gait90: GaitConfig) -> None:
    """A tilt limit no robot can keep ends the run with Bullet's trouble message."""
    scene = pair_scene(config.robot, gait90, 1.3, math.radians(330.0), math.radians(180.0), (0.0, 0.1))
    rec = run_mujoco(config.with_physics(max_tilt=1e-9), scene, 1.0, sample_every=3)
    assert 'body tilt' in rec.trouble and 'tipped over' in rec.trouble
    assert len(rec.time) < 1.0 * gait90.period / (3 * config.physics.control_tick)


def test_both_engines_implement_the_interface(config: SimConfig, gait90: GaitConfig) -> None:
    """The same scene in either engine: the same robots at the start, the same time per tick, robots checked
    alike, and a bad engine name is one clear error."""
    scene = pair_scene(config.robot, gait90, 1.3, math.radians(330.0), math.radians(180.0), (0.0, 0.1))
    worlds: list[Engine] = [Physics(config, scene), MujocoPhysics(config, scene, MujocoSettings())]
    for world in worlds:
        gaits = GaitController.for_scene(world)
        runner = Runner(world, [gaits])
        gaits.start(0.0)
        runner.run(6)
        assert world.time == pytest.approx(6 * config.physics.control_tick)
        assert world.fsr().shape == (2, 4) and world.robot_contacts().shape == (2, 2)
        with pytest.raises(SceneError, match='unknown robot 2'):
            world.check_robot(2)
    bullet, mujoco = worlds
    assert np.abs(bullet.arm_angles() - mujoco.arm_angles()).max() < 0.05   # the same gait drives both
    for world in worlds:
        world.close()
    with pytest.raises(ConfigError, match="unknown engine 'ode'"):
        engine_factory('ode')
