"""smarticle-calibrate: fit the sim to recorded bags and write a calibrated preset file (docs/calibration_from_bags.md).

    smarticle-calibrate BAG [BAG ...] --fit NAME[=LO:HI][,NAME...] [--preset NAME|FILE] [--out DIR] [--workers N]

For each bag it rebuilds the run's scene (the first tracked poses after the gait start, the gait amplitude, each
robot's clock rate and phase), simulates it and prints the gap per observable at the preset's values, and for
runs of two or more robots the whole run's bound share and bound lifetime (bag and sim; reported, not fitted);
with ``--fit`` it fits the named parameters (``smarticle_experiments.calibrate``), prints the fitted values with
their 95 % intervals and the gaps and binding after the fit, draws both (DIR/gaps.png: the gaps, then a panel
per binding observable) and writes DIR/preset.yaml, which the sim bridge (its ``preset`` parameter), the demo
(``--preset FILE``), ``smarticle-sim --preset FILE`` and an experiment spec (``preset: FILE``) load.
Bad input is one line on stderr and exit 2.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from smarticle_common.cli import add_version, closed_pipe_safe
from smarticle_common.facts import GAIT_PERIOD

PROG = 'smarticle-calibrate'


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, description='Compare the sim with recorded runs (bags) and fit named parameters to them; '
        'write a calibrated preset file.')
    add_version(parser, 'smarticle_experiments')
    parser.add_argument('bags', nargs='+', metavar='BAG', help='bag folders of recorded runs')
    parser.add_argument('--fit', metavar='NAME[=LO:HI][,...]', default='',
                        help='parameters to fit (PhysicsConfig / RobotSpec fields, e.g. friction_body_plate, '
                        'restitution, servo_speed, total_mass); without it only the gaps are printed')
    parser.add_argument('--preset', default='small', help='robot preset name or preset file to start from '
                        '(default: small)')
    parser.add_argument('--engine', default='bullet', choices=('bullet', 'mujoco'),
                        help='engine of the sim (default: bullet)')
    parser.add_argument('--out', type=Path, default=Path('out/calibration'),
                        help='folder for preset.yaml and gaps.png (default: out/calibration)')
    parser.add_argument('--period', type=float, default=GAIT_PERIOD,
                        help=f'nominal gait period in s (default: {GAIT_PERIOD:g})')
    parser.add_argument('--alpha-max-deg', type=float, default=None,
                        help='gait amplitude in degrees (default: read from the joint commands, else 90)')
    parser.add_argument('--duration', type=float, default=None,
                        help='use at most this many seconds of each bag after the gait start')
    parser.add_argument('--max-evaluations', type=int, default=40,
                        help='most distance evaluations of the optimiser (default: 40)')
    parser.add_argument('--workers', type=int, default=0,
                        help='Dask worker processes for the bags\' trials (default 0: run in this process)')
    return parser


def _fail(message: str) -> int:
    print(f'{PROG}: {message}', file=sys.stderr)
    return 2


def _print_binding(binding: dict[str, dict[str, float]]) -> None:
    from smarticle_common.facts import R_BIND_BL

    from . import calibrate as cal

    if not binding:
        print('binding: no run of two or more robots')
        return
    print(cal.format_binding(f'binding over whole runs (not in the distance; bound: r < {R_BIND_BL:g} BL at a '
                             'period\'s strobe):', binding))


def run(ns: argparse.Namespace) -> int:
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.errors import ConfigError

    from . import calibrate as cal

    if not (math.isfinite(ns.period) and ns.period > 0):
        return _fail(f'--period must be a positive number of seconds, got {ns.period}')
    if ns.workers < 0 or ns.max_evaluations < 1:
        return _fail('--workers must be >= 0 and --max-evaluations >= 1')
    try:
        build_config(ns.preset)
        params = cal.parse_fit(ns.fit) if ns.fit else []
        runs = []
        for bag in ns.bags:
            if not Path(bag).exists():
                raise cal.BagFitError(f'bag {bag} does not exist')
            runs.append(cal.load_run(bag, ns.period, ns.alpha_max_deg, ns.duration))
        cal.check_bounds(params, runs)
    except (cal.BagFitError, ConfigError) as err:
        return _fail(str(err))
    for r in runs:
        clocks = ', '.join(f'{k}: rate {rate:.4f} phase {phase:.3f}' for k, (rate, phase)
                           in enumerate(zip(r.rates, r.phases, strict=True)))
        print(f'{r.name}: {r.robots} robots, {r.periods} periods, alpha_max {math.degrees(r.alpha_max):.0f} deg; '
              f'clocks {clocks}')
        for note in r.notes:
            print(f'  note: {note}')
    mapper: Any = None
    client_cm: Any = None
    if ns.workers > 0:
        from .engine import dask_client
        client_cm = dask_client(None, ns.workers)
        client = client_cm.__enter__()

        def mapper(fn: Any, items: Any) -> list[Any]:
            return list(client.gather(client.map(fn, items, pure=False)))
    try:
        problem = cal.Problem(runs, ns.preset, params, ns.engine, mapper)
        ns.out.mkdir(parents=True, exist_ok=True)
        if not params:
            res = problem.residuals([])
            gaps = cal.gaps(res)
            print(cal.format_gaps(f'gap per observable at {ns.preset} (distance {cal.distance(res):.4g}):', gaps))
            binding = cal.compare_binding(problem)
            _print_binding(binding)
            print(f'drawn: {cal.draw_gaps(ns.out / "gaps.png", gaps, binding=binding)}')
            return 0
        result = cal.fit(problem, ns.max_evaluations)
        binding = cal.compare_binding(problem, result.values)
    except ConfigError as err:
        return _fail(str(err))
    finally:
        if client_cm is not None:
            client_cm.__exit__(None, None, None)
    print(cal.format_gaps(f'gap per observable (distance {result.distance_default:.4g} at {ns.preset}, '
                          f'{result.distance_fit:.4g} fitted, {result.terms} terms):',
                          result.gaps_default, result.gaps_fit))
    print('fitted (95 % bootstrap interval over segments):')
    for name, value, (lo, hi) in zip(result.names, result.values, result.intervals, strict=True):
        print(f'  {name} = {value:.4g} [{lo:.4g}, {hi:.4g}]')
    print(f'evaluations: {result.evaluations}')
    _print_binding(binding)
    preset = cal.write_preset(ns.out / 'preset.yaml', ns.preset, params, result, [str(b) for b in ns.bags])
    print(f'drawn: {cal.draw_gaps(ns.out / "gaps.png", result.gaps_default, result.gaps_fit, binding)}')
    print(f'preset file: {preset}')
    return 0


@closed_pipe_safe
def main(argv: list[str] | None = None) -> None:
    ns = build_parser().parse_args(argv)
    sys.exit(run(ns))


if __name__ == '__main__':
    main()
