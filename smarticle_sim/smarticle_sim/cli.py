"""``smarticle-sim``: batch runs of the PyBullet smarticle world (no ROS) and a speed benchmark.

    smarticle-sim run --robots 7 --scene dense --periods 300 --alpha-max 90 --seed 1 --out run.npz
    smarticle-sim run --scene pair --r 1.3 --theta 90 --phi 180 --phase 0 0.25 --periods 75 --out pair.npz
    smarticle-sim bench --robots 7 --periods 10 [--cpu-time]
    smarticle-sim run --noise paper --seed 1 --periods 100 --out noisy.npz
    smarticle-sim run --preset out/calibration/preset.yaml --scene pair --periods 20 --out lab_pair.npz
    smarticle-sim phase-drift --robots 7 --periods 100 --seed 1
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

from smarticle_common.gait import GaitConfig, GaitError

from smarticle_common.runs import save_npz

from .batch import plot_trajectories, run_trial
from .drift import format_phase_drift, phase_drift
from .benchmark import benchmark, format_table
from .errors import SimError
from .scenes import Scene, build_scene
from smarticle_common.facts import GAIT_PERIOD, PRESETS

from .config_builder import build_config
from .settings import NoiseConfig, SimConfig
from smarticle_common.cli import add_version, closed_pipe_safe


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``smarticle-sim``."""
    parser = argparse.ArgumentParser(prog='smarticle-sim',
                                     description=__doc__.split('\n')[0] if __doc__ else None)
    add_version(parser, 'smarticle_sim')
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='simulate a scene and write an npz recording plus a trajectory PNG')
    bench = sub.add_parser('bench', help='time the Runner loop against a bare PyBullet loop (prints a table)')
    drift = sub.add_parser('phase-drift', help="measure the robots' gait phase spread against time under "
                                               'the noise (default: --noise paper; prints a table)')
    for p in (run, bench, drift):
        p.add_argument('--scene', choices=('dense', 'pair', 'random'), default='dense')
        p.add_argument('--robots', type=int, default=7, help='number of robots (dense, random)')
        p.add_argument('--periods', type=float, default=300.0, help='gait periods to simulate')
        p.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude (degrees)')
        p.add_argument('--period', type=float, default=GAIT_PERIOD, help='gait period (s)')
        p.add_argument('--seed', type=int, default=1, help='seed of the scene builder')
        p.add_argument('--preset', default='small', metavar='NAME|FILE',
                       help=f'robot preset name ({", ".join(sorted(PRESETS))}) or a preset file (.yaml, e.g. '
                            "smarticle-calibrate's preset.yaml: a base preset and its physics and robot values; "
                            'default: small)')
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
        p.add_argument('--noise', choices=('none', 'paper'), default='paper' if p is drift else 'none',
                       help='noise with a cause: none, or the cited figures (paper); the options below '
                            'change single sources')
        p.add_argument('--clock-rate-sd', type=float, default=None,
                       help="relative sd of each robot's gait clock rate (paper: 0.0029)")
        p.add_argument('--servo-jitter', type=float, default=None,
                       help='servo command delay, uniform in [0, this] s (paper: 0.02, one 50 Hz PWM frame)')
        p.add_argument('--friction-sd', type=float, default=None,
                       help='relative sd of the body-plate friction across the plate (paper: 0.06)')
        p.add_argument('--friction-length', type=float, default=None,
                       help='correlation length of the friction field (m; paper: 0.05)')
        p.add_argument('--noise-seed', type=int, default=None, help='seed of the noise draws (default: --seed)')
    run.add_argument('--out', type=Path, default=Path('run.npz'), help='npz output file')
    run.add_argument('--png', type=Path, default=None, help='trajectory PNG (default: next to --out)')
    run.add_argument('--sample-every', type=int, default=None,
                     help='record every n control ticks (default: about 20 Hz, every 3 ticks at 60 Hz)')
    run.add_argument('--fsr', action='store_true', help='also record FSR forces and robot-robot contacts')
    run.add_argument('--no-fsr', action='store_true',
                     help='do not record FSR forces and contacts (the default; overrides --fsr)')
    run.add_argument('--no-progress', action='store_true', help='no progress bar')
    drift.add_argument('--every', type=int, default=10, help='table row every this many periods')
    bench.add_argument('--repeats', type=int, default=3)
    bench.add_argument('--cpu-time', action='store_true',
                       help='time with process CPU time instead of wall time (steadier on a shared machine)')
    return parser


def config_from_args(args: argparse.Namespace) -> SimConfig:
    """Build the SimConfig named by the command-line options."""
    given = (('time_step', args.time_step), ('control_tick', args.control_tick),
             ('solver_iterations', args.solver_iterations))
    physics = {name: value for name, value in given if value is not None}
    return build_config(args.preset, physics, noise=noise_from_args(args))


def noise_from_args(args: argparse.Namespace) -> NoiseConfig:
    """The NoiseConfig named by ``--noise`` and the single-source options."""
    noise = NoiseConfig.paper() if args.noise == 'paper' else NoiseConfig.none()
    given = (('clock_rate_sd', args.clock_rate_sd), ('servo_jitter', args.servo_jitter),
             ('friction_sd', args.friction_sd), ('friction_length', args.friction_length),
             ('seed', args.noise_seed))
    return replace(noise, **{name: value for name, value in given if value is not None})


def scene_from_args(args: argparse.Namespace, config: SimConfig) -> Scene:
    """Build the scene named by the command-line options."""
    gait = GaitConfig.from_degrees(args.alpha_max, period=args.period, servo_speed=config.robot.servo_speed)
    return build_scene(args.scene, config.robot, gait, args.robots, seed=args.seed, r=args.r,
                       theta=math.radians(args.theta), phi=math.radians(args.phi),
                       phases=(args.phase[0], args.phase[1]), random_phases=args.random_phases,
                       phase_jitter=args.phase_jitter)


@closed_pipe_safe
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
        if args.command == 'phase-drift':
            study = phase_drift(config, scene, args.periods)
            print(format_phase_drift(study, args.every))
            return 3 if study.trouble else 0
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
