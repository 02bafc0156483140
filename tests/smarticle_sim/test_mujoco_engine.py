"""The cross-engine check: the same robots, scene and gait in MuJoCo as in Bullet."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from smarticle_common.gait import GaitConfig

from smarticle_sim.errors import SimError
from smarticle_sim.mujoco_engine import HertzLaw, MujocoSettings, build_model, hertz_contact_forces, run_mujoco
from smarticle_sim.physics import ARM_JOINTS, Physics
from smarticle_sim.scenes import RobotPlacement, Scene, pair_scene
from smarticle_sim.settings import SimConfig


def p5_pair(config: SimConfig, gait: GaitConfig, phase2: float = 0.1) -> Scene:
    """P5's start (r 1.3 BL, theta 330, phi 180), robot 2 ``phase2`` of a period ahead (its arm part-way)."""
    return pair_scene(config.robot, gait, 1.3, math.radians(330.0), math.radians(180.0), (0.0, phase2))


@pytest.mark.parametrize('mass_model', ['uniform', 'authors'])
def test_the_mujoco_robots_are_the_bullet_robots(config: SimConfig, gait90: GaitConfig, mass_model: str) -> None:
    """Every link's centre of mass, mass and inertia are where and what Bullet has them (the authors' uneven
    arms too)."""
    config = config.with_diagnostics(mass_model=mass_model)
    scene = p5_pair(config, gait90)
    model = build_model(config, scene, MujocoSettings())
    data = mujoco.MjData(model)
    for k, robot in enumerate(scene.robots):
        for j, alpha in enumerate((robot.alpha1, robot.alpha2)):
            data.qpos[model.jnt_qposadr[model.joint(f'robot{k}_arm{j}').id]] = alpha
    mujoco.mj_forward(model, data)
    with Physics(config, scene) as physics:
        c = physics.client
        for k, body in enumerate(physics.body_ids):
            base = np.array(c.getBasePositionAndOrientation(body)[0])
            assert data.xipos[model.body(f'robot{k}').id] == pytest.approx(base, abs=1e-9)
            for j, link in enumerate(ARM_JOINTS):
                com = np.array(c.getLinkState(body, link)[0])
                assert data.xipos[model.body(f'robot{k}_link{j}').id] == pytest.approx(com, abs=1e-9)
                assert model.body(f'robot{k}_link{j}').mass[0] == pytest.approx(c.getDynamicsInfo(body, link)[0])
                assert model.body(f'robot{k}_link{j}').inertia == pytest.approx(c.getDynamicsInfo(body, link)[2])
            assert model.body(f'robot{k}').mass[0] == pytest.approx(c.getDynamicsInfo(body, -1)[0])
            assert model.body(f'robot{k}').inertia == pytest.approx(c.getDynamicsInfo(body, -1)[2])
    # the arms of one robot never collide with each other; robots and plate do
    assert model.nexclude == len(scene.robots)


def test_a_lone_robot_follows_its_gait(config: SimConfig, gait90: GaitConfig) -> None:
    """At every quarter boundary the arms stand at the gait's corner (the servo's lag under its own load)."""
    a = gait90.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, math.pi / 2.0, a, a, gait90),), name='lone')
    rec = run_mujoco(config, scene, 1.0, sample_every=1, settings=MujocoSettings())
    per_quarter = round(gait90.period / 4.0 / config.physics.control_tick)
    for q in range(1, 5):
        assert rec.arm_angles[q * per_quarter, 0] == pytest.approx(gait90.corner(q), abs=0.02)
    assert rec.trouble == ''
    assert rec.meta['engine'] == 'mujoco'
    assert not rec.contacts.any()   # nobody to touch


def test_the_same_scene_gives_the_same_trajectory_and_a_pair_touches(config: SimConfig,
                                                                   gait90: GaitConfig) -> None:
    scene = p5_pair(config, gait90)
    first = run_mujoco(config, scene, 2.0, sample_every=2)
    again = run_mujoco(config, scene, 2.0, sample_every=2)
    assert np.array_equal(first.poses, again.poses)
    assert np.array_equal(first.arm_angles, again.arm_angles)
    assert first.contacts[:, 0, 1].any() and np.array_equal(first.contacts[:, 0, 1], first.contacts[:, 1, 0])
    assert len(first.time) == round(2.0 * gait90.period / (2 * config.physics.control_tick)) + 1
    # the pair moved: the robots push each other
    assert np.abs(first.poses[-1, :, :2] - first.poses[0, :, :2]).max() > 1e-4


