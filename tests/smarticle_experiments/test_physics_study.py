"""The physics study's measurements as trial kinds, and ``smarticle-experiments physics-study`` on tiny runs."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from smarticle_experiments.cli import main
from smarticle_experiments.errors import SpecError
from smarticle_experiments.physics_study import split_settings, study_config
from smarticle_experiments.kinds import KINDS, run_kind


def test_a_lone_robots_drift_run_takes_the_amplitude_and_reports_the_bodys_tilt() -> None:
    base = {**KINDS['study_drift'].defaults, 'settings': {'time_step': 1 / 240}, 'periods': 2, 'skip': 1}
    small = run_kind('study_drift', {**base, 'alpha_max_deg': 10.0}, 0)
    full = run_kind('study_drift', {**base, 'alpha_max_deg': 90.0}, 0)
    assert small['alpha'] == 10.0 and full['alpha'] == 90.0 and not small['trouble'] and not full['trouble']
    for row in (small, full):
        # a lone robot on the plate stays flat: its tilt is measured every tick and is far below a degree
        assert math.isfinite(row['tilt_max_deg']) and 0.0 <= row['tilt_rms_deg'] <= row['tilt_max_deg'] < 1.0
        assert row['net_um'] > 0.0
    # a 10 deg stroke is a different walker from a 90 deg one: the two runs do not share a drift
    assert abs(small['net_um'] - full['net_um']) > 1.0


def test_settings_split_into_physics_robot_diagnostics_and_gait_speed() -> None:
    physics, robot, diagnostics, speed = split_settings({'time_step': 1 / 480.3, 'arm_mass': 0.005, 'cfm': 0.01,
                                                         'gait_speed': 20.0})
    assert physics == {'time_step': 1 / 480, 'control_tick': 1 / 60} and robot == {'arm_mass': 0.005}
    assert split_settings({'time_step': 1 / 250})[0]['control_tick'] == 1 / 250   # 1/60 s is no whole step count
    assert diagnostics == {'cfm': 0.01} and speed == 20.0
    config, gait_speed = study_config({'gait_speed': 20.0, 'split_impulse': True})
    assert gait_speed == 20.0 and config.robot.servo_speed == 20.0   # the servo is made fast enough for the gait
    assert config.diagnostics.split_impulse is True and config.diagnostics.changed == ('split_impulse',)
    with pytest.raises(SpecError, match='colour'):
        split_settings({'colour': 1})
    with pytest.raises(SpecError, match='x_rvt'):   # the Bullet knobs are Diagnostics fields, by their own names
        split_settings({'x_rvt': 0.01})


def test_physics_study_runs_on_the_engine_and_prints_its_tables(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'store'
    engine = ['--out', str(out), '--workers', '1', '--no-progress']
    assert main(['physics-study', 'drift', '--periods', '2', '--dt', '240', '480', *engine]) == 0
    text = capsys.readouterr().out
    assert '| shipped | 90 |' in text and 'Richardson' in text
    assert main(['physics-study', 'mechanism', '--periods', '1', '--set', 'restitution=0.5', *engine]) == 0
    text = capsys.readouterr().out
    assert '| restitution=0.5 |' in text
    records = [r for r in (out / 'physics_mechanism' / 'trials').glob('*.json')]
    assert len(records) == 16                                  # the 16 starts, overlapping ones included
    assert main(['physics-study', 'tables', '--out', str(out)]) == 0
    tables = capsys.readouterr().out
    assert '## drift' in tables and '## mechanism' in tables
    assert main(['physics-study', 'drift', '--set', 'colour=red', *engine]) == 2
    assert 'colour' in capsys.readouterr().err
