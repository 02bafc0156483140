"""Batch runs and the smarticle-sim CLI: a short run writes a readable npz and a PNG."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig
from smarticle_common.topics import FSR_FACES

from smarticle_common.runs import load_npz, save_npz
from smarticle_sim.batch import run_trial
from smarticle_sim.cli import main
from smarticle_sim.scenes import dense_scene
from smarticle_sim.settings import SimConfig


def test_cli_dense_run_writes_npz_and_png(tmp_path: Path) -> None:
    out = tmp_path / 'run.npz'
    code = main(['run', '--robots', '7', '--scene', 'dense', '--periods', '2', '--alpha-max', '90',
                 '--seed', '1', '--out', str(out), '--no-progress'])
    assert code == 0
    png = out.with_suffix('.png')
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    with np.load(out) as data:
        samples = data['time'].shape[0]
        assert samples == 2 * 32 + 1                     # 20 Hz (default) over 3.2 s, plus t = 0
        assert data['poses'].shape == (samples, 7, 3)
        assert data['arm_angles'].shape == (samples, 7, 2)
        assert data['fsr'].shape == (samples, 7, 4)
        assert data['contacts'].shape == (samples, 7, 7) and data['contacts'].dtype == bool
        assert tuple(data['fsr_faces']) == FSR_FACES
        assert float(data['body_length']) == 0.054
        meta = json.loads(str(data['meta']))
    assert meta['seed'] == 1 and meta['trouble'] == '' and meta['scene'] == 'dense'
    assert (np.abs(np.load(out)['arm_angles']) <= np.radians(91)).all()


def test_cli_pair_run_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'pair.npz'
    assert main(['run', '--scene', 'pair', '--r', '1.6', '--theta', '0', '--phi', '180',
                 '--phase', '0', '0.25', '--periods', '1', '--out', str(out), '--no-progress',
                 '--sample-every', '4', '--no-fsr']) == 0
    rec = load_npz(out)
    assert rec.poses.shape == (25, 2, 3)
    assert main(['run', '--scene', 'pair', '--r', '1.3', '--theta', '90', '--phi', '180',
                 '--out', str(tmp_path / 'x.npz'), '--no-progress']) == 2
    assert 'overlap' in capsys.readouterr().err
    assert main(['run', '--time-step', '0.004', '--out', str(tmp_path / 'y.npz'), '--no-progress']) == 2
    assert 'control_tick' in capsys.readouterr().err


def test_recording_round_trip(tmp_path: Path) -> None:
    config = SimConfig()
    scene = dense_scene(config.robot, GaitConfig.from_degrees(60.0), 3, seed=2)
    rec = run_trial(config, scene, 0.5, sample_every=2, record_fsr=True, record_contacts=True)
    assert rec.meta['fsr_recorded'] and rec.fsr.shape == (len(rec.time), 3, 4)
    back = load_npz(save_npz(rec, tmp_path / 'r.npz'))
    for name in ('time', 'poses', 'arm_angles', 'fsr', 'contacts'):
        assert np.array_equal(getattr(rec, name), getattr(back, name))
    assert back.meta == json.loads(json.dumps(rec.meta))


def test_cli_runs_a_preset_file_and_refuses_a_bad_one(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--preset FILE`` (the format smarticle-calibrate writes): the run's config holds the file's values."""
    preset = tmp_path / 'lab.yaml'
    preset.write_text('preset: small\nphysics: {friction_body_plate: 0.42, restitution: 0.5}\n'
                      'robot: {servo_speed: 9.5}\ncalibration: {bags: [lab_pair]}\n', encoding='utf-8')
    out = tmp_path / 'lab.npz'
    assert main(['run', '--preset', str(preset), '--scene', 'pair', '--r', '1.6', '--theta', '0', '--periods', '1',
                 '--out', str(out), '--no-progress']) == 0
    meta = load_npz(out).meta
    assert meta['physics']['friction_body_plate'] == 0.42 and meta['physics']['restitution'] == 0.5
    assert meta['robot']['servo_speed'] == 9.5 and meta['robot']['name'] == 'small'
    capsys.readouterr()

    bad = tmp_path / 'bad.yaml'
    bad.write_text('physics: {friction_plate: 0.3}\n', encoding='utf-8')
    for preset_arg, words in ((str(bad), ('bad.yaml', 'friction_plate')),
                              (str(tmp_path / 'missing.yaml'), ('missing.yaml', 'cannot be read')),
                              ('tiny', ("'tiny'", 'feedback, small', 'preset file'))):
        assert main(['run', '--preset', preset_arg, '--periods', '1', '--out', str(tmp_path / 'x.npz'),
                     '--no-progress']) == 2
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and all(word in err for word in words), err
    assert not (tmp_path / 'x.npz').exists()
