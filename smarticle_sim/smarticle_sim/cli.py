"""``smarticle-sim``: batch runs of the PyBullet smarticle world (no ROS) and a speed benchmark.

    smarticle-sim run --robots 7 --scene dense --periods 300 --alpha-max 90 --seed 1 --out run.npz
    smarticle-sim run --scene pair --r 1.3 --theta 90 --phi 180 --phase 0 0.25 --periods 75 --out pair.npz
    smarticle-sim bench --robots 7 --periods 10 [--cpu-time]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from smarticle_common.gait import GaitConfig, GaitError

from smarticle_common.runs import save_npz

from .batch import plot_trajectories, run_trial
from .benchmark import benchmark, format_table
from .errors import SimError
from .scenes import Scene, build_scene
from smarticle_common.facts import GAIT_PERIOD, PRESETS

from .settings import SimConfig


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``smarticle-sim``."""
    parser = argparse.ArgumentParser(prog='smarticle-sim',
                                     description=__doc__.split('\n')[0] if __doc__ else None)
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='simulate a scene and write an npz recording plus a trajectory PNG')
    bench = sub.add_parser('bench', help='time the Runner loop against a bare PyBullet loop (prints a table)')
    for p in (run, bench):
        p.add_argument('--scene', choices=('dense', 'pair', 'random'), default='dense')
        p.add_argument('--robots', type=int, default=7, help='number of robots (dense, random)')
        p.add_argument('--periods', type=float, default=300.0, help='gait periods to simulate')
        p.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude (degrees)')
        p.add_argument('--period', type=float, default=GAIT_PERIOD, help='gait period (s)')
        p.add_argument('--seed', type=int, default=1, help='seed of the scene builder')
        p.add_argument('--preset', choices=sorted(PRESETS), default='small', help='robot preset')
        p.add_argument('--time-step', type=float, default=None, help='physics time step (s)')
        p.add_argument('--control-tick', type=float, default=None, help='control tick (s), whole steps')
        p.add_argument('--solver-iterations', type=int, default=None)
        p.add_argument('--r', type=float, default=1.3, help='pair: centre distance (BL)')
        p.add_argument('--theta', type=float, default=90.0,
                       help='pair: polar angle from robot 1 body x axis (deg)')
        p.add_argument('--phi', type=float, default=180.0, help='pair: heading difference (deg)')
        p.add_argument('--phase', type=float, nargs=2, default=(0.0, 0.0), metavar=('P1', 'P2'),
                       help='pair: gait phases of robots 1 and 2 (fraction of a period)')
        p.add_argument('--random-phases', action='store_true', help='random: seeded random gait phases')
        p.add_argument('--phase-jitter', type=float, default=0.0,
                       help='dense: seeded gait-phase offsets in +-this many periods (default 0: in phase)')
    run.add_argument('--out', type=Path, default=Path('run.npz'), help='npz output file')
    run.add_argument('--png', type=Path, default=None, help='trajectory PNG (default: next to --out)')
    run.add_argument('--sample-every', type=int, default=None,
                     help='record every n control ticks (default: about 20 Hz, every 3 ticks at 60 Hz)')
    run.add_argument('--fsr', action='store_true', help='also record FSR forces and robot-robot contacts')
    run.add_argument('--no-fsr', action='store_true',
                     help='do not record FSR forces and contacts (the default; overrides --fsr)')
    run.add_argument('--no-progress', action='store_true', help='no progress bar')
    bench.add_argument('--repeats', type=int, default=3)
    bench.add_argument('--cpu-time', action='store_true',
                       help='time with process CPU time instead of wall time (steadier on a shared machine)')
    return parser


def config_from_args(args: argparse.Namespace) -> SimConfig:
    """Build the SimConfig named by the command-line options."""
    given = (('time_step', args.time_step), ('control_tick', args.control_tick),
             ('solver_iterations', args.solver_iterations))
    physics = {name: value for name, value in given if value is not None}
    return SimConfig.from_preset(args.preset, **physics)


def scene_from_args(args: argparse.Namespace, config: SimConfig) -> Scene:
    """Build the scene named by the command-line options."""
    gait = GaitConfig.from_degrees(args.alpha_max, period=args.period, servo_speed=config.robot.servo_speed)
    return build_scene(args.scene, config.robot, gait, args.robots, seed=args.seed, r=args.r,
                       theta=math.radians(args.theta), phi=math.radians(args.phi),
                       phases=(args.phase[0], args.phase[1]), random_phases=args.random_phases,
                       phase_jitter=args.phase_jitter)


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``smarticle-sim``; returns the process exit code."""
    args = build_parser().parse_args(argv)
    try:
        config = config_from_args(args)
        scene = scene_from_args(args, config)
        if args.command == 'bench':
            clock = time.process_time if args.cpu_time else time.perf_counter
            rows = benchmark(config, scene, args.periods, args.repeats, clock)
            print(f'{len(scene.robots)} robots, scene {scene.name}, {args.periods:g} periods, '
                  f'time step {config.physics.time_step:.6g} s, best of {args.repeats}, '
                  f'{"CPU" if args.cpu_time else "wall"} time')
            print(format_table(rows))
            return 0
        rec = run_trial(config, scene, args.periods, sample_every=args.sample_every,
                        record_fsr=args.fsr and not args.no_fsr,
                        record_contacts=args.fsr and not args.no_fsr,
                        progress=not args.no_progress)
    except (SimError, GaitError) as error:
        print(f'smarticle-sim: error: {error}', file=sys.stderr)
        return 2
    out = save_npz(rec, args.out)
    png = plot_trajectories(rec, args.png or out.with_suffix('.png'))
    print(f'wrote {out} ({len(rec.time)} samples of {rec.poses.shape[1]} robots) and {png}')
    if rec.trouble:
        print(f'smarticle-sim: {rec.trouble}', file=sys.stderr)
        return 3
    return 0


if __name__ == '__main__':
    sys.exit(main())
