"""The dense-scene and P6 runs of the Chrono reference (tools/chrono_reference/dense_scenes.py, p6_chrono.py):
the starts each engine gets, the at-rest conversion of a held C2 row, and the figures of the rules.

Everything but the last test runs without Chrono; the last runs a held start in the driver and is skipped
with one line when it is not built.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig, open_loop_angles
from smarticle_common.runs import Recording

from smarticle_sim.chrono_reference import (ChronoSettings, at_rest_scene, chrono_available, run_chrono,
                                            scene_document)
from smarticle_sim.errors import SceneError
from smarticle_sim.scenes import RobotPlacement, RobotState, Scene, dense_scene
from smarticle_sim.settings import SimConfig

TOOLS = Path(__file__).resolve().parents[2] / 'tools' / 'chrono_reference'


def tool(name: str) -> ModuleType:
    """A script of tools/chrono_reference imported as a module."""
    if str(TOOLS) not in sys.path:
        sys.path.insert(0, str(TOOLS))
    spec = importlib.util.spec_from_file_location(name, TOOLS / f'{name}.py')
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


dense = tool('dense_scenes')
p6c = tool('p6_chrono')


def moving_state(z: float = 0.02) -> RobotState:
    """A running robot's state: raised, tilted a little, moving."""
    return RobotState(z, (0.01, 0.0, 0.0, math.sqrt(1 - 1e-4)), (1e-3, 0.0, 0.0), (0.0, 0.0, 0.1), (0.2, 0.0))


# ------------------------------------------------------------------ at-rest starts


def test_at_rest_scene_keeps_poses_and_gaits_drops_the_state_arms_at_the_gait_start(gait90: GaitConfig) -> None:
    g2 = GaitConfig(gait90.alpha_max, gait90.period, gait90.servo_speed, 0.3)
    a1, a2 = open_loop_angles(g2, 0.3)
    scene = Scene((RobotPlacement(0.01, -0.02, 0.4, gait90.alpha_max + 2e-4, gait90.alpha_max, gait90,
                                  moving_state()),
                   RobotPlacement(0.09, 0.03, -1.2, a1, a2 - 5e-4, g2, moving_state())), name='held', seed=3,
                  overlap_tolerance=0.002)
    rest, correction = at_rest_scene(scene)
    assert correction == pytest.approx(5e-4)
    assert rest.name == 'held' and rest.seed == 3 and rest.overlap_tolerance == 0.002
    for before, after in zip(scene.robots, rest.robots, strict=True):
        assert after.state is None
        assert (after.x, after.y, after.heading, after.gait) == (before.x, before.y, before.heading, before.gait)
        assert before.gait is not None
        assert (after.alpha1, after.alpha2) == open_loop_angles(before.gait, before.gait.phase)


def test_at_rest_scene_refuses_arms_off_their_gait_start_and_robots_without_a_gait(gait90: GaitConfig) -> None:
    off = Scene((RobotPlacement(0.0, 0.0, 0.0, gait90.alpha_max - 0.1, gait90.alpha_max, gait90),))
    with pytest.raises(SceneError, match='from where its gait starts'):
        at_rest_scene(off)
    with pytest.raises(SceneError, match='no gait'):
        at_rest_scene(Scene((RobotPlacement(0.0, 0.0, 0.0, 0.0, 0.0, None),)))


# ------------------------------------------------------------------ P6's held rows


def test_held_rows_take_each_harvest_seeds_earliest_row() -> None:
    rows = p6c.held_rows()
    seeds = [s.seed for s in rows]
    assert seeds == sorted(set(seeds)) and len(seeds) >= 8
    from smarticle_experiments.p6 import load_held_starts

    every = [s for s in load_held_starts() if s.state is not None]
    assert set(seeds) == {s.seed for s in every}
    for row in rows:
        same = [s for s in every if s.seed == row.seed]
        assert (row.period, row.i, row.j) == min((s.period, s.i, s.j) for s in same)


