"""How the simulation cost grows with the number of robots, and the P1 scene against raw PyBullet stepping.

Part 1, scale: for N robots (dense hexagonal packing like the paper's Fig. 1(c), or ``--scene random``
at the same area per robot) the same scene is run four ways, interleaved, best of ``--repeats``:

* ``raw``: a bare PyBullet loop (``stepSimulation`` plus corner targets at gait quarter boundaries);
* ``world``: ``Runner.run`` (gait cores, command-on-change, trouble checks), no recording;
* ``batch``: ``run_trial`` with its defaults (poses and arm angles at 20 Hz, no FSR);
* ``batch+all``: ``run_trial`` recording poses, FSR and contacts every control tick.

Reports the real-time factor, microseconds per robot-step and, for the Runner-based modes, the time
spent outside ``Physics.step`` within the same run (the steady measure of overhead on a shared
machine), and fits cost ~ N^b (least squares on log time-per-step against log N).

Part 2, P1: 7 robots dense (seed 1), 300 periods (``--quick``: 30), batch core with the CLI defaults
against the raw loop of the same scene in the same run (``--previous``: also both at the previous default,
1/960 s with 5 solver iterations and roll / pitch inertia x100). Target: >= 10x real time on one
core at the default step.

Writes ``out/benchmarks/sim_scale.csv``, ``sim_scale_p1.csv`` and ``sim_scale.png``.

    .venv/bin/python tests/benchmarks/bench_sim_scale.py --quick
    .venv/bin/python tests/benchmarks/bench_sim_scale.py
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import (PhysicsTimer, Progress, add_clock_argument, clock_of, figure, machine_line, markdown_table,
                     out_path, write_csv)
from smarticle_common.gait import GaitConfig
from smarticle_sim.benchmark import bare_loop, batch_loop, runner_loop
from smarticle_sim.scenes import Scene, dense_scene, random_scene
from smarticle_sim.settings import SimConfig

MODES = ('raw', 'world', 'batch', 'batch+all')


def scene_for(kind: str, config: SimConfig, gait: GaitConfig, n: int, seed: int) -> tuple[SimConfig, Scene]:
    """The N-robot scene and a config whose plate is large enough for it (4 reaches of margin)."""
    spec = config.robot
    if kind == 'dense':
        scene = dense_scene(spec, gait, n, seed=seed)
    else:   # same area per robot as 7 robots in a 0.3 m square
        region = 0.3 * math.sqrt(n / 7.0)
        scene = random_scene(spec, gait, n, seed=seed, region=max(region, 4.0 * spec.reach))
    extent = max(max(abs(r.x), abs(r.y)) for r in scene.robots)
    plate = max(config.physics.plate_size, 2.0 * (extent + 4.0 * spec.reach))
    return config.with_physics(plate_size=round(plate, 3)), scene


def mode_fn(mode: str, config: SimConfig, scene: Scene, periods: float,
            clock: Callable[[], float]) -> Callable[[], tuple[int, float]]:
    """A callable running ``mode`` once and returning (physics steps, wall seconds)."""
    if mode == 'raw':
        return lambda: bare_loop(config, scene, periods, clock)
    if mode == 'world':
        return lambda: runner_loop(config, scene, periods, clock)
    if mode == 'batch':
        return lambda: batch_loop(config, scene, periods, clock=clock)
    return lambda: batch_loop(config, scene, periods, 1, True, clock)


def best_of(fns: dict[str, Callable[[], tuple[int, float]]], repeats: int, clock: Callable[[], float],
            progress: Progress | None = None, label: str = '') -> dict[str, tuple[int, float, float]]:
    """Run every callable ``repeats`` times, interleaved; keep each one's fastest run.

    Values: (steps, seconds, seconds inside Physics.step -- 0 for the raw loop, which has none).
    """
    best: dict[str, tuple[int, float, float]] = {}
    for rep in range(repeats):
        for name, fn in fns.items():
            with PhysicsTimer(clock) as timer:
                steps, seconds = fn()
            if name not in best or seconds < best[name][1]:
                best[name] = (steps, seconds, timer.inside)
        if progress is not None:
            progress.step(f'{label} repeat {rep + 1}: ' + ', '.join(
                f'{k} {s / w:,.0f} steps/s' for k, (s, w, _) in best.items()))
    return best


def solver_setting(text: str) -> tuple[int, float | None]:
    """'N' -> (N, None): N solver iterations at Bullet's residual threshold; 'N:T' -> (N, T)."""
    iterations, _, threshold = text.partition(':')
    try:
        return int(iterations), (float(threshold) if threshold else None)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected N or N:THRESHOLD, got {text!r}') from None


