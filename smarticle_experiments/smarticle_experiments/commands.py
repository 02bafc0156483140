"""The study commands of ``smarticle-experiments``: P6, the C2 harvest, the C2 collision record, the physics study.

Each command builds a spec (a mapping of a trial kind, its parameters, a grid and seeds) from its options
and runs it through ``harness.run_mapping``: the one Dask engine, the one store, the one report. Only
``c2-collisions`` runs in this process: it records one pair at every physics step for
``smarticle-feedback-calibrate`` and is not a statistic.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from smarticle_common.cli import seeds_argument

from .assignments import parse_assignments
from .errors import ExperimentError, SpecError
from .harness import RunOptions, positive_float, run_mapping
from .store import DEFAULT_ROOT, ResultStore

if TYPE_CHECKING:
    from .physics_study import StudyRow


@dataclass(frozen=True)
class StudyCommand:
    """A subcommand: its name, one-line help, whether it runs trials on the engine, its options and its run."""

    name: str
    help: str
    runs_trials: bool
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


def _assignments(items: list[str]) -> dict[str, object]:
    """``--set NAME=VALUE`` items as a mapping (SpecError naming a malformed one)."""
    try:
        return parse_assignments(items)
    except ValueError as err:
        raise SpecError(f'--set {err}') from None


# ------------------------------------------------------------------ p6


def p6_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``p6``."""
    from .p6 import START_NAMES

    parser.add_argument('--seeds', type=seeds_argument, default=list(range(40)), metavar='SEEDS',
                        help='seeds of every condition (default 0..39)')
    parser.add_argument('--periods', type=positive_float, default=200.0, help='gait periods per trial')
    parser.add_argument('--open-loop', type=float, nargs='*', default=[70.0, 80.0, 85.0, 90.0],
                        help='open-loop amplitudes (deg); none after the flag: no open-loop condition')
    parser.add_argument('--feedback', type=float, nargs='*', default=[90.0],
                        help='feedback amplitudes (deg); none after the flag: no feedback condition')
    parser.add_argument('--contacts', action='store_true',
                        help="also each pair's travel while bound and the periods in which the robots touch "
                             '(a step hook per trial; the trajectory is the same)')
    parser.add_argument('--start', choices=sorted(START_NAMES), default='harvested',
                        help='harvested: where the C2 gliders of dense runs live (default); held: the full state of '
                             'a C2 glider held by collisions in a dense run (seeded pick of the shipped starts); '
                             'colliding: robot 2 a quarter period ahead, colliding from the first period')
    parser.add_argument('--noise', choices=['paper', 'none'], default='paper',
                        help='noise with a cause: paper (the cited defaults, default) or none')
    parser.add_argument('--windows', default=None,
                        help='YAML file of impact windows for the feedback conditions (a parameter file such as '
                             "config/feedback.yaml, or the 'feedback parameters' of smarticle-feedback-calibrate); "
                             'default: the shipped windows')
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='replace a PhysicsConfig field for every trial (repeatable), e.g. restitution=0.5')
    parser.add_argument('--quick', action='store_true', help='seeds 0..2, 30 periods, open loop 90 vs feedback 90')
    parser.add_argument('--engine', choices=('bullet', 'mujoco'), default='bullet',
                        help='the engine of the trials (default bullet); in MuJoCo the run is p6_run-mujoco')


def p6_run(args: argparse.Namespace) -> int:
    """Run P6's conditions x seeds into the store (``p6_runs``) and print its report."""
    from .p6 import window_values
    from .report import write_report

    if args.quick:
        args.seeds, args.periods, args.open_loop, args.feedback = [0, 1, 2], 30.0, [90.0], [90.0]
    windows: dict[str, object] = {}
    if args.windows is not None:
        try:
            windows = window_values(args.windows)
        except (OSError, ValueError) as err:   # ParameterError is a ValueError
            raise SpecError(f'--windows: {err}') from None
    grid = ([{'alpha_max_deg': list(args.open_loop), 'feedback': [False]}] if args.open_loop else []) + \
        ([{'alpha_max_deg': list(args.feedback), 'feedback': [True]}] if args.feedback else [])
    if not grid:
        raise SpecError('no condition to run: give --open-loop or --feedback amplitudes')
    data = {'name': 'p6_run' if args.engine == 'bullet' else f'p6_run-{args.engine}',
            'description': 'C2 lifetimes, open loop against feedback', 'tags': ['paper'],
            'kind': 'p6', 'engine': args.engine, 'store': 'p6_runs', 'periods': args.periods, 'noise': args.noise,
            'physics': _assignments(args.set),
            'params': {'start': args.start, 'windows': windows, 'details': bool(args.contacts)},
            'grid': grid, 'report': ['p6']}
    spec, trials, store, code = run_mapping(data, args.seeds, RunOptions.from_args(args), args.command)
    path = write_report(spec, trials, store, code)
    sys.stdout.write(path.read_text() + f'\nreport: {path}\n')
    return 0


