"""The Chrono reference: the scene the driver reads, the recording it writes, and a pair run end to end.

The end-to-end tests need the driver built (tools/chrono_reference/build_chrono.sh); without it they are
skipped with one line. The scene and recording tests run everywhere and need no Chrono.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig, open_loop_angles
from smarticle_common.poses import heading_quaternion

from smarticle_sim.chrono_reference import (ChronoSettings, ChronoUnavailable, chrono_available, driver_path,
                                            pair_chrono_trial, read_recording, run_chrono,
                                            scene_document, single_chrono_trial)
from smarticle_sim.errors import SceneError, SimError
from smarticle_sim.diagnostics import box_inertia
from smarticle_sim.scenes import RobotPlacement, Scene, pair_scene
from smarticle_sim.settings import SimConfig

needs_chrono = pytest.mark.skipif(not chrono_available(),
                                  reason='Chrono is not built (tools/chrono_reference/build_chrono.sh): '
                                         'the Chrono reference run is skipped')


def in_phase_pair(config: SimConfig, gait: GaitConfig, phase2: float = 0.0) -> Scene:
    """The in-phase pair of the reference check: r 1.3 BL, theta 330 deg, phi 180 deg."""
    return pair_scene(config.robot, gait, 1.3, math.radians(330.0), math.radians(180.0), (0.0, phase2), seed=7)


def test_scene_document_carries_the_robots_material_and_timing(config: SimConfig, gait90: GaitConfig) -> None:
    scene = in_phase_pair(config, gait90, phase2=0.1)
    doc = scene_document(config, scene, 3.2, 0.05, ChronoSettings(), fixed=[0])
    json.dumps(doc)   # JSON-ready
    spec = config.robot
    assert doc['step'] == 1e-4 and doc['duration'] == 3.2 and doc['record_interval'] == 0.05
    assert doc['contact'] == 'smc' and doc['collision_system'] == 'multicore'
    assert doc['robot_material'] == {'youngs_modulus': 2e7, 'poisson_ratio': 0.3, 'friction': 0.3, 'restitution': 0.85}
    assert doc['plate_material']['friction'] == config.physics.friction_body_plate
    first, second = doc['robots']
    assert first['fixed'] and not second['fixed']
    assert first['body']['mass'] == pytest.approx(spec.body_mass)
    assert first['body']['inertia'] == pytest.approx(box_inertia(spec.body_mass, spec.body_width, spec.body_depth,
                                                                 spec.body_height))
    assert [a['mass'] for a in first['arms']] == [spec.arm_mass, spec.arm_mass]
    assert first['arm_z'] == pytest.approx(spec.arm_clearance + spec.arm_height / 2 - spec.body_height / 2)
    assert second['gait']['phase'] == 0.1
    assert (second['alpha1'], second['alpha2']) == pytest.approx(open_loop_angles(gait90, 0.1))
    assert (second['x'], second['y'], second['heading']) == (scene.robots[1].x, scene.robots[1].y,
                                                              scene.robots[1].heading)


def test_scene_document_takes_the_authors_mass_model_and_inertia_factors(gait90: GaitConfig) -> None:
    config = SimConfig().with_diagnostics(mass_model='authors', yaw_inertia_scale=0.5)
    doc = scene_document(config, in_phase_pair(config, gait90), 1.6, 0.05, ChronoSettings())
    robot = doc['robots'][0]
    arm1, arm2 = (a['mass'] for a in robot['arms'])
    assert arm1 > 9 * arm2                        # one heavy arm, one of its 100 kg/m^3 box
    uniform = box_inertia(config.robot.body_mass, config.robot.body_width, config.robot.body_depth,
                          config.robot.body_height)
    assert robot['body']['inertia'][2] < 0.5 * uniform[2]


def test_scene_document_refuses_what_the_driver_cannot_run(config: SimConfig, gait90: GaitConfig) -> None:
    scene = in_phase_pair(config, gait90)
    with pytest.raises(SimError, match='whole number of Chrono steps'):
        scene_document(config, scene, 1.6, 0.05, ChronoSettings(time_step=3e-4 / 7))
    off = Scene((RobotPlacement(0.0, 0.0, 0.0, 0.3, 0.3, gait90),))
    with pytest.raises(SceneError, match='where its gait starts'):
        scene_document(config, off, 1.6, 0.05, ChronoSettings())
    with pytest.raises(SceneError, match='not all in the scene'):
        scene_document(config, scene, 1.6, 0.05, ChronoSettings(), fixed=[2])
    with pytest.raises(SimError, match='ChronoSettings.contact'):
        ChronoSettings(contact='soft')


def test_read_recording_turns_driver_rows_into_the_run_format(tmp_path: Path) -> None:
    n, rows = 2, 3
    width = 1 + 9 * n + n * n
    data = np.zeros((rows, width))
    data[:, 0] = [0.0, 0.05, 0.1]
    for k, heading in enumerate((0.3, -2.0)):
        base = 1 + 9 * k
        data[:, base:base + 3] = [0.01 * k, -0.02, 0.0135]
        qx, qy, qz, qw = heading_quaternion(heading - math.pi / 2)    # the body x axis from its normal
        data[:, base + 3:base + 7] = [qx, qy, qz, qw]
        data[:, base + 7:base + 9] = [0.5, -0.5]
    data[1, 1 + 9 * n + 1] = data[1, 1 + 9 * n + 2] = 1.0     # robots 0 and 1 touched before sample 1
    path = tmp_path / 'recording.bin'
    np.concatenate([data.ravel(), [1.0, 2.0]]).astype('<f8').tofile(path)   # a torn last row is dropped
    rec = read_recording(path, n, 0.054, {'engine': 'chrono'})
    assert rec.time.tolist() == [0.0, 0.05, 0.1]
    assert rec.poses.shape == (3, 2, 3) and rec.arm_angles.shape == (3, 2, 2) and rec.fsr.shape == (3, 2, 4)
    assert rec.poses[:, 0, 2] == pytest.approx([0.3] * 3)
    assert rec.poses[:, 1, 2] == pytest.approx([-2.0] * 3)
    assert rec.contacts[:, 0, 1].tolist() == [False, True, False]
    assert rec.contacts[1, 1, 0]
    path.write_bytes(b'\0' * 16)
    with pytest.raises(SimError, match='no complete sample'):
        read_recording(path, n, 0.054)


def test_without_the_driver_every_run_says_so_in_one_line(tmp_path: Path, config: SimConfig,
                                                          gait90: GaitConfig,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    missing = tmp_path / 'no-such-driver'
    monkeypatch.setenv('SMARTICLE_CHRONO_DRIVER', str(missing))
    with pytest.raises(ChronoUnavailable) as info:
        driver_path()
    message = str(info.value)
    assert '\n' not in message and 'build_chrono.sh' in message and str(missing) in message
    assert isinstance(info.value, SimError)
    assert not chrono_available()
    with pytest.raises(ChronoUnavailable):
        run_chrono(config, in_phase_pair(config, gait90), 1.0, 3)
    with pytest.raises(ChronoUnavailable):
        pair_chrono_trial({'periods': 1.0}, 0)
    with pytest.raises(ChronoUnavailable):
        single_chrono_trial({'periods': 1.0}, 0)
    with pytest.raises(SimError, match='unknown parameter'):
        pair_chrono_trial({'period': 1.0}, 0)
    with pytest.raises(SimError, match='not a ChronoSettings field'):
        pair_chrono_trial({'chrono': {'step': 1e-4}}, 0)


@needs_chrono
def test_an_in_phase_pair_runs_end_to_end_with_the_gait(config: SimConfig, gait90: GaitConfig,
                                                        tmp_path: Path) -> None:
    periods = 3
    scene = in_phase_pair(config, gait90)
    rec = run_chrono(config, scene, periods, 3, keep=tmp_path)
    per = round(gait90.period / (3 * config.physics.control_tick))          # samples per period
    assert rec.trouble == ''
    assert rec.poses.shape == (periods * per + 1, 2, 3)
    assert rec.arm_angles.shape == (periods * per + 1, 2, 2)
    assert np.all(np.isfinite(rec.poses)) and np.all(np.isfinite(rec.arm_angles))
    assert rec.time == pytest.approx(np.arange(periods * per + 1) * 3 * config.physics.control_tick)
    assert rec.meta['engine'] == 'chrono' and rec.meta['chrono_version'].startswith('10.')
    assert (tmp_path / 'scene.json').is_file()
    # the arms follow the open-loop square gait (rigid speed motors), robot 2 as robot 1
    expected = np.array([open_loop_angles(gait90, t / gait90.period) for t in rec.time])
    for k in range(2):
        assert np.abs(rec.arm_angles[:, k] - expected).max() < 0.02
    # the start is where the scene put the robots, the bodies move with the gait and stay flat
    assert rec.poses[0, :, :2] == pytest.approx(np.array([[r.x, r.y] for r in scene.robots]), abs=1e-6)
    moved = np.linalg.norm(np.diff(rec.poses[:, :, :2], axis=0), axis=2).sum(axis=0)
    assert np.all(moved > 1e-4)
    assert rec.meta['peak_tilt_deg'] < 10.0
    # 1.3 BL apart in phase, the arms collide
    assert rec.contacts[:, 0, 1].any()


@needs_chrono
def test_the_pair_kind_reports_its_end_state(config: SimConfig) -> None:
    result = pair_chrono_trial({'periods': 2.0, 'phase2': 0.1}, 3)
    assert result['admissible'] and result['trouble'] == ''
    assert result['periods_run'] == 2
    assert 0.5 < result['r_end_bl'] < 3.0 and 0.0 <= result['phi_end_deg'] < 360.0
    assert math.isfinite(result['travel_w']) and result['wall_time_s'] > 0.0
    overlapping = pair_chrono_trial({'r_bl': 0.5, 'periods': 1.0}, 3)
    assert not overlapping['admissible'] and 'overlap' in overlapping['why']


@needs_chrono
def test_a_lone_robot_drifts_a_little() -> None:
    result = single_chrono_trial({'periods': 2.0}, 5)
    assert result['trouble'] == '' and result['cycles'] == 2
    assert 0.0 < result['drift_um_per_cycle'] < 5000.0
