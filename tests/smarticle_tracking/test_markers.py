"""Marker shapes of the glider monitor, their PNG rendering, and the shipped parameter files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from smarticle_tracking.glider_monitor import GliderMonitor
from smarticle_tracking.gliders import GliderClass, GliderConfig
from smarticle_tracking.markers import (BOUND_COLOUR, CLASS_COLOURS, ROBOT_COLOUR, RobotDims, render_png, robot_outline,
                                       scene_markers)
from smarticle_tracking.parameters import (MONITOR_PARAMS, TRACKER_PARAMS,
                                         SettingsError, monitor_settings, parse_tag_ids, tracker_config)

from tests.helpers.glider_scenes import pair_scene, periods


def test_defaults_build_valid_configs() -> None:
    tracker = tracker_config({s.name: s.default for s in TRACKER_PARAMS})
    assert tracker.tag_ids == tuple(range(7))
    monitor = monitor_settings({s.name: s.default for s in MONITOR_PARAMS})
    assert monitor.t0 is None and monitor.glider.r_bind == pytest.approx(1.6 * 0.054)
    assert parse_tag_ids('3, 4 5') == (3, 4, 5)
    with pytest.raises(SettingsError, match='tag_ids'):
        parse_tag_ids('1 two')


def test_outline_has_body_heading_tick_and_arms() -> None:
    dims = RobotDims()
    body_only = robot_outline((0.0, 0.0, math.pi / 2), None, dims)
    assert len(body_only) == 10                     # 4 body edges + heading tick, as point pairs
    xs = [p[0] for p in body_only[:8]]
    assert max(xs) == pytest.approx(0.027) and min(xs) == pytest.approx(-0.027)
    assert body_only[9] == pytest.approx((0.0, 0.022))   # the tick points along the normal (+y)
    with_arms = robot_outline((0.0, 0.0, math.pi / 2), (math.pi / 2, math.pi / 2), dims)
    assert len(with_arms) == 26
    assert max(p[1] for p in with_arms) == pytest.approx(0.05)   # arms folded up along +y


def _bound_pairs() -> tuple[np.ndarray, tuple]:  # type: ignore[type-arg]
    times, poses = pair_scene(periods(6, 1, 5), phi=math.pi)
    monitor = GliderMonitor(GliderConfig(min_periods=3))
    bound: tuple = ()  # type: ignore[type-arg]
    for t, frame in zip(times, poses, strict=True):
        bound = monitor.update(t, frame)
    return poses[-1], bound


def test_scene_markers_show_robots_and_a_bond_coloured_by_class() -> None:
    frame, bound = _bound_pairs()
    assert [(b.i, b.j, b.glider_class) for b in bound] == [(0, 1, GliderClass.C1)]
    frame = frame.copy()
    frame[2] = np.nan                                   # robot 2 not seen: not drawn
    shapes = scene_markers(frame, bound)
    assert shapes[0].kind == 'delete_all'
    robots = {s.id: s for s in shapes if s.ns == 'robots'}
    assert sorted(robots) == [0, 1]
    assert robots[0].rgba == CLASS_COLOURS[GliderClass.C1]
    bonds = [s for s in shapes if s.ns == 'gliders']
    assert len(bonds) == 1 and bonds[0].points == (tuple(frame[0, :2]), tuple(frame[1, :2]))
    label = next(s for s in shapes if s.ns == 'glider_labels')
    assert label.text.startswith('C1 bound pair 0-1') and '5 T' in label.text   # still: a bound pair, no glider
    unbound = scene_markers(frame, ())
    assert all(s.rgba == ROBOT_COLOUR for s in unbound if s.ns == 'robots')


def test_a_pair_bound_fewer_than_k_periods_has_no_class_label_or_colour() -> None:
    times, poses = pair_scene(periods(6, 1, 5), phi=math.pi)
    monitor = GliderMonitor(GliderConfig(min_periods=30))
    for t, frame in zip(times, poses, strict=True):
        bound = monitor.update(t, frame)
    shapes = scene_markers(poses[-1], bound)
    label = next(s for s in shapes if s.ns == 'glider_labels')
    assert label.text.startswith('bound 0-1') and 'C1' not in label.text
    assert {s.rgba for s in shapes if s.ns in ('robots', 'gliders') and s.id in (0, 1)} == {BOUND_COLOUR}


def test_render_png_writes_a_picture(tmp_path: Path) -> None:
    frame, bound = _bound_pairs()
    arms = np.array([[1.2, 1.2], [0.3, -0.4], [0.0, 0.0]])
    path = render_png(scene_markers(frame, bound, arms), tmp_path / 'markers.png', title='test')
    assert path.stat().st_size > 5000 and path.read_bytes()[:4] == b'\x89PNG'
