"""The one way trials run: a spec's trials on the Dask engine into the store, for every command.

``run_spec`` is what ``smarticle-experiments run`` does; the study commands (``p6``, ``c2-harvest``,
``physics-study``) build their spec as a mapping and go through ``run_mapping``, so every trial of every
study is a trial kind run by the one engine into the one store.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from .spec import ExperimentSpec, Trial, spec_from_mapping
from .store import DEFAULT_ROOT, ResultStore

PROG = 'smarticle-experiments'


def positive_int(text: str) -> int:
    """An integer >= 1 (argparse type)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a whole number') from None
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be >= 1, got {value}')
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not (value > 0 and value != float('inf')):
        raise argparse.ArgumentTypeError(f'must be > 0, got {text}')
    return value


def add_engine_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of every command that runs trials: the engine and the store."""
    parser.add_argument('--out', type=Path, default=DEFAULT_ROOT, help=f'store root (default {DEFAULT_ROOT})')
    parser.add_argument('--scheduler', default=None, help='address of an existing Dask scheduler (tcp://HOST:8786)')
    parser.add_argument('--workers', type=positive_int, default=None,
                        help='LocalCluster worker processes (default: one per core)')
    parser.add_argument('--retries', type=int, default=2, help='Dask retries of a task whose machinery failed')
    parser.add_argument('--retry-failed', action='store_true', help='also rerun trials that raised before')
    parser.add_argument('--no-progress', action='store_true', help='no progress bar')


@dataclass(frozen=True)
class RunOptions:
    """How a run runs: the store root, the engine (an existing scheduler or a LocalCluster of ``workers``),
    retries, whether failed trials run again, the progress bar."""

    out: Path = DEFAULT_ROOT
    scheduler: str | None = None
    workers: int | None = None
    retries: int = 2
    retry_failed: bool = False
    progress: bool = True

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> RunOptions:
        """The options of a command line parsed with ``add_engine_arguments``."""
        return cls(out=Path(args.out), scheduler=args.scheduler, workers=args.workers, retries=args.retries,
                   retry_failed=bool(args.retry_failed), progress=not args.no_progress)


def summary_name(spec: ExperimentSpec) -> str:
    """``summary`` for the spec that owns its store, ``summary-<name>`` for one that shares another's."""
    return 'summary' if spec.store == spec.name else f'summary-{spec.name}'


def run_spec(spec: ExperimentSpec, options: RunOptions) -> tuple[list[Trial], ResultStore, dict[str, str]]:
    """Run a spec's missing trials on the engine of ``options`` and write the summary; print the run's line."""
    from .engine import dask_client, run_trials
    from .kinds import engine_missing

    code = spec.code()
    trials = spec.trials(code)
    store = ResultStore(options.out / spec.store)
    missing = engine_missing(spec.kind)   # checked once per spec, before any cluster starts
    if missing is not None:
        print(f'{spec.name}: skipped, {len(trials)} trials not run: {missing}')
        return trials, store, code
    if not {t.key for t in trials} - store.done(options.retry_failed):
        summary = store.write_summary(store.records(t.key for t in trials), summary_name(spec))
        print(f'{spec.name}: {len(trials)} trials: {len(trials)} already stored, 0 done now; summary {summary}')
        return trials, store, code
    with dask_client(options.scheduler, options.workers) as client:   # connect before writing anything
        store.folder.mkdir(parents=True, exist_ok=True)
        (store.folder / f'spec-{spec.name}.yaml').write_text(yaml.safe_dump(
            {'name': spec.name, 'kind': spec.kind, 'engine': spec.engine, 'source': spec.source,
             'base': dict(spec.base), 'grid': [dict(b) for b in spec.grid], 'seeds': list(spec.seeds),
             'code': code}, sort_keys=False))
        workers = len(client.nthreads())
        sys.stderr.write(f'{spec.name}: {len(trials)} trials, store {store.folder}, {workers} workers\n')
        try:
            stats = run_trials(trials, store, client, code, retries=options.retries,
                               retry_failed=options.retry_failed, progress=options.progress)
        finally:   # also when interrupted: the summary of what is stored so far
            summary = store.write_summary(store.records(t.key for t in trials), summary_name(spec))
    print(f'{spec.name}: {stats.total} trials: {stats.skipped} already stored, {stats.ok} done now, '
          f'{stats.failed} failed, {stats.lost} lost by the engine ({stats.wall_s:.1f} s, {stats.workers} workers); '
          f'summary {summary}')
    return trials, store, code


def run_mapping(data: dict[str, Any], seeds: Sequence[int], options: RunOptions, command: str
                ) -> tuple[ExperimentSpec, list[Trial], ResultStore, dict[str, str]]:
    """Run the spec of a command (a mapping) over ``seeds`` (the report is ``report-<name>-seeds-<ranges>``)."""
    spec = spec_from_mapping({**data, 'seeds': 1}, f'{PROG} {command}').with_seeds(list(seeds))
    trials, store, code = run_spec(spec, options)
    return spec, trials, store, code


