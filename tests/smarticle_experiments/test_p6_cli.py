"""The P6 command lines on tiny runs: files written, tables printed, bad input refused."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from smarticle_experiments import c2_collisions, c2_harvest, p6


def test_p6_writes_its_tables_and_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'p6'
    assert p6.main(['--seeds', '1', '--periods', '2', '--open-loop', '90', '--feedback', '90', '--jobs', '1',
                    '--start', 'colliding', '--noise', 'none', '--out', str(out)]) == 0
    text = capsys.readouterr().out
    assert '| open loop 90 deg | 1 |' in text and '| feedback 90 deg | 1 |' in text and 'log-rank' in text
    for name in ('p6_trials.csv', 'p6_summary.csv', 'p6_survival.png', 'p6_r_traces.png'):
        assert (out / name).stat().st_size > 0


def test_p6_refuses_an_unknown_start_or_noise(capsys: pytest.CaptureFixture[str]) -> None:
    for flag, value in (('--start', 'nowhere'), ('--noise', 'loud')):
        with pytest.raises(SystemExit) as exc:
            p6.main([flag, value])
        assert exc.value.code == 2 and value in capsys.readouterr().err
    with pytest.raises(ValueError, match='start must be one of'):
        p6.run_p6([p6.Condition(90.0, False)], [0], 1.0, start='nowhere')


def test_c2_collisions_records_the_colliding_start(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'c2'
    assert c2_collisions.main(['--start', 'colliding', '--noise', 'none', '--periods', '1', '--out', str(out)]) == 0
    assert 'compression' in capsys.readouterr().out
    for name in ('c2_steps.npz', 'c2_events.csv', 'c2_events.png'):
        assert (out / name).stat().st_size > 0


def test_c2_harvest_says_when_nothing_was_harvested(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert c2_harvest.main(['--seeds', '5000', '--periods', '2', '--jobs', '1', '--out', str(tmp_path)]) == 1
    assert 'no C2 samples' in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        c2_harvest.main(['--seeds', '9-3'])
    assert exc.value.code == 2


def test_p6_takes_windows_from_a_parameter_file_or_the_calibration_output(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """--windows: the shipped parameter file gives the shipped windows; a flat mapping (what
    smarticle-feedback-calibrate prints) changes them; a file without windows is refused with exit code 2."""
    root = Path(__file__).resolve().parents[2]
    assert p6.windows_file(root / 'smarticle_feedback' / 'config' / 'feedback.yaml') == p6.default_feedback_config()
    flat = tmp_path / 'calibrated.yaml'
    flat.write_text('arm1_back_min: 0.15\narm1_back_max: 10.31\narm1_back_enabled: true\n', encoding='utf-8')
    config = p6.windows_file(flat)
    assert config != p6.default_feedback_config()
    assert 'arm1_back' in config.enabled_faces and 'arm1_back' not in p6.default_feedback_config().enabled_faces
    empty = tmp_path / 'empty.yaml'
    empty.write_text('period: 1.6\n', encoding='utf-8')
    for bad, says in ((empty, 'no impact windows'), (tmp_path / 'missing.yaml', 'missing.yaml')):
        with pytest.raises(SystemExit) as exc:
            p6.main(['--windows', str(bad)])
        assert exc.value.code == 2 and says in capsys.readouterr().err
    typo = tmp_path / 'typo.yaml'
    typo.write_text('arm1_bak_min: 1.0\narm1_back_max: 10.0\n', encoding='utf-8')
    with pytest.raises(SystemExit):
        p6.main(['--windows', str(typo)])
    assert 'arm1_bak_min' in capsys.readouterr().err


def test_p6_set_changes_the_physics_of_every_trial(capsys: pytest.CaptureFixture[str]) -> None:
    """--set NAME=VALUE replaces PhysicsConfig fields (the trajectory changes); a bad name or value is refused."""
    runs = {}
    for sets in ((), ('restitution=0.3',)):
        physics = p6.physics_changes(argparse.ArgumentParser(), sets)
        trials = p6.run_p6([p6.Condition(90.0, False)], [0], 3.0, jobs=1, progress=False, noise='none',
                           start='colliding', physics=physics)
        runs[sets] = trials[0].r
    assert runs[()].shape == runs[('restitution=0.3',)].shape
    assert not (runs[()] == runs[('restitution=0.3',)]).all()
    for bad, says in (('restitution=2', 'restitution'), ('no_such_field=1', 'no_such_field'),
                      ('restitution', 'NAME=VALUE')):
        with pytest.raises(SystemExit) as exc:
            p6.main(['--set', bad])
        assert exc.value.code == 2 and says in capsys.readouterr().err