def test_a_held_row_becomes_the_same_pair_at_rest_in_phase_for_chrono_and_bullet() -> None:
    config, gait = p6c.config_and_gait()
    row = p6c.held_rows()[0]
    scene, correction = p6c.row_scene(row, gait)
    assert correction < 1e-5                              # the row's arms sit on the gait's corner
    a, b = scene.robots
    ra, rb = row.state
    # the pair's shape and headings are the row's, its centre moved to the plate's centre
    assert (b.x - a.x, b.y - a.y) == pytest.approx((rb.x - ra.x, rb.y - ra.y))
    assert (a.x + b.x, a.y + b.y) == pytest.approx((0.0, 0.0), abs=1e-12)
    assert (a.heading, b.heading) == (ra.heading, rb.heading)
    r = math.hypot(b.x - a.x, b.y - a.y) / config.robot.body_length
    assert r == pytest.approx(row.r_bl, abs=1e-3)
    for robot in scene.robots:
        assert robot.state is None and robot.gait is not None and robot.gait.phase == 0.0
        assert (robot.alpha1, robot.alpha2) == pytest.approx((math.radians(90.0), math.radians(90.0)))
    doc = scene_document(config, scene, 1.6, 0.05, ChronoSettings())     # the driver's scene: no refusal
    assert [rob['gait']['phase'] for rob in doc['robots']] == [0.0, 0.0]
    assert doc['robots'][0]['body']['size'][0] == pytest.approx(config.robot.body_width)


def test_pair_outcome_applies_p6s_rule(gait90: GaitConfig) -> None:
    bl, period, per = 0.054, gait90.period, 32
    t = np.arange(0, 100 * per + 1) * period / per
    poses = np.zeros((len(t), 2, 3))
    poses[:, 1, 1] = 1.4 * bl
    poses[t > 40.5 * period, 1, 1] = 3.0 * bl            # apart from period 40 on
    meta = {'trouble': ''}
    rec = Recording(t, poses, np.zeros((len(t), 2, 2)), np.zeros((len(t), 2, 4)), np.zeros((len(t), 2, 2), bool),
                    bl, meta)
    out = p6c.pair_outcome(rec, period, 100)
    assert out['broken'] and out['lifetime'] == 41 and out['periods_run'] == 100
    together = poses.copy()
    together[:, 1, 1] = 1.4 * bl
    held = Recording(t, together, rec.arm_angles, rec.fsr, rec.contacts, bl, meta)
    assert not p6c.pair_outcome(held, period, 100)['broken']
    rows = [{'broken': True, 'lifetime': 20, 'periods_run': 100},
            {'broken': False, 'lifetime': 101, 'periods_run': 100}]
    assert p6c.kaplan_meier(rows, 10) == 1.0 and p6c.kaplan_meier(rows, 25) == 0.5


# ------------------------------------------------------------------ dense scenes


def test_a_dense_seed_is_p1s_start_the_same_in_every_engine() -> None:
    config = SimConfig()
    scene, gait = dense.scene_of(4, config)
    again = dense_scene(config.robot, gait, n=7, seed=4)
    assert scene == again and len(scene.robots) == 7
    assert all(r.gait is not None and r.gait.phase == 0.0 for r in scene.robots)      # in phase
    assert dense.scene_of(5, config)[0] != scene
    doc = scene_document(config, scene, 60 * gait.period, dense.SAMPLE_EVERY * config.physics.control_tick,
                         ChronoSettings())                                     # a whole number of Chrono steps
    assert len(doc['robots']) == 7


def test_largest_cluster_links_centres_closer_than_the_distance() -> None:
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [10.0, 0.0], [10.5, 0.0], [30.0, 0.0]])
    assert dense.largest_cluster(xy, 1.1) == 3
    assert dense.largest_cluster(xy, 0.9) == 2            # only 3 and 4 linked
    assert dense.largest_cluster(xy, 0.4) == 1


