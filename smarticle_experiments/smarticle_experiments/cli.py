"""``smarticle-experiments``: list, run, report and check the paper's experiments and studies (no ROS).

    smarticle-experiments list [--all] [-v]                      # each spec's trials and run time on 2 cores
    smarticle-experiments run p1 --trials 151                    # embedded LocalCluster, one worker per core
    smarticle-experiments run p1 --scheduler tcp://HOST:8786     # an existing Dask cluster
    smarticle-experiments run my_spec.yaml --periods 5 --seeds 0..2
    smarticle-experiments run p7 --engine mujoco --report        # any simulated kind in MuJoCo too
    smarticle-experiments report p1
    smarticle-experiments report --summary                       # the status table of the paper's claims
    smarticle-experiments status p1
    smarticle-experiments p6 --seeds 0..39                       # P6 open loop against feedback
    smarticle-experiments c2-harvest --seeds 5000..5019          # where the feedback robot's C2 gliders sit
    smarticle-experiments c2-collisions --seed 1                 # every contact event of one C2 pair
    smarticle-experiments physics-study drift --dt 240 480       # the physics study's measurements

Every command that runs trials runs them as trial kinds on the one Dask engine (``--workers``,
``--scheduler``) into the one store (``--out``). ``--trials N`` is N trials in all (a multiple of the spec's
grid points); ``--seeds`` the seeds of every grid point; ``--engine`` the engine of its trials (the spec's
``engine``, default bullet). A shipped spec is found whatever its case. Bad input (unknown spec key or name,
zero or negative count, empty grid, a kind that does not run in the engine, a scheduler that does not answer)
prints one line naming the cause (for a name, the closest shipped ones) and exits with code 2, writing nothing.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from smarticle_common.cli import add_version, closed_pipe_safe, seeds_argument
from smarticle_sim.settings import NotConvergedWarning

from .errors import ExperimentError, SchedulerError, SpecError
from .harness import PROG, RunOptions, add_engine_arguments, positive_float, positive_int, run_spec
from .spec import STATUSES, TAGS, ExperimentSpec, archive_names, builtin_names, load_spec
from .kind import ENGINES
from .kinds import KINDS
from .store import DEFAULT_ROOT, ResultStore



class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error and exit code 2."""

    def error(self, message: str) -> NoReturn:
        """Print ``prog: error: message`` on one line and exit 2."""
        sys.stderr.write(f'{PROG}: error: {message}\n')
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser."""
    from .commands import STUDY_COMMANDS

    parser = _Parser(prog=PROG, description=(__doc__ or '').split('\n')[0])
    add_version(parser, 'smarticle_experiments')
    sub = parser.add_subparsers(dest='command', required=True, parser_class=_Parser)
    lister = sub.add_parser('list', help='the shipped experiment specs, current ones by tag')
    lister.add_argument('--all', action='store_true',
                        help='also the superseded specs (and, in a source tree, the archived ones)')
    lister.add_argument('-v', '--verbose', action='store_true', help='also the trial kinds and their parameters')
    for name, text in (('run', 'run the trials the store does not hold yet'),
                       ('report', 'write report.md and PNG figures from the stored trials'),
                       ('status', 'count done, failed and missing trials')):
        p = sub.add_parser(name, help=text)
        p.add_argument('spec', nargs='?' if name == 'report' else None,
                       help='a shipped spec name (see list; any case) or a YAML file')
        p.add_argument('--trials', type=positive_int, default=None, metavar='N',
                       help='N trials in all instead of the spec\'s: seeds 0..N/G-1 at each of its G grid points '
                            '(N a multiple of G; list shows each spec\'s trials)')
        p.add_argument('--seeds', type=seeds_argument, default=None, metavar='SEEDS',
                       help='only these seeds at every grid point (7, 1000..1029 or 1,5,10..12), in the same '
                            'store; the report is report-<name>-seeds-<ranges>')
        p.add_argument('--periods', type=positive_float, default=None, help='gait periods per trial')
        p.add_argument('--engine', choices=ENGINES, default=None,
                       help="the engine of the trials instead of the spec's (default: its engine field, else its "
                            "kind's first, bullet); in another engine the spec is named <name>-<engine>, same store")
        if name == 'run':
            add_engine_arguments(p)
            p.add_argument('--report', action='store_true', help='write the report after the run')
        else:
            p.add_argument('--out', type=Path, default=DEFAULT_ROOT, help=f'store root (default {DEFAULT_ROOT})')
    sub.choices['report'].add_argument(
        '--summary', action='store_true',
        help='print the status table of the paper\'s claims (one line each) from the stored current paper specs')
    for command in STUDY_COMMANDS:
        p = sub.add_parser(command.name, help=command.help, description=command.help)
        command.add_arguments(p)
        if command.runs_trials:
            add_engine_arguments(p)
        p.set_defaults(study=command)
    return parser


def resolve(args: argparse.Namespace) -> ExperimentSpec:
    """The spec named on the command line with --trials / --seeds / --periods applied."""
    spec = load_spec(args.spec, args.engine)
    if args.trials is not None and args.seeds is not None:
        raise SpecError('--trials and --seeds both choose the seeds: give one')
    if args.trials is not None:
        spec = spec.with_trial_count(args.trials)
    if args.seeds is not None:
        spec = spec.with_seeds(args.seeds)
    if args.periods is not None:
        spec = spec.with_periods(args.periods)
    return spec


def _list_line(name: str, width: int, path: str | None = None) -> str:
    """One spec's line: name, kind, trial count, run time on 2 cores, description (or why it is invalid)."""
    from .estimate import duration_text, run_seconds

    try:
        with warnings.catch_warnings(record=True) as caught:   # noted on the spec's line, not as a traceback
            warnings.simplefilter('always', NotConvergedWarning)
            spec = load_spec(path or name)
        note = '  (a grid point is coarser than converges: NotConvergedWarning)' if any(
            issubclass(w.category, NotConvergedWarning) for w in caught) else ''
        return (f'{name:{width}s} {spec.kind:13s} {len(spec.points()) * len(spec.seeds):6d} trials '
                f'{duration_text(run_seconds(spec)):>9s}  {spec.description}{note}')
    except SpecError as exc:
        return f'{name:{width}s} INVALID: {exc}'


