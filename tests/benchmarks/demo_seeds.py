"""The demo's scenes on many seeds, without ROS: does a glider form and travel, does the feedback halt?

Runs ``./demo.sh``'s two scenes (``smarticle_bringup.demo_scenes``) through the batch core (``run_batch``:
the ``Runner`` with the gait cores and, in the feedback scene, the impact controller with the shipped
windows of config/stack.yaml), the same physics, starts and controller as the demo's lock-step ROS run of
that seed, and prints one row per seed, then the counts. Not a test: it prints tables and writes a CSV
under out/benchmarks/.

The rule, fixed before the seeds were run and not changed since (``demo_scenes``): a **glider** is a pair
bound (centre distance under 1.6 BL in some frame of each gait period) for at least 30 periods in a row,
the glider analysis of smarticle_tracking.gliders from the gait start; it **travels** if its net
centre-of-mass displacement over its bound run is at least 0.5 W. A seed counts for the gliders scene if
at least one glider travels, for the feedback scene if the controller halted at least once. The demo's
claim: at least 8 of 10 seeds in each.

Usage: python tests/benchmarks/demo_seeds.py [--seeds 0..9] [--periods 40] [--phase-offset 0.1]
[--scenes gliders,feedback] [--gliders-feedback] [--clock-noise]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers
from smarticle_bringup.demo_scenes import (FEEDBACK, GLIDERS, MIN_PERIODS, SCENES, TRAVEL_MIN_W_PER_100, DemoScene,
                                           analyse, run_batch, travelling)
from smarticle_common.cli import seeds_argument
from tests.benchmarks._common import machine_line, markdown_table, out_path, write_csv


def shared_windows() -> dict[str, Any]:
    """The impact windows the demo's feedback nodes read: config/stack.yaml's ``/**`` section."""
    import yaml
    from smarticle_bringup.launch_files import package_share

    path = package_share('smarticle_bringup') / 'config' / 'stack.yaml'
    return dict(yaml.safe_load(path.read_text(encoding='utf-8'))['/**']['ros__parameters'])


def glider_row(scene: DemoScene, seed: int, periods: float, windows: dict[str, Any] | None = None,
               clock_noise: bool = False) -> dict[str, Any]:
    """One seed of the gliders scene: its start, its bound pairs and whether one is a glider (travels; with
    ``windows``: with the impact controller of those windows, and its halts)."""
    start = scene.start_for(seed)
    wall0 = time.perf_counter()
    run = run_batch(scene, seed, periods, feedback=windows is not None, windows=windows, clock_noise=clock_noise)
    wall = time.perf_counter() - wall0
    width = scene.spec.body_length
    gliders = analyse(scene, run.times, run.poses).gliders
    best = max(gliders, key=lambda g: g.distance, default=None)
    moving = [g for g in gliders if travelling(g)]
    return {
        'seed': seed, 'start': f'{start.r_bl:.2f} / {start.theta_deg:.0f} / {start.phi_deg:.0f}',
        'gliders': len(gliders), 'class': best.label if best else '-',
        'life': best.lifetime_periods if best else float('nan'),
        'ongoing': ('yes' if best.ongoing else 'no') if best else '-',
        'r_bl': best.r_mean / width if best else float('nan'),
        'travel_w': best.distance / width if best else float('nan'),
        'rate': best.travel_w_per_100 if best else float('nan'),
        'travels': 'yes' if moving else 'no', 'halts': len(run.halts) if windows is not None else '-',
        'trouble': run.trouble or '-', 'wall_s': wall,
    }


def feedback_row(scene: DemoScene, seed: int, periods: float, windows: dict[str, Any]) -> dict[str, Any]:
    """One seed of the feedback scene: its halts per robot and the first halt's time."""
    wall0 = time.perf_counter()
    run = run_batch(scene, seed, periods, windows=windows)
    wall = time.perf_counter() - wall0
    per_robot = [sum(1 for _, k, _ in run.halts if k == robot) for robot in range(run.poses.shape[1])]
    return {'seed': seed, 'halts': len(run.halts), 'per_robot': ' / '.join(str(n) for n in per_robot),
            'first_s': run.halts[0][0] if run.halts else float('nan'),
            'trouble': run.trouble or '-', 'wall_s': wall}


GLIDER_COLUMNS = (('seed', 'seed', 'd'), ('start', 'start r [BL] / theta / phi [deg]', ''),
                  ('gliders', 'bound pairs', 'd'), ('class', 'what', ''), ('life', 'lifetime [periods]', '.0f'),
                  ('ongoing', 'bound at the end', ''), ('r_bl', 'r [BL]', '.2f'), ('travel_w', 'travel [W]', '.2f'),
                  ('rate', 'W per 100 periods', '.1f'),
                  ('travels', f'travels (>= {TRAVEL_MIN_W_PER_100:g} W per 100 periods)', ''), ('halts', 'halts', ''),
                  ('trouble', 'trouble', ''),
                  ('wall_s', 'wall [s]', '.1f'))
FEEDBACK_COLUMNS = (('seed', 'seed', 'd'), ('halts', 'halts', 'd'), ('per_robot', 'robot 0 / 1', ''),
                    ('first_s', 'first halt [s after start]', '.2f'), ('trouble', 'trouble', ''),
                    ('wall_s', 'wall [s]', '.1f'))


def main(argv: list[str] | None = None) -> int:
    """Run the seeds and print the tables; exit 0 (the counts are reported, not asserted)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--seeds', type=seeds_argument, default=list(range(10)),
                        help='seeds (0..9 by default; syntax 7, 0..19, 0,3,5)')
    parser.add_argument('--periods', type=float, default=None,
                        help=f'gliders scene: gait periods (default the demo\'s, {GLIDERS.periods:g})')
    parser.add_argument('--feedback-periods', type=float, default=None,
                        help=f'feedback scene: gait periods (default the demo\'s, {FEEDBACK.periods:g})')
    parser.add_argument('--phase-offset', type=float, default=None,
                        help='gliders scene: robot 1 ahead of robot 0 by this many periods (default the '
                             f"demo's, {GLIDERS.start.phases[1]:g}; 0 = in phase, the contrast)")
    parser.add_argument('--gliders-feedback', action='store_true',
                        help='gliders scene: run the impact controller too (the shipped windows) and count its halts '
                             '(the demo runs this scene open loop: the small robot\'s contacts stay below the window)')
    parser.add_argument('--clock-noise', action='store_true',
                        help="gliders scene: each robot's gait clock off by the seed's draw of the cited spread "
                             '(0.29 %% sd), as ./demo.sh --clock-noise runs it')
    parser.add_argument('--scenes', default='gliders,feedback',
                        help=f'comma-separated scenes to run (default gliders,feedback; known: {", ".join(SCENES)})')
    args = parser.parse_args(argv)
    wanted = [s for s in args.scenes.split(',') if s]
    unknown = set(wanted) - set(SCENES)
    if unknown:
        parser.error(f'unknown scene(s) {", ".join(sorted(unknown))}; known: {", ".join(SCENES)}')
    print(f'# demo scenes on seeds {args.seeds[0]}..{args.seeds[-1]} ({len(args.seeds)}), batch core, '
          f'{machine_line()}')
    if 'gliders' in wanted:
        scene = GLIDERS
        if args.phase_offset is not None:
            scene = replace(scene, start=replace(scene.start, phases=(0.0, args.phase_offset % 1.0)))
        periods = scene.periods if args.periods is None else args.periods
        rows = []
        for seed in args.seeds:
            rows.append(glider_row(scene, seed, periods, shared_windows() if args.gliders_feedback else None,
                                   args.clock_noise))
            print(f'[gliders seed {seed}] {rows[-1]["gliders"]} bound pair(s), a glider: {rows[-1]["travels"]}',
                  file=sys.stderr, flush=True)
        hits = sum(r['travels'] == 'yes' for r in rows)
        control = ('with the impact controller' if args.gliders_feedback else 'open loop') + \
            (', clock noise' if args.clock_noise else '')
        print(f'\n## {scene.key}: {scene.title}\n{scene.preset} robots, start {scene.start}, jitter +-{scene.jitter}, '
              f'{periods:g} periods, {control}; bound pair = bound >= {MIN_PERIODS} periods, glider = a bound pair '
              f'whose centre travels (net) >= {TRAVEL_MIN_W_PER_100:g} W per 100 periods '
              '(the longest-travelling bound pair of each seed)\n')
        print(markdown_table(rows, GLIDER_COLUMNS))
        print(f'\n**{hits} of {len(rows)} seeds** have a glider (>= {TRAVEL_MIN_W_PER_100:g} W per 100 periods)')
        print(f'CSV: {write_csv(out_path("demo_seeds_gliders.csv"), rows)}')
    if 'feedback' in wanted:
        scene = FEEDBACK
        periods = scene.periods if args.feedback_periods is None else args.feedback_periods
        windows = shared_windows()
        rows = []
        for seed in args.seeds:
            rows.append(feedback_row(scene, seed, periods, windows))
            print(f'[feedback seed {seed}] {rows[-1]["halts"]} halts', file=sys.stderr, flush=True)
        hits = sum(r['halts'] > 0 for r in rows)
        print(f'\n## {scene.key}: {scene.title}\n{scene.preset} robots, start {scene.start}, jitter +-{scene.jitter}, '
              f'{periods:g} periods, the windows of config/stack.yaml\n')
        print(markdown_table(rows, FEEDBACK_COLUMNS))
        print(f'\n**{hits} of {len(rows)} seeds** have halts')
        print(f'CSV: {write_csv(out_path("demo_seeds_feedback.csv"), rows)}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
