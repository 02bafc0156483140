"""The online glider monitor agrees with the batch analysis, frame by frame and at the end."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tests.helpers.glider_scenes import FRAMES_PER_PERIOD, PERIOD, pair_scene, periods

from smarticle_tracking.errors import GliderConfigError, GliderInputError
from smarticle_tracking.glider_monitor import GliderMonitor
from smarticle_tracking.gliders import GliderClass, GliderConfig, PairKind, analyse_gliders, running_labels


def jostling_robots(seed: int, n_frames: int = 2500, n_robots: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Robots random-walking in a small box, so pairs bind and unbind often; some frames unseen."""
    rng = np.random.default_rng(seed)
    times = np.arange(n_frames) * 0.2 + 3.0
    times[n_frames // 2:] += 7.3                               # a gap: whole periods without frames
    xy = np.cumsum(rng.normal(scale=0.01, size=(n_frames, n_robots, 2)), axis=0)
    xy = 0.15 - np.abs(np.mod(xy, 0.6) - 0.3)                  # reflect into a 0.3 m box
    heading = np.cumsum(rng.normal(scale=0.05, size=(n_frames, n_robots, 1)), axis=0)
    poses = np.concatenate([xy, heading], axis=2)
    poses[rng.random((n_frames, n_robots)) < 0.05] = np.nan
    return times, poses


def stream(monitor: GliderMonitor, times: np.ndarray, poses: np.ndarray,
           contacts: np.ndarray | None = None) -> list[tuple]:
    """Feed every frame; return the bound set after each frame."""
    seen = []
    for k, t in enumerate(times):
        bound = monitor.update(float(t), poses[k], None if contacts is None else contacts[k])
        seen.append(bound)
    return seen


def key(i: int, j: int, start: int, life: int) -> tuple[int, int, int, int]:
    """Identity of a glider across the two implementations."""
    return (i, j, start, life)


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_streaming_finds_the_same_gliders_as_batch(seed: int) -> None:
    times, poses = jostling_robots(seed)
    rng = np.random.default_rng(100 + seed)
    contacts = rng.random((times.size, 10)) < 0.01
    cfg = GliderConfig(min_periods=5, r_bind=0.09, travel_min_w_per_100=10.0)   # random walkers: both kinds
    batch = analyse_gliders(times, poses, cfg, contacts=contacts)
    monitor = GliderMonitor(cfg, history=10_000)
    stream(monitor, times, poses, contacts)
    online = monitor.finish()
    assert len(batch.gliders) > 10
    by_key = {key(b.i, b.j, b.start_period, b.age_periods): b for b in online}
    assert sorted(by_key) == sorted(key(g.i, g.j, g.start_period, g.lifetime_periods) for g in batch.gliders)
    for g in batch.gliders:
        b = by_key[key(g.i, g.j, g.start_period, g.lifetime_periods)]
        assert b.glider_class is g.glider_class
        assert b.start_time == pytest.approx(g.start_time)
        assert b.age == pytest.approx(g.lifetime)
        assert b.is_bound_pair and (b.kind, b.is_glider) == (g.kind, g.is_glider)
        assert b.travel_w_per_100 == pytest.approx(g.travel_w_per_100, abs=1e-9, nan_ok=True)
        assert b.phi_mean == pytest.approx(g.phi_mean, abs=1e-9)
        assert b.distance == pytest.approx(g.distance, abs=1e-12)
        assert b.isolation == pytest.approx(g.isolation, abs=1e-12)
        assert b.isolated is g.isolated
    assert len({round(g.isolation, 6) for g in batch.gliders}) > 1   # jostling robots crowd some periods
    assert {g.kind for g in batch.gliders} == {PairKind.GLIDER, PairKind.BOUND_PAIR}


def test_bound_set_after_each_period_matches_the_batch_table() -> None:
    times, poses = jostling_robots(5, n_frames=1500)
    cfg = GliderConfig(min_periods=3, r_bind=0.09)
    batch = analyse_gliders(times, poses, cfg)
    bound = batch.periods.bound
    q = np.floor((times - times[0]) / PERIOD + 1e-9).astype(int)
    last_of_period = np.flatnonzero(np.r_[q[1:] != q[:-1], True])
    monitor = GliderMonitor(cfg)
    seen = stream(monitor, times, poses)
    run = np.zeros(bound.shape[1], dtype=int)
    for qq in range(bound.shape[0]):
        previous = run.copy()
        run = np.where(bound[qq], run + 1, 0)
        frames = last_of_period[q[last_of_period] == qq]
        if frames.size == 0:
            continue
        reported = {(b.i, b.j): b.age_periods for b in seen[frames[0]]}
        pairs = batch.coords.pairs
        expected = {(int(pairs[p, 0]), int(pairs[p, 1])): int(run[p] if bound[qq, p] else previous[p])
                    for p in np.flatnonzero(bound[qq] | (previous > 0))}
        assert reported == expected, qq


def test_live_report_of_a_c1_glider() -> None:
    times, poses = pair_scene(periods(50, 2, 40), phi=math.radians(185), theta=math.radians(80))
    monitor = GliderMonitor(GliderConfig(min_periods=30))
    seen = stream(monitor, times, poses)
    at = 35 * FRAMES_PER_PERIOD + 4                            # mid period 35, run started at 2
    (b,) = seen[at]
    assert (b.i, b.j, b.start_period, b.age_periods, b.is_bound_pair) == (0, 1, 2, 34, True)
    assert (b.kind, b.is_glider, b.label) == (PairKind.BOUND_PAIR, False, 'C1 bound pair')   # it does not move
    assert b.glider_class is GliderClass.C1
    assert (b.r, b.theta, b.phi) == (pytest.approx(0.08), pytest.approx(math.radians(80)),
                                     pytest.approx(math.radians(185)))
    early = seen[5 * FRAMES_PER_PERIOD][0]
    assert (early.is_bound_pair, early.is_glider, early.label) == (False, False, 'bound')
    assert seen[-1] == ()
    (done,) = monitor.finish()
    assert (done.age_periods, done.r) == (40, pytest.approx(0.08))    # r as of the run, not after


def test_the_live_label_is_the_batch_label_of_the_run_so_far() -> None:
    """Each period the monitor says what the run so far is: 'bound', then 'C2 bound pair', then 'C2 glider'."""
    times, poses = pair_scene(periods(70, 3, 60), phi=math.radians(10))
    moving = times >= 45 * PERIOD
    poses[moving, :2, 1] += 0.008 * (times[moving] - 45 * PERIOD)[:, None]
    cfg = GliderConfig(min_periods=30)
    analysis = analyse_gliders(times, poses, cfg)
    (g,) = analysis.gliders
    expected = running_labels(analysis, g)
    seen = stream(GliderMonitor(cfg), times, poses)
    live = [seen[(g.start_period + n) * FRAMES_PER_PERIOD + FRAMES_PER_PERIOD - 1][0].label
            for n in range(g.lifetime_periods)]                  # at the last frame of each bound period
    assert live == list(expected)
    assert live[0] == 'bound' and live[29] == 'C2 bound pair' and live[-1] == 'C2 glider' == g.label
    assert 'C2 glider' not in live[:44]


def test_memory_is_bounded_by_history() -> None:
    mask = ([True] * 3 + [False]) * 50
    times, poses = pair_scene(mask)
    monitor = GliderMonitor(GliderConfig(min_periods=2), history=5)
    stream(monitor, times, poses)
    assert len(monitor.finished) == 5
    assert monitor.finished[-1].start_period == 4 * 48


def test_nan_frames_do_not_break_the_monitor() -> None:
    times, poses = pair_scene(periods(40, 0, 40))
    poses[1::3, 1] = np.nan
    monitor = GliderMonitor(GliderConfig(min_periods=30))
    seen = stream(monitor, times, poses)
    assert all(len(s) == 1 and math.isfinite(s[0].r) and math.isfinite(s[0].phi_mean) for s in seen)


def test_frames_before_t0_are_ignored() -> None:
    times, poses = pair_scene(periods(20, 0, 20))
    monitor = GliderMonitor(GliderConfig(min_periods=3), t0=5 * PERIOD)
    assert monitor.update(0.0, poses[0]) == ()
    (b,) = monitor.update(float(times[5 * FRAMES_PER_PERIOD]), poses[5 * FRAMES_PER_PERIOD])
    assert (b.start_period, b.age_periods, b.start_time) == (0, 1, pytest.approx(5 * PERIOD))


def test_bad_frames_are_rejected_and_reset_allows_a_new_run() -> None:
    times, poses = pair_scene(periods(4, 0, 4))
    monitor = GliderMonitor()
    monitor.update(1.0, poses[0])
    with pytest.raises(GliderInputError, match='backwards'):
        monitor.update(0.5, poses[1])
    with pytest.raises(GliderInputError, match='robots'):
        monitor.update(2.0, poses[1, :2])
    with pytest.raises(GliderInputError, match='one per pair'):
        monitor.update(2.0, poses[1], contacts=np.zeros(2, dtype=bool))
    with pytest.raises(GliderInputError, match='finite'):
        monitor.update(math.nan, poses[1])
    monitor.finish()
    with pytest.raises(GliderInputError, match='reset'):
        monitor.update(3.0, poses[2])
    monitor.reset()
    assert monitor.t0 is None and monitor.update(0.0, poses[0, :2]) != ()
    with pytest.raises(GliderConfigError):
        GliderMonitor(history=0)


def test_add_then_bound_pairs_is_update() -> None:
    """Frames added without building the bound pairs leave the same monitor: its bound pairs when asked,
    its finished pairs at the end, equal to one fed by update."""
    times, poses = jostling_robots(3, n_frames=800)
    cfg = GliderConfig(min_periods=5, r_bind=0.09, travel_min_w_per_100=10.0)
    updated, added = GliderMonitor(cfg, history=10_000), GliderMonitor(cfg, history=10_000)
    asked = 0
    for k, t in enumerate(times):
        bound = updated.update(float(t), poses[k])
        added.add(float(t), poses[k])
        if k % 7 == 0:
            asked += bool(bound)
            assert added.bound_pairs() == bound
    assert asked > 0
    assert added.finish() == updated.finish()