# ------------------------------------------------------------------ c2-harvest


def c2_harvest_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``c2-harvest``."""
    parser.add_argument('--seeds', type=seeds_argument, default=list(range(5000, 5020)), metavar='SEEDS',
                        help='seeds of the dense trials (default 5000..5019)')
    parser.add_argument('--periods', type=positive_float, default=150.0, help='gait periods per trial')
    parser.add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    parser.add_argument('--preset', default='feedback', help='robot preset (default feedback)')


def c2_harvest_run(args: argparse.Namespace) -> int:
    """Run the dense trials into the store (``c2_harvest``); write the samples, held starts and histogram."""
    from .c2_harvest import (HELD_EVERY, HELD_SHARE, format_summary, held_starts, plot, sample_from_record,
                             summary, write_csv)

    data = {'name': 'c2_harvest', 'description': "where the feedback robot's C2 gliders sit in dense runs",
            'tags': ['calibration'], 'kind': 'c2_harvest', 'store': 'c2_harvest', 'periods': args.periods,
            'preset': args.preset, 'params': {'alpha_max_deg': args.alpha}}
    spec, trials, store, _ = run_mapping(data, args.seeds, RunOptions.from_args(args), args.command)
    records = store.records(t.key for t in trials)
    samples = [sample_from_record(s) for r in records if r.get('status') == 'ok' for s in r['result']['samples']]
    if not samples:
        raise ExperimentError('no C2 samples: no C2 glider of the minimum length formed in these trials')
    touched = [x for x in samples if x.touched]
    print(format_summary(summary(samples), summary(touched) if touched else None))
    out = store.folder / f'report-{spec.name}'
    held = held_starts(samples)
    print(f'\n{len(held)} starts of {len({(x.seed, x.i, x.j) for x in held})} C2 gliders held by collisions '
          f'(touched in >= {HELD_SHARE:.0%} of their periods; every {HELD_EVERY}th period with contact): '
          f'{write_csv(held, out / "c2_held_starts.csv")}')
    print(f'wrote {write_csv(samples, out / "c2_samples.csv")} and {plot(samples, out / "c2_harvest.png")}')
    return 0


# ------------------------------------------------------------------ c2-collisions


def c2_collisions_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``c2-collisions``."""
    from .p6 import START_NAMES

    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--periods', type=positive_float, default=40.0)
    parser.add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    parser.add_argument('--rows', type=int, default=24, help='events shown in the table on stdout')
    parser.add_argument('--start', choices=sorted(START_NAMES), default='harvested',
                        help='the P6 start (default harvested; held: the state of a C2 held by collisions; '
                             'colliding: robot 2 a quarter period ahead)')
    parser.add_argument('--noise', choices=['paper', 'none'], default='paper',
                        help='noise with a cause, as in P6 (default paper)')
    parser.add_argument('--out', type=Path, default=Path('out/feedback/c2'), help='output folder')


def c2_collisions_run(args: argparse.Namespace) -> int:
    """Record one C2 pair at every physics step: event table and signature on stdout; CSV, PNG, npz in --out."""
    from smarticle_feedback.collisions import (find_events, format_events, format_signature, plot_events,
                                               signature, write_events_csv)

    from .c2_collisions import record_pair
    from .p6 import p6_noise, start_base

    rec = record_pair(args.seed, args.periods, args.alpha, base=start_base(args.start), noise=p6_noise(args.noise))
    rec.save(args.out / 'c2_steps.npz')
    events = find_events(rec)
    write_events_csv(events, args.out / 'c2_events.csv')
    first = math.floor((events[0].t_peak - rec.start_time) / rec.period) if events else 0   # plot from the first
    plot_events(rec, events, args.out / 'c2_events.png', (float(first), float(min(first + 4, args.periods))))
    sys.stdout.write(format_events(events, limit=args.rows) + '\n\n' + format_signature(signature(events)) + '\n')
    sys.stdout.write(f'\n{len(events)} events in {args.periods:g} periods (seed {args.seed}); files in {args.out}/\n')
    return 0


