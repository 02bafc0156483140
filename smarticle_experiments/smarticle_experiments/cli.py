"""``smarticle-experiments``: list, run, report and check the paper's experiments (no ROS).

    smarticle-experiments list [-v]
    smarticle-experiments run p1 --trials 151                    # embedded LocalCluster, one worker per core
    smarticle-experiments run p1 --scheduler tcp://HOST:8786     # an existing Dask cluster
    smarticle-experiments run my_spec.yaml --periods 5 --trials 3
    smarticle-experiments report p1
    smarticle-experiments status p1

Bad input (unknown spec key, zero or negative count, empty grid, a scheduler that does not answer) prints
one line naming the cause and exits with code 2, writing nothing.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

import yaml
from smarticle_sim.settings import NotConvergedWarning

from .errors import ExperimentError, SchedulerError, SpecError
from .spec import ExperimentSpec, builtin_names, load_spec, parse_seed_ranges
from .store import DEFAULT_ROOT, ResultStore, code_version
from .trials import KINDS

PROG = 'smarticle-experiments'


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error and exit code 2."""

    def error(self, message: str) -> NoReturn:
        """Print ``prog: error: message`` on one line and exit 2."""
        sys.stderr.write(f'{PROG}: error: {message}\n')
        raise SystemExit(2)


