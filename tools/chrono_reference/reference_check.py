"""The Chrono reference check of a pair: the same start in Chrono (the authors' engine) and in Bullet.

Runs two robots from pair coordinates for N periods in each engine asked for (Chrono, Bullet, and MuJoCo with
its default ``MujocoSettings``), one run after the other,
and prints one markdown table row per run (end r and phi, net travel of the pair's centre, bound and
colliding tails, trouble, wall time); ``--out`` also writes the rows as JSON.

Usage:
  python tools/chrono_reference/reference_check.py --phase2 0 0.1 --periods 40 \
      --engines chrono bullet --bullet-steps 960 9600 --seeds 0 --out out/chrono_reference/pair.json

Bullet's contacts are read at the samples only, so its colliding tail counts touches at sample instants;
Chrono's counts any overlap between samples.

Needs the Chrono build for the chrono engine (tools/chrono_reference/build_chrono.sh); without it the
Chrono rows are skipped with one line and the Bullet rows still run.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from smarticle_common.cli import seeds_argument, closed_pipe_safe
from smarticle_common.facts import R_BIND_BL
from smarticle_common.gait import GaitConfig
from smarticle_common.runs import save_npz

from smarticle_sim.batch import run_trial
from smarticle_sim.errors import SceneError
from smarticle_sim.chrono_reference import ChronoSettings, ChronoUnavailable, pair_figures, run_chrono
from smarticle_sim.mujoco_engine import MujocoSettings, run_mujoco
from smarticle_sim.scenes import pair_scene
from smarticle_sim.config_builder import build_config

COLUMNS = ('engine', 'step', 'phase2', 'seed', 'r_end_bl', 'phi_end_deg', 'travel_w', 'travel_w_per_100',
           'bound_tail_periods', 'colliding_tail_periods', 'trouble', 'wall_time_s')


def run_one(engine: str, step: float, phase2: float, seed: int, args: argparse.Namespace) -> dict[str, Any]:
    """One pair run in ``engine`` ('chrono', 'bullet' or 'mujoco') at ``step`` s; its figures."""
    config = build_config(physics=None if engine in ('chrono', 'mujoco') else {'time_step': step},
                          diagnostics={'mass_model': args.mass_model} if args.mass_model != 'uniform' else None,
                          engine=engine)
    gait = GaitConfig.from_degrees(args.alpha_max, servo_speed=config.robot.servo_speed)
    scene = pair_scene(config.robot, gait, args.r, math.radians(args.theta), math.radians(args.phi),
                       (0.0, phase2), seed=seed)
    if engine == 'chrono':
        rec = run_chrono(config, scene, args.periods, args.sample_every,
                         ChronoSettings(time_step=step, contact=args.contact),
                         fixed=(0,) if args.hold_first else ())
    elif engine == 'mujoco':
        if args.hold_first:
            raise SystemExit('--hold-first is a Chrono option here')
        rec = run_mujoco(config, scene, args.periods, args.sample_every, MujocoSettings(time_step=step))
    else:
        if args.hold_first:
            raise SystemExit('--hold-first is a Chrono option here')
        rec = run_trial(config, scene, args.periods, sample_every=args.sample_every, record_contacts=True)
    if args.keep is not None:
        save_npz(rec, args.keep / f'{engine}_{step:.3g}_phase{phase2:g}_seed{seed}.npz')
    figures = pair_figures(rec, gait.period, config.physics.control_tick * args.sample_every, R_BIND_BL, 10)
    if engine != 'chrono':
        figures['wall_time_s'] = None
    return {'engine': engine, 'step': step, 'phase2': phase2, 'seed': seed, 'mass_model': args.mass_model,
            **figures}


def cell(value: Any) -> str:
    """A table cell."""
    if isinstance(value, float):
        return f'{value:.3g}' if abs(value) < 1e-3 and value != 0.0 else f'{value:.3f}'.rstrip('0').rstrip('.')
    return '' if value is None else str(value)


def main() -> int:
    """Run the check and print the table."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--r', type=float, default=1.3, help='start r (BL)')
    parser.add_argument('--theta', type=float, default=330.0, help='start theta (deg)')
    parser.add_argument('--phi', type=float, default=180.0, help='start phi (deg)')
    parser.add_argument('--phase2', type=float, nargs='+', default=[0.0, 0.1], help="robot 2's gait phase(s)")
    parser.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude (deg)')
    parser.add_argument('--periods', type=float, default=40.0)
    parser.add_argument('--sample-every', type=int, default=3, help='control ticks (1/60 s) between samples')
    parser.add_argument('--engines', nargs='+', choices=('chrono', 'bullet', 'mujoco'), default=['chrono', 'bullet'])
    parser.add_argument('--chrono-steps', type=float, nargs='+', default=[1e-4], help='Chrono steps (s)')
    parser.add_argument('--bullet-steps', type=int, nargs='+', default=[960, 9600],
                        help='Bullet steps as steps per second')
    parser.add_argument('--contact', choices=('smc', 'nsc'), default='smc', help="Chrono's contact")
    parser.add_argument('--mass-model', choices=('uniform', 'authors'), default='uniform',
                        help="the robots' masses in every engine: uniform (the default robot) or the authors' "
                             "published, lopsided arms (Diagnostics.mass_model)")
    parser.add_argument('--hold-first', action='store_true', help="hold robot 1's body in place (Chrono)")
    parser.add_argument('--seeds', type=seeds_argument, default=[0], help='scene seeds (7, 0..3, 0,3)')
    parser.add_argument('--out', type=Path, help='also write the rows as JSON here')
    parser.add_argument('--keep', type=Path, help='also save each run (npz, the run format) in this folder')
    args = parser.parse_args()
    rows = []
    print('| ' + ' | '.join(COLUMNS) + ' |')
    print('|' + ' --- |' * len(COLUMNS))
    for phase2 in args.phase2:
        for seed in args.seeds:
            for engine in args.engines:
                steps = {'chrono': args.chrono_steps, 'bullet': [1.0 / n for n in args.bullet_steps],
                         'mujoco': [MujocoSettings().time_step]}[engine]
                for step in steps:
                    try:
                        row = run_one(engine, step, phase2, seed, args)
                    except ChronoUnavailable as exc:
                        print(f'skipped: {exc}', file=sys.stderr)
                        break
                    except SceneError as exc:   # the robots overlap at this start: not run in any engine
                        print(f'inadmissible start (not run): {exc}', file=sys.stderr)
                        break
                    rows.append(row)
                    print('| ' + ' | '.join(f'{row[c]:.3g}' if c == 'step' else cell(row[c]) for c in COLUMNS)
                          + ' |', flush=True)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({'args': {k: str(v) if isinstance(v, Path) else v
                                                 for k, v in vars(args).items()}, 'rows': rows}, indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(closed_pipe_safe(main)())
