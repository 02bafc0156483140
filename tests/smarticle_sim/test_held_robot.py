"""A robot held in place (``RobotPlacement.held``, ``pair_scene(hold_first=True)``): its body neither moves
nor tips while the other robot pushes it, its arms still follow the gait, and a pair without it is unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig, open_loop_angles

from smarticle_experiments.errors import SpecError
from smarticle_experiments.kinds import KINDS, run_kind, validate_params
from smarticle_sim.batch import run_trial
from smarticle_sim.errors import SimError
from smarticle_sim.mujoco_engine import MujocoSettings, run_mujoco
from smarticle_sim.physics import Physics
from smarticle_sim.scenes import Scene, pair_scene, state_scene
from smarticle_sim.settings import SimConfig

#: A start whose robots collide within the first periods (r 1.3 BL, theta 0, phi 180, 0.1 period apart).
START = (1.3, 0.0, math.pi)
PHASES = (0.0, 0.1)
PERIODS = 6


def _scene(config: SimConfig, gait: GaitConfig, hold: bool) -> Scene:
    return pair_scene(config.robot, gait, *START, PHASES, seed=0, hold_first=hold)


def test_held_body_stays_put_while_pushed(config: SimConfig, gait90: GaitConfig) -> None:
    rec = run_trial(config, _scene(config, gait90, True), PERIODS, sample_every=1, record_fsr=True,
                    record_contacts=True)
    assert not rec.trouble
    assert rec.contacts[:, 0, 1].sum() >= 3                 # robot 2 keeps hitting it
    assert rec.fsr[:, 0].max() > 0.01                       # the contacts act on the held robot (N) ...
    moved = np.abs(rec.poses[:, 0, :] - rec.poses[0, 0, :]).max()
    assert moved < 1e-9                                     # ... but its body does not move or turn
    assert rec.meta['peak_tilt_deg'] < 1.0                  # robot 2 may tip a little; the held body stays flat
    assert rec.meta['initial'][0]['held'] and 'held' not in rec.meta['initial'][1]
    free = run_trial(config, _scene(config, gait90, False), PERIODS, sample_every=1)
    assert np.abs(free.poses[:, 0, :2] - free.poses[0, 0, :2]).max() > 0.002   # unheld, the same pushes move it


def test_held_body_does_not_tip(config: SimConfig, gait90: GaitConfig) -> None:
    with Physics(config, _scene(config, gait90, True)) as world:
        world.step(400)
        pos, quat = world.client.getBasePositionAndOrientation(world.body_ids[0])
        assert pos[2] == pytest.approx(config.robot.body_height / 2.0, abs=1e-12)
        assert np.allclose(quat, world.client.getQuaternionFromEuler([0.0, 0.0, 0.0]), atol=1e-12)
        assert world.client.getDynamicsInfo(world.body_ids[0], -1)[0] == 0.0        # the held base: no mass
        assert world.client.getDynamicsInfo(world.body_ids[1], -1)[0] == pytest.approx(config.robot.body_mass)


def test_held_arms_follow_the_gait(config: SimConfig, gait90: GaitConfig) -> None:
    rec = run_trial(config, _scene(config, gait90, True), PERIODS, sample_every=1)
    gait = rec.meta['initial'][0]
    assert gait['phase'] == 0.0
    want = np.array([open_loop_angles(gait90, t / gait90.period) for t in rec.time])
    error = np.abs(rec.arm_angles[:, 0, :] - want)
    assert np.ptp(rec.arm_angles[:, 0, :], axis=0) == pytest.approx([math.pi, math.pi], abs=0.02)
    assert np.median(error) < 0.02                          # the servo's lag behind the open-loop corners
    lone = run_trial(config, _scene(config, gait90, False), PERIODS, sample_every=1)
    assert np.median(np.abs(lone.arm_angles[:, 0, :] - want)) == pytest.approx(np.median(error), abs=0.02)


def test_the_default_pair_holds_nothing(config: SimConfig, gait90: GaitConfig) -> None:
    scene = pair_scene(config.robot, gait90, *START, PHASES, seed=0)
    assert not any(r.held for r in scene.robots)
    with Physics(config, scene) as world:
        masses = [world.client.getDynamicsInfo(b, -1)[0] for b in world.body_ids]
        assert masses == pytest.approx([config.robot.body_mass] * 2)
        placements = world.placements()
    held = _scene(config, gait90, True)
    with Physics(config, held) as world:
        kept = state_scene(world.placements(), [gait90, gait90])
    assert [p.held for p in kept.robots] == [True, False] and not any(p.held for p in placements)


def test_the_pair_kind_holds_robot_1(config: SimConfig) -> None:
    params = {**KINDS['pair'].defaults, 'theta_deg': 0.0, 'phi_deg': 180.0, 'phase2': 0.1, 'periods': 4.0,
              'trajectory': False}
    held = run_kind('pair', {**params, 'hold_first': True}, 0)
    free = run_kind('pair', params, 0)
    assert held['admissible'] and free['admissible']
    assert held != free
    with pytest.raises(SpecError, match='hold_first'):
        validate_params('pair_mujoco', {**KINDS['pair_mujoco'].defaults, 'hold_first': True})


def test_mujoco_refuses_a_held_robot(config: SimConfig, gait90: GaitConfig) -> None:
    with pytest.raises(SimError, match='held'):
        run_mujoco(config, _scene(config, gait90, True), 1.0, 3, MujocoSettings())
