"""Batch glider analysis on constructed runs with known answers."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.glider_scenes import FRAMES_PER_PERIOD, PERIOD, R_BOUND, R_FREE, pair_scene, periods

from smarticle_tracking.errors import GliderConfigError, GliderInputError
from smarticle_tracking.glider_plots import draw_pair_coordinates, plot_glider_analysis
from smarticle_tracking.gliders import (GliderClass, GliderConfig, PairKind, analyse_gliders, bound_runs,
                                        classify_configuration, ensemble_msd, format_glider_table,
                                        glider_summary, glider_table, running_labels)


def config(k: int, **kw: object) -> GliderConfig:
    """Default config with K = ``k``."""
    return GliderConfig(min_periods=k, **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize('k', [1, 30, 100])
def test_bound_for_exactly_k_periods_is_a_glider_at_k_not_at_k_plus_1(k: int) -> None:
    times, poses = pair_scene(periods(k + 20, 7, k))
    found = analyse_gliders(times, poses, config(k)).gliders
    assert len(found) == 1
    g = found[0]
    assert (g.i, g.j, g.start_period, g.lifetime_periods) == (0, 1, 7, k)
    assert g.start_time == pytest.approx(7 * PERIOD)
    assert g.lifetime == pytest.approx(k * PERIOD)
    assert not g.ongoing
    assert analyse_gliders(times, poses, config(k + 1)).gliders == ()


def test_one_close_frame_binds_the_whole_period() -> None:
    times, poses = pair_scene(periods(40, 0, 0))              # always apart
    close = np.arange(0, times.size, FRAMES_PER_PERIOD) + 3    # one frame in each period
    poses[close, 1, :2] = poses[close, 0, :2] + [0.0, R_BOUND]
    analysis = analyse_gliders(times, poses, config(40))
    assert analysis.periods.bound[:, 0].all()
    assert analysis.gliders[0].lifetime_periods == 40
    assert analysis.gliders[0].ongoing


def test_contacts_bind_pairs_that_are_far_apart() -> None:
    times, poses = pair_scene(periods(50, 0, 0))
    contacts = np.zeros((times.size, 3), dtype=bool)
    contacts[10 * FRAMES_PER_PERIOD + 5:(45 * FRAMES_PER_PERIOD):FRAMES_PER_PERIOD, 0] = True
    (g,) = analyse_gliders(times, poses, config(30), contacts=contacts).gliders
    assert (g.start_period, g.lifetime_periods) == (10, 35)
    assert g.r_mean == pytest.approx(R_FREE)
    with pytest.raises(GliderInputError, match=r'\(T, P\)'):
        analyse_gliders(times, poses, config(30), contacts=contacts[:, :2])


def test_a_gap_of_one_unbound_period_splits_a_run() -> None:
    mask = periods(80, 0, 35)
    mask[36:70] = [True] * 34
    times, poses = pair_scene(mask)
    found = analyse_gliders(times, poses, config(30)).gliders
    assert [(g.start_period, g.lifetime_periods) for g in found] == [(0, 35), (36, 34)]
    runs = bound_runs(np.array(mask)[:, None])
    assert runs.start.tolist() == [0, 36] and runs.stop.tolist() == [35, 70]


@pytest.mark.parametrize(('phi', 'expected'), [
    (math.pi, GliderClass.C1),
    (math.radians(200), GliderClass.C1),          # "nearly" anti-aligned
    (math.radians(10), GliderClass.C2),
    (math.radians(350), GliderClass.C2),
    (math.radians(90), GliderClass.UNCLASSIFIED),
])
def test_c1_versus_c2(phi: float, expected: GliderClass) -> None:
    times, poses = pair_scene(periods(40, 0, 35), phi=phi)
    (g,) = analyse_gliders(times, poses, config(30)).gliders
    assert g.glider_class is expected
    assert g.phi_mean == pytest.approx(phi)


def test_class_uses_the_circular_mean_across_zero() -> None:
    # phi alternates 10 and 350 degrees: arithmetic mean 180 (C1!), circular mean 0 (C2).
    times, _ = pair_scene(periods(40, 0, 35))
    phi = np.where(np.arange(times.size) % 2 == 0, math.radians(10), math.radians(350))
    times, poses = pair_scene(periods(40, 0, 35), phi=phi)
    (g,) = analyse_gliders(times, poses, config(30)).gliders
    assert g.glider_class is GliderClass.C2
    assert min(g.phi_mean, 2 * math.pi - g.phi_mean) == pytest.approx(0.0, abs=1e-9)


def test_classify_configuration_tolerance() -> None:
    assert classify_configuration(math.radians(140), math.radians(45)) is GliderClass.C1
    assert classify_configuration(math.radians(130), math.radians(45)) is GliderClass.UNCLASSIFIED
    assert classify_configuration(math.nan) is GliderClass.UNCLASSIFIED


@pytest.mark.parametrize(('phi_deg', 'expected'), [
    (135.5, GliderClass.C1), (148.0, GliderClass.C1), (224.5, GliderClass.C1),   # C1: 135 to 225 deg
    (134.5, GliderClass.UNCLASSIFIED), (225.5, GliderClass.UNCLASSIFIED),
    (315.5, GliderClass.C2), (0.0, GliderClass.C2), (44.5, GliderClass.C2),      # C2: 315 to 45 deg
    (45.5, GliderClass.UNCLASSIFIED), (314.5, GliderClass.UNCLASSIFIED), (90.0, GliderClass.UNCLASSIFIED),
])
def test_the_default_phi_bands(phi_deg: float, expected: GliderClass) -> None:
    """C1 is a mean phi of 135-225 deg (the demo's glider, mean phi 148 deg, is C1), C2 315-45 deg."""
    assert classify_configuration(math.radians(phi_deg)) is expected
    assert classify_configuration(math.radians(phi_deg), GliderConfig().class_tolerance) is expected


def test_a_still_bound_pair_is_not_a_glider_and_a_travelling_one_is() -> None:
    """A glider is a bound pair whose centre of mass travels >= 1 W per 100 periods of its run."""
    still = analyse_gliders(*pair_scene(periods(40, 0, 40), velocity=(0.0, 0.0)), config(30))
    (g,) = still.gliders
    assert (g.kind, g.is_glider, g.label) == (PairKind.BOUND_PAIR, False, 'C1 bound pair')
    assert g.travel_w_per_100 == pytest.approx(0.0)
    # 1.1 and 0.9 W per 100 periods over 40 samples (39 periods between the first and the last)
    for rate, kind in ((1.1, PairKind.GLIDER), (0.9, PairKind.BOUND_PAIR)):
        speed = rate / 100.0 * 0.054 * 40 / (39 * PERIOD)
        (g,) = analyse_gliders(*pair_scene(periods(40, 0, 40), velocity=(speed, 0.0)), config(30)).gliders
        assert g.travel_w_per_100 == pytest.approx(rate)
        assert g.kind is kind
    (g,) = analyse_gliders(*pair_scene(periods(40, 0, 40), velocity=(0.001, 0.0)),
                           config(30, travel_min_w_per_100=50.0)).gliders
    assert not g.is_glider                                      # the rate is a setting


def test_running_labels_appear_only_once_their_definition_is_met() -> None:
    # bound from period 0 for 60 periods, still for the first 40 periods, then moving fast
    times, poses = pair_scene(periods(60, 0, 60), phi=math.radians(180))
    moving = times >= 40 * PERIOD
    poses[moving, :2, 0] += 0.01 * (times[moving] - 40 * PERIOD)[:, None]
    analysis = analyse_gliders(times, poses, config(30))
    (g,) = analysis.gliders
    labels = running_labels(analysis, g)
    assert len(labels) == 60
    assert set(labels[:29]) == {'bound'}                       # fewer than K = 30 periods: no class, no glider
    assert set(labels[29:41]) == {'C1 bound pair'}             # K periods, still
    first = labels.index('C1 glider')
    assert 41 <= first < 60 and set(labels[first:]) == {'C1 glider'}
    assert labels[-1] == g.label                               # the whole run's words


def test_the_summary_line_counts_bound_pairs_and_gliders() -> None:
    still = analyse_gliders(*pair_scene(periods(40, 0, 40)), config(30)).gliders
    assert glider_summary(still) == '1 bound pair, no glider'
    moving = analyse_gliders(*pair_scene(periods(40, 0, 40), velocity=(0.002, 0.0)), config(30)).gliders
    assert glider_summary(moving) == '1 bound pair, 1 of them a glider (0-1 C1)'
    assert glider_summary(()) == 'no bound pair, no glider'


def test_theta_and_r_of_the_glider() -> None:
    times, poses = pair_scene(periods(40, 0, 40), theta=math.radians(300))
    (g,) = analyse_gliders(times, poses, config(30)).gliders
    assert g.theta_mean == pytest.approx(math.radians(300))
    assert g.r_mean == pytest.approx(R_BOUND)


def test_transport_of_a_ballistic_glider() -> None:
    v = (0.003, -0.004)                                        # 5 mm/s
    times, poses = pair_scene(periods(220, 10, 200), velocity=v)
    cfg = config(100)
    (g,) = analyse_gliders(times, poses, cfg).gliders
    elapsed = (200 - 1) * PERIOD                               # first to last per-period sample
    assert g.distance == pytest.approx(0.005 * elapsed)
    assert g.path_length == pytest.approx(0.005 * elapsed)
    assert g.v_com == pytest.approx(0.005)
    assert g.net_speed == pytest.approx(0.005)
    assert g.beta == pytest.approx(2.0, abs=1e-6)
    assert g.com_path.shape == (200, 2)
    row = glider_table([g], cfg)[0]
    assert row['distance_w'] == pytest.approx(g.distance / 0.054)
    assert row['v_com_mm_s'] == pytest.approx(5.0)
    w_cfg = dataclasses.replace(cfg, width=0.1)
    assert glider_table([g], w_cfg)[0]['distance_w'] == pytest.approx(g.distance / 0.1)


def test_random_walk_glider_is_diffusive() -> None:
    rng = np.random.default_rng(11)
    n_periods = 1200
    times, poses = pair_scene(periods(n_periods, 0, n_periods))
    walk = np.cumsum(rng.normal(scale=1e-3, size=(n_periods, 2)), axis=0)
    poses[:, :2, :2] += np.repeat(walk, FRAMES_PER_PERIOD, axis=0)[:, None, :]
    (g,) = analyse_gliders(times, poses, config(30, msd_max_lag=60)).gliders
    assert g.beta == pytest.approx(1.0, abs=0.15)


def test_nan_frames_are_skipped_not_propagated() -> None:
    times, poses = pair_scene(periods(60, 5, 50), phi=math.radians(175), velocity=(0.002, 0.0))
    clean = analyse_gliders(times, poses, config(30)).gliders[0]
    holed = poses.copy()
    rng = np.random.default_rng(0)
    not_first = np.flatnonzero(np.arange(times.size) % FRAMES_PER_PERIOD != 0)
    holed[rng.choice(not_first, 150, replace=False), rng.integers(0, 2)] = np.nan
    holed[::FRAMES_PER_PERIOD * 3, 1] = np.inf                # some first frames too: next one is used
    (g,) = analyse_gliders(times, holed, config(30)).gliders
    assert (g.start_period, g.lifetime_periods, g.glider_class) == (5, 50, GliderClass.C1)
    for name in ('r_mean', 'theta_mean', 'phi_mean', 'distance', 'path_length', 'v_com', 'beta'):
        value = getattr(g, name)
        assert math.isfinite(value), name
        assert value == pytest.approx(getattr(clean, name), rel=0.02), name
    assert np.all(np.isfinite(g.com_path))


def test_a_robot_unseen_for_whole_periods_leaves_nan_samples_but_finite_statistics() -> None:
    times, poses = pair_scene(periods(60, 0, 60), velocity=(0.002, 0.0))
    contacts = np.zeros((times.size, 3), dtype=bool)
    contacts[:, 0] = True                                      # FSRs still report the contact
    poses[20 * FRAMES_PER_PERIOD:23 * FRAMES_PER_PERIOD, 1] = np.nan
    (g,) = analyse_gliders(times, poses, config(30), contacts=contacts).gliders
    assert g.lifetime_periods == 60
    assert np.isnan(g.com_path[20:23]).all() and np.isfinite(np.delete(g.com_path, [20, 21, 22], 0)).all()
    assert all(math.isfinite(v) for v in (g.r_mean, g.phi_mean, g.distance, g.v_com, g.beta))
    # without contacts those periods are unbound and the run splits
    split = analyse_gliders(times, poses, config(30)).gliders
    assert [(s.start_period, s.lifetime_periods) for s in split] == [(23, 37)]


def test_never_seen_pair_finds_nothing() -> None:
    times, poses = pair_scene(periods(40, 0, 40))
    poses[:, 1] = np.nan
    analysis = analyse_gliders(times, poses, config(1))
    assert analysis.gliders == ()
    assert not analysis.periods.bound.any()


def test_frames_before_t0_are_ignored() -> None:
    times, poses = pair_scene(periods(60, 0, 40))
    analysis = analyse_gliders(times, poses, config(30), t0=10 * PERIOD)
    (g,) = analysis.gliders
    assert (g.start_period, g.lifetime_periods) == (0, 30)
    assert g.start_time == pytest.approx(10 * PERIOD)
    assert analysis.times[0] == pytest.approx(10 * PERIOD)


def test_bad_input_is_rejected_clearly() -> None:
    times, poses = pair_scene(periods(5, 0, 5))
    backwards = times.copy()
    backwards[3] = backwards[1]
    with pytest.raises(GliderInputError, match='must not decrease'):
        analyse_gliders(backwards, poses)
    with pytest.raises(GliderInputError, match='one entry per frame'):
        analyse_gliders(times[:-1], poses)
    with pytest.raises(GliderInputError, match='finite'):
        analyse_gliders(np.full(times.size, np.nan), poses)
    with pytest.raises(GliderInputError, match='no frames at or after t0'):
        analyse_gliders(times, poses, t0=1e6)


@pytest.mark.parametrize('bad', [
    {'period': 0.0}, {'r_bind': -1.0}, {'min_periods': 0}, {'min_periods': 2.5},
    {'class_tolerance': math.pi}, {'width': math.nan}, {'msd_min_lag': 3, 'msd_max_lag': 3},
])
def test_invalid_config_is_a_value_error(bad: dict[str, object]) -> None:
    with pytest.raises(GliderConfigError):
        GliderConfig(**bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        GliderConfig(**bad)  # type: ignore[arg-type]


def test_summary_table_lists_every_glider() -> None:
    mask = periods(200, 0, 40)
    mask[60:160] = [True] * 100
    phi = np.where(np.arange(200 * FRAMES_PER_PERIOD) < 50 * FRAMES_PER_PERIOD, math.radians(5), math.pi)
    times, poses = pair_scene(mask, phi=phi, velocity=(0.001, 0.0))
    cfg = config(30)
    gliders = analyse_gliders(times, poses, cfg).gliders
    rows = glider_table(gliders, cfg)
    assert [(r['class'], r['start_period'], r['lifetime_periods']) for r in rows] == [('C2', 0, 40),
                                                                                     ('C1', 60, 100)]
    assert {'i', 'j', 'class', 'start_s', 'lifetime_s', 'distance_w', 'beta', 'v_com_mm_s'} <= set(rows[0])
    text = format_glider_table(rows)
    lines = text.splitlines()
    assert 'dist [W]' in lines[0] and 'V_com [mm/s]' in lines[0] and 'beta' in lines[0]
    assert 'travels' in lines[0] and 'W / 100 T' in lines[0] and 'kind' in lines[0]
    assert len(lines) == 4 and ' C2 ' in lines[2] and ' C1 ' in lines[3]
    # 0.001 m/s: 39 x 1.6 mm in 40 periods = 2.9 W per 100 periods, a glider; 99 x 1.6 mm in 100: 2.96
    assert [(r['kind'], r['travels']) for r in rows] == [('glider', True), ('glider', True)]
    assert rows[0]['travel_w_per_100'] == pytest.approx(100 * 0.001 * 39 * PERIOD / 0.054 / 40)
    assert format_glider_table([]) == 'no bound pairs, so no gliders'
    ens = ensemble_msd(gliders, max_lag=5)
    assert np.all(np.isfinite(ens.msd))


def test_plots_write_pngs(tmp_path: Path) -> None:
    times, poses = pair_scene(periods(60, 5, 40), velocity=(0.002, 0.001))
    analysis = analyse_gliders(times, poses, config(30))
    out = plot_glider_analysis(analysis, tmp_path / 'run' / 'gliders.png')
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    empty = plot_glider_analysis(analyse_gliders(times, poses, config(50)), tmp_path / 'none.png')
    assert empty.stat().st_size > 1000
    figure = draw_pair_coordinates(tmp_path / 'pair.png')
    assert figure.read_bytes()[:4] == b'\x89PNG'


def test_performance_smoke_twenty_thousand_frames_seven_robots() -> None:
    rng = np.random.default_rng(9)
    n_frames, n_robots = 20000, 7
    times = np.arange(n_frames) * 0.05
    start = np.stack([np.cos(np.arange(n_robots)), np.sin(np.arange(n_robots))], axis=1) * 0.08
    xy = start + np.cumsum(rng.normal(scale=4e-4, size=(n_frames, n_robots, 2)), axis=0)
    heading = np.cumsum(rng.normal(scale=0.02, size=(n_frames, n_robots, 1)), axis=0)
    poses = np.concatenate([xy, heading], axis=2)
    poses[rng.random((n_frames, n_robots)) < 0.02] = np.nan
    analysis = analyse_gliders(times, poses, config(30))
    assert analysis.coords.r.shape == (n_frames, 21)
    assert analysis.periods.bound.shape == (625, 21)
    for g in analysis.gliders:
        assert g.lifetime_periods >= 30 and math.isfinite(g.r_mean)


def test_a_third_robot_near_the_pair_crowds_exactly_the_periods_it_visits() -> None:
    times, poses = pair_scene(periods(50, 0, 50))                # bound all 50 periods
    visit = (times >= 10 * PERIOD) & (times < 13 * PERIOD)        # periods 10, 11, 12
    poses[visit, 2, :2] = poses[visit, 0, :2] + [0.0, -0.10]      # 10 cm from robot 0: within 2 W
    (g,) = analyse_gliders(times, poses, config(30)).gliders
    assert g.isolation == pytest.approx(47 / 50)
    assert g.isolated                                              # 0.94 >= 0.9
    (g,) = analyse_gliders(times, poses, config(30, isolated_fraction=0.95)).gliders
    assert not g.isolated
    poses[visit, 2, :2] = poses[visit, 0, :2] + [0.0, -0.12]      # 12 cm > 2 W = 10.8 cm: not near
    (g,) = analyse_gliders(times, poses, config(30)).gliders
    assert g.isolation == 1.0


def test_a_pair_inside_a_cluster_is_not_isolated_and_the_table_says_so() -> None:
    times, poses = pair_scene(periods(40, 0, 40))
    poses[:, 2, :2] = poses[:, 1, :2] + [0.0, 0.09]               # a third robot rides along
    gliders = analyse_gliders(times, poses, config(30)).gliders
    pair = [g for g in gliders if (g.i, g.j) == (0, 1)][0]
    assert pair.isolation == 0.0 and not pair.isolated
    rows = {(r['i'], r['j']): r for r in glider_table(gliders)}
    assert rows[(0, 1)]['isolated'] is False
    assert 'isolated' in format_glider_table(glider_table(gliders)).splitlines()[0]


def test_the_one_bound_rule_is_r_under_1_6_bl_in_any_frame() -> None:
    from smarticle_common.facts import BODY_LENGTH, R_BIND_BL
    assert GliderConfig().r_bind == pytest.approx(R_BIND_BL * BODY_LENGTH)
    times, poses = pair_scene(periods(40, 0, 0))
    close = np.arange(0, times.size, FRAMES_PER_PERIOD) + 5
    poses[close, 1, :2] = poses[close, 0, :2] + [0.0, 0.99 * R_BIND_BL * BODY_LENGTH]
    assert analyse_gliders(times, poses, config(40)).periods.bound[:, 0].all()
    poses[close, 1, :2] = poses[close, 0, :2] + [0.0, 1.01 * R_BIND_BL * BODY_LENGTH]
    assert not analyse_gliders(times, poses, config(40)).periods.bound[:, 0].any()