def cmd_list(args: argparse.Namespace) -> int:
    """Print the current shipped specs grouped by tag (with --all the superseded and archived ones too)."""
    from .estimate import REFERENCE_CORES

    names = builtin_names()
    width = max(len(name) for name in names)
    print(f'# name, trial kind, trials, run time on {REFERENCE_CORES} idle cores by the cost model of '
          f'docs/experiments.md ("Run time estimates"), description')
    specs: dict[str, ExperimentSpec | None] = {}
    for name in names:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter('ignore', NotConvergedWarning)
                specs[name] = load_spec(name)
        except SpecError:
            specs[name] = None
    for tag in (*TAGS, ''):
        chosen = [n for n, s in specs.items() if s is not None and s.status == 'current'
                  and (tag in s.tags if tag else not s.tags)]
        if chosen:
            print(f'# {tag or "untagged"}')
            for name in chosen:
                print(_list_line(name, width))
    invalid = [n for n, s in specs.items() if s is None]
    for name in invalid:
        print(_list_line(name, width))
    if args.all:
        for status in STATUSES[1:]:
            chosen = [n for n, s in specs.items() if s is not None and s.status == status]
            if chosen:
                print(f'# {status}')
                for name in chosen:
                    print(_list_line(name, width))
        archived = archive_names()
        if archived:
            print('# archived (not installed; each runs from the commit named in archive/README.md)')
            for name in archived:
                print(f'{name:{width}s}')
    if args.verbose:
        print('\ntrial kinds (parameters and defaults):')
        for kind, info in KINDS.items():
            print(f'  {kind}: {info.description}')
            print('    ' + ', '.join(f'{k}={v!r}' for k, v in info.defaults.items()))
    return 0


def run_plan(spec: ExperimentSpec, args: argparse.Namespace) -> str:
    """What ``run`` is about to do, one line: the spec's trials, how many the store lacks, and how long they take
    on this run's cores (or on 2 cores for a remote cluster) by the cost model of ``estimate``."""
    import os

    from .estimate import REFERENCE_CORES, duration_text, run_seconds

    total = len(spec.points()) * len(spec.seeds)
    done = ResultStore(args.out / spec.store).done(args.retry_failed)
    todo = total - len({t.key for t in spec.trials(spec.code())} & done)
    cores = REFERENCE_CORES if args.scheduler else (args.workers or os.cpu_count() or 1)
    where = f'{cores} {"core" if cores == 1 else "cores"}' + (
        f' (a cluster of N cores: {cores}/N of that)' if args.scheduler else '')
    return (f'{spec.name}: {total} trials ({len(spec.points())} grid points x {len(spec.seeds)} seeds) in '
            f'{spec.engine}, '
            f'{todo} to run: about {duration_text(run_seconds(spec, cores, todo))} on {where} by the cost model '
            f'of docs/experiments.md')


def cmd_run(args: argparse.Namespace) -> int:
    """Run a spec's missing trials and write the summary (and report)."""
    from .report import write_report

    spec = resolve(args)
    print(run_plan(spec, args), flush=True)
    trials, store, code = run_spec(spec, RunOptions.from_args(args))
    if args.report:
        print(f'report: {write_report(spec, trials, store, code)}')
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    """Write the report of a spec from its stored trials (or, with --summary, print the claims' status table)."""
    from .report import status_table, write_report

    if args.summary:
        if args.spec is not None:
            raise SpecError('report --summary reads every current paper spec: give no spec')
        print(status_table(args.out))
        return 0
    if args.spec is None:
        raise SpecError('report: name a spec (or give --summary)')
    spec = resolve(args)
    code = spec.code()
    store = ResultStore(args.out / spec.store)
    trials = spec.trials(code)
    if not store.keys() & {t.key for t in trials}:
        raise SpecError(f'{spec.name}: no stored trials of this spec and code version in {store.folder}; run it first')
    print(write_report(spec, trials, store, code))
    return 0


def cmd_status(args: argparse.Namespace) -> int:
    """Print counts of the spec's trials: done, failed (trial / engine), in trouble, missing."""
    spec = resolve(args)
    code = spec.code()
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


@closed_pipe_safe
def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; bad input exits 2 with one line on stderr."""
    args = build_parser().parse_args(argv)
    try:
        if args.command in COMMANDS:
            return COMMANDS[args.command](args)
        return int(args.study.run(args))
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
