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

from smarticle_common.cli import seeds_argument

from .assignments import parse_assignments
from .errors import ExperimentError, SpecError
from .harness import positive_float, run_mapping


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
    data = {'name': 'p6_run', 'description': 'C2 lifetimes, open loop against feedback', 'tags': ['paper'],
            'kind': 'p6', 'store': 'p6_runs', 'periods': args.periods, 'noise': args.noise,
            'physics': _assignments(args.set),
            'params': {'start': args.start, 'windows': windows, 'details': bool(args.contacts)},
            'grid': grid, 'report': ['p6']}
    spec, trials, store, code = run_mapping(data, args.seeds, args)
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
    spec, trials, store, _ = run_mapping(data, args.seeds, args)
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


STUDY_COMMANDS: tuple[StudyCommand, ...] = (
    StudyCommand('p6', 'P6: C2 pairs of the feedback robot, open loop against impact-halt feedback', True,
                 p6_arguments, p6_run),
    StudyCommand('c2-harvest', "where the feedback robot's C2 gliders sit: dense open-loop runs, every C2 glider "
                 'sampled at its period boundaries', True, c2_harvest_arguments, c2_harvest_run),
    StudyCommand('c2-collisions', 'every contact event of one C2 pair, recorded at every physics step', False,
                 c2_collisions_arguments, c2_collisions_run),
)