def synthetic_dense(bl: float, period: float, periods: int = 60) -> Recording:
    """Three robots: 0 and 1 bound and gliding 0.02 W per period, robot 2 far away; 32 samples per period."""
    per = 32
    t = np.arange(periods * per + 1) * period / per
    poses = np.zeros((len(t), 3, 3))
    drift = 0.02 * bl * t / period
    poses[:, 0, 0] = drift
    poses[:, 1, 0] = drift + 1.3 * bl
    poses[:, 2, :2] = (20 * bl, 20 * bl)
    s = len(t)
    return Recording(t, poses, np.zeros((s, 3, 2)), np.zeros((s, 3, 4)), np.zeros((s, 3, 3), bool), bl,
                     {'trouble': '', 'period': period})


def test_scene_figures_find_an_isolated_bound_pair_and_its_travel() -> None:
    bl, period = 0.054, 1.6
    f = dense.scene_figures(synthetic_dense(bl, period), period)
    assert f['trouble'] == '' and f['periods_run'] == 60
    (pair,) = f['bound_pairs']
    assert (pair['i'], pair['j']) == (0, 1) and pair['isolated'] and pair['periods'] >= 59
    assert pair['travel_w_per_100'] == pytest.approx(2.0, rel=0.05)
    assert f['largest_cluster_end'] == 2
    short = dense.scene_figures(synthetic_dense(bl, period, periods=20), period)
    assert short['bound_pairs'] == []                         # under 30 periods is not a bound pair


def test_engine_summary_and_verdicts() -> None:
    def scene(pairs: list[tuple[bool, float]], cluster: int, trouble: str = '') -> dict:
        return {'trouble': trouble, 'periods_run': 60, 'largest_cluster_end': cluster,
                'bound_pairs': [{'isolated': iso, 'travel_w_per_100': w, 'i': 0, 'j': 1, 'periods': 40}
                                for iso, w in pairs]}

    a = dense.engine_summary([scene([(False, 1.0)], 4), scene([(True, 3.0), (False, 1.0)], 5), scene([], 2),
                              scene([], 7, trouble='robot 3 tipped')])
    assert a['sound'] == 3 and a['trouble'] == (1, 4)
    assert a['with_bound'] == (2, 3) and a['isolated_pairs'] == (1, 3) and a['with_isolated'] == (1, 3)
    assert a['bound_per_scene'][0] == pytest.approx(1.0) and a['largest_cluster'][0] == pytest.approx(11 / 3)
    assert a['travel'][0] == pytest.approx((1.0 + 2.0) / 2)
    b = dense.engine_summary([scene([(False, 0.05)], 2), scene([(False, 0.04)], 2), scene([], 2)])
    assert dense.travel_verdict(a, b).startswith('differ')
    assert dense.travel_verdict(b, b).startswith('agree (both still)')
    assert dense.share_verdict((8, 8), (0, 8)).startswith('differ')
    assert dense.share_verdict((2, 8), (3, 8)).startswith('agree')
    assert dense.mean_verdict((1.0, 0.5, 1.5), (2.0, 1.6, 2.4)).startswith('differ')
    lines = dense.table({'bullet': a, 'chrono': b})
    assert len(lines) == 2 + len(dense.ROWS) and 'bullet vs chrono' in lines[0]


# ------------------------------------------------------------------ end to end in Chrono


@pytest.mark.skipif(not chrono_available(), reason='Chrono is not built (tools/chrono_reference/build_chrono.sh): '
                                                    'the Chrono reference run is skipped')
def test_a_held_row_runs_in_chrono_and_stays_put_for_a_period() -> None:
    config, gait = p6c.config_and_gait()
    row = p6c.held_rows()[0]
    scene, _ = p6c.row_scene(row, gait)
    rec = run_chrono(config, scene, 1, p6c.SAMPLE_EVERY, ChronoSettings())
    assert rec.trouble == '' and rec.poses.shape[1] == 2
    r0 = np.hypot(*(rec.poses[0, 1, :2] - rec.poses[0, 0, :2])) / config.robot.body_length
    assert r0 == pytest.approx(row.r_bl, abs=2e-3)
    assert rec.meta['initial'][0]['phase'] == 0.0 and rec.meta['initial'][1]['phase'] == 0.0