def main(argv: list[str] | None = None) -> int:
    """Run both parts, print tables, write CSV and PNG."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true',
                        help='smaller budgets, one repeat, P1 over 30 periods (~1.5 min)')
    parser.add_argument('--robots', type=int, nargs='+', default=[1, 2, 7, 20, 50])
    parser.add_argument('--scene', choices=('dense', 'random'), default='dense')
    parser.add_argument('--budget', type=float, default=None,
                        help='robot-steps per scale run (default 150000, quick 40000); periods = budget / '
                             '(N x steps per period), at least 2')
    parser.add_argument('--p1-periods', type=float, default=None, help='P1 length (default 300, quick 30)')
    parser.add_argument('--repeats', type=int, default=None, help='interleaved repeats (default 3, quick 1)')
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--skip-p1', action='store_true')
    parser.add_argument('--skip-scale', action='store_true')
    parser.add_argument('--previous', action='store_true',
                        help='P1 also at the previous default (1/960 s, 5 solver iterations, roll / pitch '
                        'inertia x100), in the same run')
    parser.add_argument('--iterations', type=solver_setting, nargs='*', default=[],
                        help='P1 also with these solver settings at the default step (batch core), in the same run: '
                             'N (iterations) or N:T (a cap of N iterations with residual threshold T, e.g. 20:1e-5)')
    parser.add_argument('--tilt', type=float, nargs='*', default=[],
                        help='P1 also with these roll / pitch inertia scales (tilt_inertia_scale) at the default '
                             'step and solver (batch core), in the same run')
    parser.add_argument('--out-dir', type=Path, default=None)
    parser.add_argument('--no-progress', action='store_true')
    add_clock_argument(parser)
    args = parser.parse_args(argv)
    budget = args.budget or (40000.0 if args.quick else 150000.0)
    repeats = args.repeats or (1 if args.quick else 3)
    p1_periods = args.p1_periods or (30.0 if args.quick else 300.0)
    base = SimConfig()
    clock = clock_of(args.clock)
    gait = GaitConfig.from_degrees(90.0, servo_speed=base.robot.servo_speed)
    dt = base.physics.time_step
    steps_per_period = gait.period / dt
    ph = base.physics
    print(f'# simulation cost against robot count; time step {dt:.6g} s, {ph.solver_iterations} solver iterations '
          f'({ph.large_pack_iterations} above {ph.large_pack_robots} robots), best of {repeats} interleaved, '
          f'{args.clock} time; {machine_line()}')
    progress = Progress(len(args.robots) * repeats * (not args.skip_scale) + repeats * (not args.skip_p1),
                        'scale', not args.no_progress)
    rows: list[dict[str, object]] = []
    if not args.skip_scale:
        for n in args.robots:
            config, scene = scene_for(args.scene, base, gait, n, args.seed)
            periods = max(2.0, round(budget / (n * steps_per_period)))
            best = best_of({m: mode_fn(m, config, scene, periods, clock) for m in MODES}, repeats, clock, progress,
                           f'N={n} ({periods:g} periods)')
            raw_rate = best['raw'][0] / best['raw'][1]
            for mode in MODES:
                steps, wall, inside = best[mode]
                rows.append({'robots': n, 'mode': mode, 'periods': periods, 'steps': steps, 'wall_s': wall,
                             'outside_physics': wall / inside - 1.0 if inside > 0 else float('nan'),
                             'real_time_factor': steps * dt / wall, 'us_per_robot_step': 1e6 * wall / (steps * n),
                             'us_per_step': 1e6 * wall / steps,
                             'vs_raw': (steps / wall) / raw_rate - 1.0, 'plate_m': config.physics.plate_size})
        print(f'\n## scale ({args.scene} scenes, seed {args.seed})')
        print(markdown_table(rows, [('robots', 'N', 'd'), ('mode', 'mode', ''), ('periods', 'periods', 'g'),
                                    ('real_time_factor', 'x real time', '.1f'),
                                    ('us_per_robot_step', 'us / robot-step', '.1f'),
                                    ('vs_raw', 'vs raw (separate runs)', '+.1%'),
                                    ('outside_physics', 'time outside stepSimulation', '+.1%')]))
        fits = []
        for mode in MODES:
            ns = np.array([r['robots'] for r in rows if r['mode'] == mode], dtype=float)
            cost = np.array([r['us_per_step'] for r in rows if r['mode'] == mode], dtype=float)
            b_all = np.polyfit(np.log(ns), np.log(cost), 1)[0] if len(ns) > 1 else math.nan
            big = ns >= 7
            b_big = np.polyfit(np.log(ns[big]), np.log(cost[big]), 1)[0] if big.sum() > 1 else math.nan
            fits.append({'mode': mode, 'b_all': float(b_all), 'b_big': float(b_big)})
        print('\ncost per physics step ~ N^b (least squares in log-log):')
        print(markdown_table(fits, [('mode', 'mode', ''), ('b_all', f'b (N = {min(args.robots)}..'
                                                                    f'{max(args.robots)})', '.2f'),
                                    ('b_big', 'b (N >= 7)', '.2f')]))
        write_csv(out_path('sim_scale.csv', args.out_dir), rows)
        plot(rows, out_path('sim_scale.png', args.out_dir))
    if not args.skip_p1:
        config = base
        scene = dense_scene(config.robot, gait, 7, seed=1)
        fns = {'raw PyBullet loop': lambda: bare_loop(config, scene, p1_periods, clock),
               'Runner.run, no recording': lambda: runner_loop(config, scene, p1_periods, clock),
               'batch core, CLI defaults': lambda: batch_loop(config, scene, p1_periods, clock=clock)}
        previous = config.with_physics(solver_iterations=5, tilt_inertia_scale=100.0)
        if args.previous:
            fns['raw PyBullet loop, previous default'] = lambda: bare_loop(previous, scene, p1_periods, clock)
            fns['batch core, previous default'] = lambda: batch_loop(previous, scene, p1_periods, clock=clock)
        for n_iter, threshold in args.iterations:
            iterated = config.with_physics(solver_iterations=n_iter, solver_residual_threshold=threshold)
            label = f'batch core, {n_iter} solver iterations'
            if threshold is not None:
                label += f', residual {threshold:g}'
            fns[label] = lambda cfg=iterated: batch_loop(cfg, scene, p1_periods, clock=clock)
        for scale in args.tilt:
            tilted = config.with_physics(tilt_inertia_scale=scale)
            fns[f'batch core, roll / pitch inertia x{scale:g}'] = (
                lambda cfg=tilted: batch_loop(cfg, scene, p1_periods, clock=clock))
        best = best_of(fns, repeats, clock, progress, 'P1')
        p1 = []
        for k, (s, w, i) in best.items():
            old_default = k.endswith('previous default')
            step = previous.physics.time_step if old_default else dt
            raw = best['raw PyBullet loop, previous default' if old_default else 'raw PyBullet loop']
            p1.append({'mode': k, 'time_step': f'1/{1.0 / step:.0f} s', 'steps': s, 'wall_s': w,
                       'steps_per_s': s / w, 'real_time_factor': s * step / w,
                       'vs_raw': (s / w) / (raw[0] / raw[1]) - 1.0,
                       'overhead_outside_physics': w / i - 1.0 if i > 0 else float('nan')})
        print(f'\n## P1: 7 robots dense (seed 1), {p1_periods:g} periods ({p1_periods * gait.period:g} s '
              f'simulated), best of {repeats}')
        print(markdown_table(p1, [('mode', 'mode', ''), ('time_step', 'step', ''), ('wall_s', 'time (s)', '.1f'),
                                  ('steps_per_s', 'steps/s', ',.0f'), ('real_time_factor', 'x real time', '.1f'),
                                  ('vs_raw', 'vs raw (separate runs)', '+.1%'),
                                  ('overhead_outside_physics', 'time outside stepSimulation', '+.1%')]))
        batch = p1[2]
        rtf, gap = float(batch['real_time_factor']), float(batch['vs_raw'])
        overhead = float(batch['overhead_outside_physics'])
        print(f'target: a P1 trial at >= 10x real time on one core at the default: '
              f'{"met" if rtf >= 10 else "NOT met"} ({rtf:.1f}x; {gap:+.1%} against the bare loop at the same step, '
              f'{overhead:+.1%} against its own stepSimulation time)')
        write_csv(out_path('sim_scale_p1.csv', args.out_dir), p1)
    print(f'wrote CSV/PNG under {out_path("x", args.out_dir).parent}')
    return 0


def plot(rows: list[dict[str, object]], path: Path) -> Path:
    """Microseconds per robot-step and real-time factor against N, one curve per mode."""
    fig = figure(10.0, 4.0)
    for idx, (key, label) in enumerate([('us_per_robot_step', 'us per robot-step'),
                                        ('real_time_factor', 'x real time')]):
        ax = fig.add_subplot(1, 2, idx + 1)
        for mode in MODES:
            pts = [(r['robots'], r[key]) for r in rows if r['mode'] == mode]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], 'o-', label=mode)
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_xlabel('robots N')
        ax.set_title(label, fontsize=9)
        ax.grid(True, which='both', lw=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    return path


if __name__ == '__main__':
    sys.exit(main())