def _positive_int(text: str) -> int:
    """An integer >= 1 (argparse type)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a whole number') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be >= 1, got {value}')
    return value


def _positive_float(text: str) -> float:
    """A finite number > 0 (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (value > 0 and value != float('inf')):
        raise argparse.ArgumentTypeError(f'must be > 0, got {text}')
    return value


def _seed_ranges(text: str) -> tuple[int, ...]:
    """argparse type: ``1000-1029`` or ``1,5,10-12``."""
    try:
        return parse_seed_ranges(text)
    except SpecError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def build_parser() -> argparse.ArgumentParser:
    """The argument parser."""
    parser = _Parser(prog=PROG, description=(__doc__ or '').split('\n')[0])
    sub = parser.add_subparsers(dest='command', required=True, parser_class=_Parser)
    lister = sub.add_parser('list', help='the shipped experiment specs')
    lister.add_argument('-v', '--verbose', action='store_true', help='also the trial kinds and their parameters')
    for name, text in (('run', 'run the trials the store does not hold yet'),
                       ('report', 'write report.md and PNG figures from the stored trials'),
                       ('status', 'count done, failed and missing trials')):
        p = sub.add_parser(name, help=text)
        p.add_argument('spec', help='a shipped spec name (see list) or a YAML file')
        p.add_argument('--trials', type=_positive_int, default=None,
                       help='seeds 0..N-1 per grid point instead of the spec\'s seeds')
        p.add_argument('--seeds', type=_seed_ranges, default=None, metavar='A-B[,C,...]',
                       help='only these seeds (e.g. 1000-1029), in the same store; the report is '
                            'report-<name>-seeds-<ranges>')
        p.add_argument('--periods', type=_positive_float, default=None, help='gait periods per trial')
        p.add_argument('--out', type=Path, default=DEFAULT_ROOT, help=f'store root (default {DEFAULT_ROOT})')
    run = sub.choices['run']
    run.add_argument('--scheduler', default=None, help='address of an existing Dask scheduler (tcp://HOST:8786)')
    run.add_argument('--workers', type=_positive_int, default=None,
                     help='LocalCluster worker processes (default: one per core)')
    run.add_argument('--retries', type=int, default=2, help='Dask retries of a task whose machinery failed')
    run.add_argument('--retry-failed', action='store_true', help='also rerun trials that raised before')
    run.add_argument('--no-progress', action='store_true', help='no progress bar')
    run.add_argument('--report', action='store_true', help='write the report after the run')
    return parser


def resolve(args: argparse.Namespace) -> ExperimentSpec:
    """The spec named on the command line with --trials / --periods applied."""
    spec = load_spec(args.spec)
    if args.trials is not None and args.seeds is not None:
        raise SpecError('--trials and --seeds both choose the seeds: give one')
    if args.trials is not None:
        spec = spec.with_seed_count(args.trials)
    if args.seeds is not None:
        spec = spec.with_seeds(args.seeds)
    if args.periods is not None:
        spec = spec.with_periods(args.periods)
    return spec


def summary_name(spec: ExperimentSpec) -> str:
    """``summary`` for the spec that owns its store, ``summary-<name>`` for one that shares another's."""
    return 'summary' if spec.store == spec.name else f'summary-{spec.name}'


def cmd_list(args: argparse.Namespace) -> int:
    """Print the shipped specs (and with -v the kinds)."""
    names = builtin_names()
    width = max(len(name) for name in names)
    for name in names:
        try:
            with warnings.catch_warnings(record=True) as caught:   # noted on the spec's line, not as a traceback
                warnings.simplefilter('always', NotConvergedWarning)
                spec = load_spec(name)
            note = '  (a grid point is coarser than converges: NotConvergedWarning)' if any(
                issubclass(w.category, NotConvergedWarning) for w in caught) else ''
            print(f'{name:{width}s} {spec.kind:9s} {len(spec.points()) * len(spec.seeds):6d} trials  '
                  f'{spec.description}{note}')
        except SpecError as exc:
            print(f'{name:{width}s} INVALID: {exc}')
    if args.verbose:
        print('\ntrial kinds (parameters and defaults):')
        for kind, info in KINDS.items():
            print(f'  {kind}: {info.description}')
            print('    ' + ', '.join(f'{k}={v!r}' for k, v in info.defaults.items()))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    """Run a spec's missing trials and write the summary (and report)."""
    from .engine import dask_client, run_trials
    from .report import write_report

    spec = resolve(args)
    code = code_version()
    trials = spec.trials(code)
    store = ResultStore(args.out / spec.store)
    if not {t.key for t in trials} - store.done(args.retry_failed):
        summary = store.write_summary(store.records(t.key for t in trials), summary_name(spec))
        print(f'{spec.name}: {len(trials)} trials: {len(trials)} already stored, 0 done now; summary {summary}')
        if args.report:
            print(f'report: {write_report(spec, trials, store, code)}')
        return 0
    with dask_client(args.scheduler, args.workers) as client:   # connect before writing anything
        store.folder.mkdir(parents=True, exist_ok=True)
        (store.folder / f'spec-{spec.name}.yaml').write_text(yaml.safe_dump(
            {'name': spec.name, 'kind': spec.kind, 'source': spec.source, 'base': dict(spec.base),
             'grid': [dict(b) for b in spec.grid], 'seeds': list(spec.seeds), 'code': code}, sort_keys=False))
        workers = len(client.nthreads())
        sys.stderr.write(f'{spec.name}: {len(trials)} trials, store {store.folder}, {workers} workers\n')
        try:
            stats = run_trials(trials, store, client, code, retries=args.retries, retry_failed=args.retry_failed,
                               progress=not args.no_progress)
        finally:   # also when interrupted: the summary of what is stored so far
            summary = store.write_summary(store.records(t.key for t in trials), summary_name(spec))
    print(f'{spec.name}: {stats.total} trials: {stats.skipped} already stored, {stats.ok} done now, '
          f'{stats.failed} failed, {stats.lost} lost by the engine ({stats.wall_s:.1f} s, {stats.workers} workers); '
          f'summary {summary}')
    if args.report:
        print(f'report: {write_report(spec, trials, store, code)}')
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    """Write the report of a spec from its stored trials."""
    from .report import write_report

    spec = resolve(args)
    code = code_version()
    store = ResultStore(args.out / spec.store)
    trials = spec.trials(code)
    if not store.keys() & {t.key for t in trials}:
        raise SpecError(f'{spec.name}: no stored trials of this spec and code version in {store.folder}; run it first')
    print(write_report(spec, trials, store, code))
    return 0


def cmd_status(args: argparse.Namespace) -> int:
    """Print counts of the spec's trials: done, failed (trial / engine), in trouble, missing."""
    spec = resolve(args)
    code = code_version()
    store = ResultStore(args.out / spec.store)
    trials = spec.trials(code)
    keys = store.keys()
    records = store.records(t.key for t in trials if t.key in keys)
    ok = [r for r in records if r.get('status') == 'ok']
    trouble = sum(bool((r.get('result') or {}).get('trouble')) for r in ok)
    failed = sum(r.get('error_kind') == 'trial' for r in records if r.get('status') != 'ok')
    lost = sum(r.get('error_kind') == 'engine' for r in records if r.get('status') != 'ok')
    stale = len(keys - {t.key for t in trials})
    wall = sum(float(r.get('wall_s', 0.0)) for r in ok)
    print(f'{spec.name}: {len(trials)} trials: {len(ok)} done ({trouble} ended in sim trouble), {failed} failed, '
          f'{lost} lost by the engine, {len(trials) - len(records)} missing; {stale} other records in '
          f'{store.folder} (other specs or code versions); mean trial {wall / max(len(ok), 1):.1f} s')
    return 0


COMMANDS = {'list': cmd_list, 'run': cmd_run, 'report': cmd_report, 'status': cmd_status}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; bad input exits 2 with one line on stderr."""
    args = build_parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except (SpecError, SchedulerError) as exc:
        sys.stderr.write(f'{PROG}: error: {exc}\n')
        return 2
    except ExperimentError as exc:
        sys.stderr.write(f'{PROG}: error: {exc}\n')
        return 1
    except KeyboardInterrupt:
        sys.stderr.write(f'{PROG}: interrupted; finished trials are stored, run again to resume\n')
        return 130


if __name__ == '__main__':
    sys.exit(main())
