"""The C2 harvest: pair order, summary statistics, the seed syntax, and a real (short) harvest."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_common.pairs import place_pair
from smarticle_experiments.c2_harvest import (C2Sample, front_order, harvest_trial, sample_from_record, sample_record,
                                              signed_deg, summary)


@pytest.mark.parametrize('theta_deg', [10.0, 100.0, 190.0, 280.0])
def test_the_pair_is_written_with_robot_two_in_front(theta_deg: float) -> None:
    pose1 = (0.1, -0.2, 0.7)
    pose2 = place_pair(pose1, 0.08, math.radians(theta_deg), math.radians(5.0))
    poses = np.array([pose1, (9.0, 9.0, 0.0), pose2])
    a, b, (r, theta, phi) = front_order(0, 2, poses)
    assert 0.0 <= theta < 180.0 and r == pytest.approx(0.08)
    assert (a, b) == ((0, 2) if theta_deg < 180.0 else (2, 0))
    if theta_deg < 180.0:
        assert theta == pytest.approx(theta_deg) and phi == pytest.approx(5.0)


def test_summary_takes_medians_with_phi_about_zero() -> None:
    samples = [C2Sample(1, 0, 1, k, 1.4 + 0.01 * k, 100.0 + k, phi) for k, phi in enumerate([350.0, 355.0, 5.0])]
    s = summary(samples)
    assert s['r_bl_median'] == pytest.approx(1.41) and s['theta_deg_median'] == pytest.approx(101.0)
    assert s['phi_deg_median'] == pytest.approx(-5.0)       # not 350: phi is taken in (-180, 180]
    assert (s['samples'], s['gliders'], s['seeds']) == (3.0, 1.0, 1.0)
    assert list(signed_deg(np.array([0.0, 180.0, 190.0, 359.0]))) == [0.0, 180.0, -170.0, -1.0]
    with pytest.raises(ValueError, match='no C2 samples'):
        summary([])


def test_a_sample_survives_the_store_to_the_bit() -> None:
    """The stored form of a sample (JSON) gives back the same sample, state included (not the gait: a start
    takes the gait of the trial it starts)."""
    import json
    from dataclasses import replace

    samples = harvest_trial(5002, periods=20.0, min_periods=5, settle=1)
    assert samples and samples[0].state is not None
    for s in samples[:3]:
        assert s.state is not None
        without_gait = replace(s, state=(replace(s.state[0], gait=None), replace(s.state[1], gait=None)))
        assert sample_from_record(json.loads(json.dumps(sample_record(s)))) == without_gait


def test_a_short_harvest_samples_only_c2_period_boundaries() -> None:
    samples = harvest_trial(5002, periods=20.0, min_periods=5, settle=1)
    assert samples, 'seed 5002 forms a C2 glider of the feedback robot within 20 periods'
    for s in samples:
        # bound = r < 1.6 BL in some frame of the period; at the period's first frame the pair may be farther
        assert 0.0 <= s.theta_deg < 180.0 and s.r_bl < 2.0
        assert min(abs(s.phi_deg), abs(360.0 - s.phi_deg)) < 90.0      # C2: parallel normals
    # one sample per period of each glider (a trial can hold two C2 gliders at once)
    assert len({(frozenset((s.i, s.j)), s.period) for s in samples}) == len(samples)


def test_the_summary_says_how_many_samples_had_contact_and_where_those_pairs_sit() -> None:
    from smarticle_experiments.c2_harvest import format_summary

    samples = [C2Sample(1, 0, 1, k, 1.2 + 0.1 * k, 90.0, 0.0, touched=k < 2) for k in range(4)]
    text = format_summary(summary(samples), summary([s for s in samples if s.touched]))
    assert '| r (BL) | 1.350 | 1.275 - 1.425 | 1.250 | 1.225 - 1.275 |' in text
    assert 'In 2 of them (50%) the pair touched during the period (1 gliders, 1 trials).' in text
    assert 'periods with contact' not in format_summary(summary(samples))


def test_the_harvest_keeps_each_samples_pair_state_and_the_csv_gives_it_back_to_the_bit(tmp_path) -> None:
    from smarticle_experiments.c2_harvest import read_csv, write_csv

    from smarticle_sim.config_builder import build_config

    bl = build_config('feedback').robot.body_length
    samples = harvest_trial(5002, periods=20.0, min_periods=5, settle=1)
    assert samples and all(s.state is not None for s in samples)
    for s in samples:
        a, b = s.state
        assert math.hypot(a.x - b.x, a.y - b.y) / bl == pytest.approx(s.r_bl, abs=1e-4)
        assert a.state is not None and 0.0 < a.state.z < 0.05
    back = read_csv(write_csv(samples, tmp_path / 'c2.csv'))

    def state(s: C2Sample) -> list[tuple[object, ...]]:
        assert s.state is not None
        return [(p.x, p.y, p.heading, p.alpha1, p.alpha2, p.state) for p in s.state]

    # every state float written with repr: the same state, bit for bit (the gait is the trial's, not the file's)
    assert [state(s) for s in back] == [state(s) for s in samples]
    assert [(s.seed, s.i, s.j, s.period, s.touched) for s in back] == [(s.seed, s.i, s.j, s.period, s.touched)
                                                                       for s in samples]
    # a file of an older harvest (no state columns) still reads, without states
    old = tmp_path / 'old.csv'
    old.write_text('seed,i,j,period,r_bl,theta_deg,phi_deg,touched\n1,0,1,7,1.2,90.0,3.0,1\n')
    assert read_csv(old) == [C2Sample(1, 0, 1, 7, 1.2, 90.0, 3.0, True, None)]
    bad = tmp_path / 'bad.csv'
    bad.write_text('seed,i,j,period,r_bl,theta_deg,phi_deg,touched\n1,0,x,7,1.2,90.0,3.0,1\n')
    with pytest.raises(ValueError, match='line 2'):
        read_csv(bad)
    with pytest.raises(ValueError, match='not a C2 samples file'):
        read_csv(tmp_path.joinpath('x.csv').write_text('a,b\n1,2\n') and tmp_path / 'x.csv')


def test_held_starts_are_the_contact_periods_of_gliders_that_touch_in_half_their_periods() -> None:
    from smarticle_experiments.c2_harvest import held_starts

    state = object()   # any recorded state
    often = [C2Sample(1, 0, 1, k, 1.0, 90.0, 0.0, k % 4 != 0, state) for k in range(8)]     # touched 6 of 8
    seldom = [C2Sample(2, 3, 4, k, 1.4, 90.0, 0.0, k == 0, state) for k in range(8)]       # touched 1 of 8
    no_state = [C2Sample(3, 0, 1, k, 1.0, 90.0, 0.0, True, None) for k in range(2)]
    held = held_starts(often + seldom + no_state, every=1)      # type: ignore[arg-type]
    assert held == [s for s in often if s.touched]
    assert held_starts(often + seldom + no_state, every=2) == [often[k] for k in (1, 3, 6)]   # type: ignore[arg-type]
    with pytest.raises(ValueError, match='every'):
        held_starts(often, every=0)    # type: ignore[arg-type]
