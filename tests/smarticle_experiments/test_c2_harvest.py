"""The C2 harvest: pair order, summary statistics, the seed syntax, and a real (short) harvest."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_common.pairs import place_pair
from smarticle_experiments.c2_harvest import C2Sample, front_order, harvest_trial, parse_seeds, signed_deg, summary


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


def test_seed_syntax() -> None:
    assert parse_seeds('3-5') == [3, 4, 5] and parse_seeds('1,7') == [1, 7]
    with pytest.raises(ValueError, match='empty'):
        parse_seeds('5-3')


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