@pytest.mark.parametrize(('change', 'named'), [
    ({'contact_timeconst': 1e-4}, 'contact_timeconst'),
    ({'servo_kv': -1.0}, 'servo_kv'),
    ({'time_step': math.nan}, 'time_step'),
    ({'servo_update': 1.5e-4}, 'servo_update'),
    ({'noslip_iterations': True}, 'noslip_iterations'),
    ({'friction_cone': 'round'}, 'friction_cone'),
    ({'robot_contact': 'chrono'}, 'robot_contact'),
    ({'hertz_poisson': 0.5}, 'hertz_poisson'),
    ({'hertz_restitution': 1.5}, 'hertz_restitution'),
    ({'hertz_youngs_modulus': 0.0}, 'hertz_youngs_modulus'),
])
def test_bad_settings_are_refused_naming_the_field(change: dict, named: str) -> None:
    with pytest.raises(SimError, match=f'MujocoSettings.{named}'):
        MujocoSettings(**change)


def test_a_bad_run_request_is_refused(config: SimConfig, gait90: GaitConfig) -> None:
    scene = p5_pair(config, gait90)
    with pytest.raises(SimError, match='periods'):
        run_mujoco(config, scene, 0.0, sample_every=2)
    with pytest.raises(SimError, match='sample_every'):
        run_mujoco(config, scene, 1.0, sample_every=0)
    with pytest.raises(SimError, match='servo updates'):
        run_mujoco(config, scene, 1.0, sample_every=1, settings=MujocoSettings(servo_update=7.0 / 9600.0))


def sphere_impact(time_step: float, speed: float = 0.3) -> tuple[float, float]:
    """Two free 17.4 g spheres meeting head on at ``speed`` without gravity, their contact left to the Hertz
    law: (rebound = separating / approach speed, deepest overlap in m)."""
    settings = MujocoSettings(time_step=time_step, servo_update=time_step)
    geom = '<geom type="sphere" size="0.01" mass="0.0174" margin="0" gap="1"/>'
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="{time_step!r}" gravity="0 0 0" integrator="implicitfast"/><worldbody>'
        f'<body pos="0 0 0"><freejoint/>{geom}</body><body pos="0.0201 0 0"><freejoint/>{geom}</body>'
        '</worldbody></mujoco>')
    data = mujoco.MjData(model)
    data.qvel[0], data.qvel[6] = speed / 2.0, -speed / 2.0
    law, owner = HertzLaw.of(settings, 0.3), np.array([0, 1])
    deepest = 0.0
    for _ in range(round(0.01 / time_step)):
        mujoco.mj_step1(model, data)
        hertz_contact_forces(model, data, law, owner)
        mujoco.mj_step2(model, data)
        if data.ncon:
            deepest = max(deepest, -float(data.contact.dist.min()))
    return (data.qvel[6] - data.qvel[0]) / speed, deepest


def test_the_hertz_contact_rebounds_with_its_restitution_and_hertz_s_overlap() -> None:
    """One contact point: the rebound is the law's 0.85 at the authors' step and finer; the deepest overlap
    is Hertz's for these spheres' reduced mass ((15 m v^2 / (16 E* sqrt R))^(2/5) = 0.135 mm without damping,
    a little less with it)."""
    for step in (1.0 / 9600.0, 1.0 / 48000.0):
        rebound, deepest = sphere_impact(step)
        assert rebound == pytest.approx(0.85, abs=0.015)
        assert 0.11e-3 < deepest < 0.135e-3


def test_the_hertz_law_caps_friction_and_ignores_creep() -> None:
    law = HertzLaw.of(MujocoSettings(), 0.3)
    normal, tangential = law.forces(1e-4, -0.1, 1.0, 0.004)          # fast sliding: Coulomb's cap
    assert normal > 0.0 and tangential == pytest.approx(0.3 * normal)
    assert law.forces(1e-4, 0.0, 5e-5, 0.004)[1] == 0.0              # below Chrono's slip threshold
    assert law.forces(1e-6, 10.0, 0.0, 0.004) == (0.0, 0.0)          # separating too fast to push
    still, approaching = law.forces(1e-4, 0.0, 0.0, 0.004)[0], law.forces(1e-4, -0.1, 0.0, 0.004)[0]
    assert approaching > still > 0.0                                  # damping adds while approaching


def test_a_hertz_pair_touches_and_its_plate_is_the_soft_one(config: SimConfig, gait90: GaitConfig) -> None:
    """The Hertz contact changes robot-robot contacts only: a lone robot moves bit for bit as with the soft
    contact; a pair touches (recorded), overlaps a fraction of a millimetre and runs clean."""
    a = gait90.alpha_max
    lone = Scene((RobotPlacement(0.0, 0.0, 0.3, a, a, gait90),), name='lone')
    soft = run_mujoco(config, lone, 1.0, sample_every=2)
    hertz = run_mujoco(config, lone, 1.0, sample_every=2, settings=MujocoSettings(robot_contact='hertz'))
    assert np.array_equal(soft.poses, hertz.poses)
    pair = run_mujoco(config, p5_pair(config, gait90), 1.0, sample_every=2,
                      settings=MujocoSettings(robot_contact='hertz'))
    assert pair.contacts[:, 0, 1].any() and pair.trouble == ''
    assert 0.0 < pair.meta['peak_overlap_mm'] < 0.3