# ------------------------------------------------------------------ physics-study

#: The physics study's experiments: their store (``physics_<name>``) and their table.
STUDY_EXPERIMENTS: tuple[str, ...] = ('mechanism', 'drift', 'pair', 'basin', 'dense', 'impact')


def _study_common(p: argparse.ArgumentParser, periods: float | None) -> None:
    """Options every physics-study experiment takes."""
    p.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                   help='a PhysicsConfig / RobotSpec field, gait_speed or x_ knob on top of the shipped defaults '
                        '(repeatable)')
    p.add_argument('--label', default=None, help='the setting\'s name in the tables (default: the --set items)')
    if periods is not None:
        p.add_argument('--periods', type=positive_float, default=periods, help='gait periods per trial')


def physics_study_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``physics-study`` (one sub-command per experiment, and ``tables``)."""
    from .harness import add_engine_arguments

    sub = parser.add_subparsers(dest='experiment', required=True)
    p = sub.add_parser('mechanism', help='collision impulses of P4-style pair starts (quadrants, normals)')
    _study_common(p, 20.0)
    p.add_argument('--phase2', type=float, nargs='*', default=[0.0], help='gait phase of both robots')
    p = sub.add_parser('drift', help='a lone robot\'s drift per cycle against the time step')
    _study_common(p, 20.0)
    p.add_argument('--dt', type=int, nargs='*', default=[], help='physics rates (Hz; default: the shipped step)')
    p.add_argument('--headings', type=float, nargs='*', default=[90.0])
    p.add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    p = sub.add_parser('pair', help='pairs from given starts against the time step')
    _study_common(p, 100.0)
    p.add_argument('--dt', type=int, nargs='*', default=[], help='physics rates (Hz; default: the shipped step)')
    p.add_argument('--starts', type=lambda t: [float(x) for x in t.split(',')], nargs='*',
                   default=[[330.0, 180.0]], help='THETA,PHI (deg) starts')
    p.add_argument('--phase2', type=float, nargs='*', default=[0.05])
    p = sub.add_parser('basin', help='a (theta, phi) grid of pair starts at r = 1.3 BL: bound at the end?')
    _study_common(p, 75.0)
    p.add_argument('--step', type=float, default=30.0, help='grid step (deg)')
    p.add_argument('--phase', type=float, nargs='*', default=[0.0, 0.25], help='gait phase of both robots')
    p = sub.add_parser('dense', help='dense stability: trouble stops, overlap, gliders')
    _study_common(p, 300.0)
    p.add_argument('--seeds', type=seeds_argument, default=list(range(10)), metavar='SEEDS',
                   help='seeds (default 0..9)')
    p.add_argument('--robots', type=int, default=7)
    p.add_argument('--jitter', type=float, default=0.0, help='gait phase offsets within +- this (periods)')
    p = sub.add_parser('impact', help='effective restitution of head-on impacts of two bodies')
    _study_common(p, None)
    p.add_argument('--pairs', nargs='*', default=['0.6:0.85', '0.2:0.76', '0.1:0.8', '0.6:0'],
                   help='contact ERP:restitution pairs')
    p.add_argument('--dt', type=int, nargs='*', default=[960, 480, 1920], help='physics rates (Hz)')
    p.add_argument('--speeds', type=float, nargs='*', default=[0.3, 0.1, 0.6], help='approach speeds (m/s)')
    p.add_argument('--phases', type=int, default=16, help='meeting points per step')
    for name in STUDY_EXPERIMENTS:
        add_engine_arguments(sub.choices[name])
    p = sub.add_parser('tables', help='the tables of every stored physics-study experiment')
    p.add_argument('--out', type=Path, default=DEFAULT_ROOT, help=f'store root (default {DEFAULT_ROOT})')


def _study_settings(args: argparse.Namespace) -> tuple[dict[str, object], str]:
    """The --set items as settings and the label of the tables."""
    return _assignments(args.set), args.label or (' '.join(args.set) or 'shipped')


def study_rows(store: ResultStore, keys: list[str] | None = None) -> list[StudyRow[Any]]:
    """The stored rows of a physics-study store: each trial's parameters, seed, physics rate and typed result."""
    from .kinds.study import study_row

    return [study_row(r) for r in store.records(keys) if r.get('status') == 'ok']


