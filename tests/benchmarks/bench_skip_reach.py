"""What the scene-dependent skips could win: a census of who is within reach of whom, tick by tick.

Issue #11 (item 6) names two skips that depend on the scene: stepping finely only where robots are within
contact reach of each other (multi-rate or per-island stepping), and moving a robot that no other robot
can reach by a cached single-robot gait cycle. Both win only as much time as the scene leaves robots out
of reach. Before building either, this script measures that share in the scene they serve (P1: 7 robots
densely packed, 90 deg, in phase) at the default physics, and prints the largest speed-up each skip could
give if its bookkeeping cost nothing:

* **global multi-rate**: the whole world steps at twice the step while no two robots are within
  ``margin`` of each other (closest points of any links, ``getClosestPoints``), so the bound is
  1 / (f_any + (1 - f_any) / 2), f_any = share of control ticks with some pair within the margin;
* **per-island**: only robots within the margin of another robot step finely, the others at twice the
  step (cost taken as linear in the robots, the measured N^1.02): 1 / (f_robot + (1 - f_robot) / 2),
  f_robot = mean share of robots within the margin of another robot;
* **cached cycle**: a robot whose centre stays farther than two reaches (plus the margin) from every other
  robot's centre for a whole gait period costs nothing: 1 / (1 - f_far), f_far = share of robot-periods.

The margins bracket what one control tick (1/60 s) can close: two arm tips approach at up to
2 x 0.39 m/s, 13 mm per tick. Writes ``out/benchmarks/sim_skip_reach.csv``.

    .venv/bin/python tests/benchmarks/bench_skip_reach.py --quick
    .venv/bin/python tests/benchmarks/bench_skip_reach.py            # seeds 1000-1002, 150 periods
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import Progress, machine_line, markdown_table, out_path, write_csv
from smarticle_common.gait import GaitConfig
from smarticle_sim.runner import Runner
from smarticle_sim.scenes import dense_scene
from smarticle_sim.settings import SimConfig

#: Contact margins (m) at which a pair counts as "within reach" for the multi-rate and per-island bounds.
MARGINS = (0.005, 0.010, 0.020)


def census(config: SimConfig, seed: int, periods: float, robots: int) -> dict[str, float]:
    """Shares of ticks / robots / robot-periods within reach in one dense trial of ``periods`` periods."""
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    scene = dense_scene(config.robot, gait, robots, seed=seed)
    far_centres = 2.0 * config.robot.reach + max(MARGINS)
    with Runner.with_gaits(config, scene) as run:
        physics, c = run.physics, run.physics.client
        ids = physics.body_ids
        run.gaits.start(0.0)
        ticks = run.ticks_for(periods * gait.period)
        per_period = run.ticks_for(gait.period)
        any_near = dict.fromkeys(MARGINS, 0)
        robot_near = dict.fromkeys(MARGINS, 0)
        near_in_period = np.zeros(robots, dtype=bool)
        far_robot_periods = 0
        for i in range(1, ticks + 1):
            run.tick()
            # closest distance between any links of each pair, capped at the largest margin
            gap = np.full((robots, robots), np.inf)
            for a, b in itertools.combinations(range(robots), 2):
                points = c.getClosestPoints(ids[a], ids[b], max(MARGINS))
                if points:
                    gap[a, b] = gap[b, a] = min(p[8] for p in points)
            nearest = gap.min(axis=1)
            for m in MARGINS:
                within = nearest <= m
                any_near[m] += bool(within.any())
                robot_near[m] += int(within.sum())
            xy = physics.body_xy()
            centre = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=-1)
            np.fill_diagonal(centre, np.inf)
            near_in_period |= centre.min(axis=1) <= far_centres
            if i % per_period == 0:
                far_robot_periods += int((~near_in_period).sum())
                near_in_period[:] = False
        row: dict[str, float] = {'seed': seed, 'periods': periods, 'robots': robots,
                                 'far_robot_periods': far_robot_periods / (robots * (ticks // per_period))}
        for m in MARGINS:
            row[f'any_{m * 1e3:g}mm'] = any_near[m] / ticks
            row[f'robot_{m * 1e3:g}mm'] = robot_near[m] / (ticks * robots)
        return row


def bounds(row: dict[str, float]) -> dict[str, float]:
    """The largest speed-up of each skip given the shares of ``row`` (a step ratio of 2)."""
    out = {'cached_cycle': 1.0 / max(1e-9, 1.0 - row['far_robot_periods'])}
    for m in MARGINS:
        key = f'{m * 1e3:g}mm'
        out[f'multirate_{key}'] = 1.0 / (row[f'any_{key}'] + (1.0 - row[f'any_{key}']) / 2.0)
        out[f'island_{key}'] = 1.0 / (row[f'robot_{key}'] + (1.0 - row[f'robot_{key}']) / 2.0)
    return out


def margin_columns(prefix: str, header: str, fmt: str) -> list[tuple[str, str, str]]:
    """Table columns ``<prefix>_<margin>mm``, one per margin of MARGINS, headed ``header`` with the margin in mm."""
    return [(f'{prefix}_{m * 1e3:g}mm', header.format(f'{m * 1e3:g}'), fmt) for m in MARGINS]


def main(argv: list[str] | None = None) -> int:
    """Run the census on each seed, print the shares and the bounds, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true', help='one seed, 20 periods (~1 min)')
    parser.add_argument('--seeds', type=int, nargs='*', default=None, help='dense-scene seeds (default 1000-1002)')
    parser.add_argument('--periods', type=float, default=None, help='gait periods per trial (default 150)')
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--out-dir', type=Path, default=None)
    parser.add_argument('--no-progress', action='store_true')
    args = parser.parse_args(argv)
    seeds = args.seeds or ([1000] if args.quick else [1000, 1001, 1002])
    periods = args.periods or (20.0 if args.quick else 150.0)
    config = SimConfig()
    print(f'# reach census: {args.robots} robots dense, 90 deg, in phase, {periods:g} periods, seeds {seeds}, '
          f'step 1/{1.0 / config.physics.time_step:.0f} s; {machine_line()}')
    progress = Progress(len(seeds), 'reach', not args.no_progress)
    rows = []
    for seed in seeds:
        row = census(config, seed, periods, args.robots)
        row.update(bounds(row))
        rows.append(row)
        progress.step(f'seed {seed}')
    mean = {k: float(np.mean([r[k] for r in rows])) for k in rows[0] if k != 'seed'}
    mean['seed'] = 'mean'  # type: ignore[assignment]
    rows.append(mean)
    shares = [('seed', 'seed', ''), *margin_columns('any', 'ticks, some pair within {} mm', '.3f'),
              *margin_columns('robot', 'robots within {} mm', '.3f'),
              ('far_robot_periods', 'robot-periods out of reach', '.4f')]
    print(markdown_table(rows, shares))
    print('\nLargest speed-up of each skip if its bookkeeping cost nothing (step ratio 2):')
    gains = [('seed', 'seed', ''), *margin_columns('multirate', 'multi-rate, {} mm', '.2f'),
             *margin_columns('island', 'per-island, {} mm', '.2f'), ('cached_cycle', 'cached cycle', '.3f')]
    print(markdown_table(rows, gains))
    path = write_csv(out_path('sim_skip_reach.csv', args.out_dir), rows)
    print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
