"""The physics study's single-robot drift run: amplitude and the body's tilt reach its row."""

from __future__ import annotations

import math

from smarticle_experiments.physics_study import drift_run, model_settings


def test_a_lone_robots_drift_run_takes_the_amplitude_and_reports_the_bodys_tilt() -> None:
    settings = model_settings('shipped', ['time_step=1/240'])
    small = drift_run(settings, 90.0, periods=2, skip=1, alpha=10.0)
    full = drift_run(settings, 90.0, periods=2, skip=1, alpha=90.0)
    assert small['alpha'] == 10.0 and full['alpha'] == 90.0 and not small['trouble'] and not full['trouble']
    for row in (small, full):
        # a lone robot on the plate stays flat: its tilt is measured every tick and is far below a degree
        assert math.isfinite(row['tilt_max_deg']) and 0.0 <= row['tilt_rms_deg'] <= row['tilt_max_deg'] < 1.0
        assert row['net_um'] > 0.0
    # a 10 deg stroke is a different walker from a 90 deg one: the two runs do not share a drift
    assert abs(small['net_um'] - full['net_um']) > 1.0