def study_table(name: str, rows: list[StudyRow[Any]]) -> str:
    """The table of one physics-study experiment."""
    from . import physics_study as ps

    table = {'mechanism': ps.mechanism_table, 'drift': ps.drift_table, 'pair': ps.pair_table,
             'basin': ps.basin_table, 'dense': ps.dense_lines, 'impact': ps.impact_table}[name]
    return '\n'.join(table(rows))


def physics_study_run(args: argparse.Namespace) -> int:
    """Run one experiment of the physics study into the store (``physics_<experiment>``) and print its table."""
    from .physics_study import MECH_STARTS

    if args.experiment == 'tables':
        for name in STUDY_EXPERIMENTS:
            rows = study_rows(ResultStore(args.out / f'physics_{name}'))
            if rows:
                print(f'## {name}\n\n{study_table(name, rows)}\n')
        return 0
    settings, label = _study_settings(args)
    rates = [{**settings, 'time_step': 1.0 / n} for n in getattr(args, 'dt', [])] or [settings]
    seeds: list[int] = [0]
    data: dict[str, object] = {'name': f'physics_{args.experiment}', 'store': f'physics_{args.experiment}',
                               'description': f'physics study: {args.experiment}', 'tags': ['diagnostic']}
    if getattr(args, 'periods', None) is not None:
        data['periods'] = args.periods
    if args.experiment == 'mechanism':
        data.update(kind='study_collision', params={'label': label, 'settings': settings},
                    grid=[{'phase': args.phase2, 'theta_deg': [float(t)], 'phi_deg': [float(f)]}
                          for t, f in MECH_STARTS])
    elif args.experiment == 'drift':
        data.update(kind='study_drift', params={'label': label, 'alpha_max_deg': args.alpha},
                    grid={'settings': rates, 'heading_deg': args.headings})
    elif args.experiment == 'pair':
        data.update(kind='study_pair', params={'label': label},
                    grid=[{'settings': rates, 'theta_deg': [t], 'phi_deg': [f], 'phase2': args.phase2}
                          for t, f in args.starts])
    elif args.experiment == 'basin':
        angles = [float(a) for a in np.arange(0.0, 360.0, args.step)]
        data.update(kind='study_pair', params={'label': label, 'settings': settings, 'r_bl': 1.3},
                    grid=[{'phase1': [p], 'phase2': [p], 'theta_deg': angles, 'phi_deg': angles} for p in args.phase])
    elif args.experiment == 'dense':
        seeds = list(args.seeds)
        data.update(kind='study_dense', params={'label': label, 'settings': settings, 'robots': args.robots,
                                                'jitter': args.jitter})
    else:   # impact
        blocks = []
        for pair in args.pairs:
            erp, _, e = pair.partition(':')
            blocks.append({'settings': [{**settings, 'contact_erp': float(erp), 'restitution': float(e),
                                         'time_step': 1.0 / n} for n in args.dt], 'speed_m_s': args.speeds})
        data.update(kind='study_impact', params={'label': label, 'phases': args.phases}, grid=blocks)
    _, trials, store, _ = run_mapping(data, seeds, RunOptions.from_args(args), args.command)
    print(study_table(args.experiment, study_rows(store, [t.key for t in trials])))
    return 0


STUDY_COMMANDS: tuple[StudyCommand, ...] = (
    StudyCommand('p6', 'P6: C2 pairs of the feedback robot, open loop against impact-halt feedback', True,
                 p6_arguments, p6_run),
    StudyCommand('c2-harvest', "where the feedback robot's C2 gliders sit: dense open-loop runs, every C2 glider "
                 'sampled at its period boundaries', True, c2_harvest_arguments, c2_harvest_run),
    StudyCommand('c2-collisions', 'every contact event of one C2 pair, recorded at every physics step', False,
                 c2_collisions_arguments, c2_collisions_run),
    StudyCommand('physics-study', "the physics study's measurements (collisions, drift, pairs, basin, dense "
                 'stability, impacts) on the engine, and their tables', False, physics_study_arguments,
                 physics_study_run),
)
