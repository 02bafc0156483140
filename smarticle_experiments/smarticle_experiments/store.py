"""The result store: one folder per experiment store, one JSON file per finished trial, a Parquet summary.

Layout of ``<root>/<store>/`` (default root ``out/experiments``)::

    trials/<key>.json     one per finished trial: key, kind, params, seed, status ('ok' or 'failed'),
                          result or traceback, wall time, worker, code version (package, source hash
                          of the trial code, pybullet, numpy) -- written atomically (temp file + os.replace)
    summary.parquet       one row per trial of the last run of the store's own spec: key, kind, seed, grid
                          values, status, scalar results (summary-<name>.parquet for another spec that
                          shares the store)
    spec-<name>.yaml      the spec of each run (as resolved)

A trial's file appears only once its result is complete, so a killed client or worker leaves no
half-written result; a trial is stored once under its key, so nothing is counted twice. ``status``
'failed' with ``error_kind`` 'trial' is a trial that raised (traceback stored; not rerun unless asked);
'engine' marks a task the engine lost (e.g. its worker died more often than allowed); it is rerun on the
next run.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any

from . import __version__
from .errors import StoreError
from .trial_code import exported_module, locate, source_hash
from .trials import code_versions

DEFAULT_ROOT = Path('out/experiments')
#: The worker's entry point (package, exported name): the module it comes from is the package of the built-in
#: trial kinds, one module each, so that package's modules and what they import are the trial code of every kind.
RUN_ENTRY: tuple[str, str] = ('smarticle_experiments', 'run_kind')


def trial_modules(path: Sequence[Path] | None = None) -> tuple[str, ...]:
    """The modules whose code the built-in trial kinds run together, as entries of ``trial_code.source_hash``:
    the package of the worker's entry point ``RUN_ENTRY`` and each of its modules (a spec's trials are keyed by
    their own kind's modules, ``kinds.kind_modules``)."""
    package = exported_module(*RUN_ENTRY, path)
    init = locate(package, path)
    kinds = sorted(p.stem for p in init.parent.glob('*.py') if p.stem != '__init__') \
        if init is not None and init.name == '__init__.py' else []
    return (package, *(f'{package}.{name}' for name in kinds))


@lru_cache(maxsize=1)
def head_commit() -> str:
    """The commit of the source tree now (HEAD; '+dirty' if tracked files have local edits), or 'no git' outside
    a git checkout (an installed package). Not part of a trial's key: that is ``code_version``'s source hash."""
    root = Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(['git', '-C', str(root), 'rev-parse', 'HEAD'], capture_output=True, text=True,
                              timeout=20, check=True).stdout.strip()
        dirty = subprocess.run(['git', '-C', str(root), 'status', '--porcelain', '--untracked-files=no'],
                               capture_output=True, text=True, timeout=20, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return 'no git'
    return (head or 'no git') + ('+dirty' if head and dirty else '')


def code_version(modules: Iterable[str] | None = None, path: Sequence[Path] | None = None) -> dict[str, str]:
    """The code version a trial key includes: the package version, the hash of the source of every project
    module ``modules`` (a kind's, ``kinds.kind_modules``; default ``trial_modules()``: every built-in kind's) run
    (``trial_code.source_hash``, cached per process; ``path``: the folders to find the packages in, default where
    Python imports them from) and the engines' library versions."""
    entries = trial_modules(path) if modules is None else tuple(modules)
    return {'smarticle_experiments': __version__, 'source': source_hash(entries, path), **code_versions()}


def json_ready(value: Any) -> Any:
    """JSON-ready copy: NaN / inf floats become None, tuples lists, numpy scalars Python numbers."""
    if isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if hasattr(value, 'item') and callable(value.item) and getattr(value, 'ndim', 1) == 0:
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temp file in the same folder and os.replace (never half-written)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f'.{path.name}.', suffix='.tmp', dir=path.parent)
    try:
        with os.fdopen(fd, 'w') as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class ResultStore:
    """One experiment store folder: per-trial JSON files and the Parquet summary."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.trials_dir = self.folder / 'trials'

    def path_of(self, key: str) -> Path:
        """The file of trial ``key``."""
        return self.trials_dir / f'{key}.json'

    def write(self, record: Mapping[str, Any]) -> Path:
        """Store one trial record (must carry 'key') atomically; return its path."""
        path = self.path_of(str(record['key']))
        try:
            write_atomic(path, json.dumps(json_ready(record), sort_keys=True, allow_nan=False))
        except OSError as exc:
            raise StoreError(f'cannot write {path}: {exc}') from None
        return path

    def read(self, key: str) -> dict[str, Any] | None:
        """The record of trial ``key``, or None if it has none (or an unreadable one)."""
        try:
            data = json.loads(self.path_of(key).read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def keys(self) -> set[str]:
        """Keys of every stored trial."""
        if not self.trials_dir.is_dir():
            return set()
        return {p.stem for p in self.trials_dir.glob('*.json')}

    def records(self, keys: Iterable[str] | None = None) -> list[dict[str, Any]]:
        """Records of ``keys`` (in that order, skipping missing ones) or of every stored trial."""
        chosen = sorted(self.keys()) if keys is None else list(keys)
        out = []
        for key in chosen:
            record = self.read(key)
            if record is not None:
                out.append(record)
        return out

    def done(self, retry_failed: bool = False) -> set[str]:
        """Keys that a run skips: finished trials (a trial that raised too, unless ``retry_failed``)."""
        out = set()
        for record in self.records():
            if record.get('status') == 'ok' or (record.get('status') == 'failed'
                                                 and record.get('error_kind') == 'trial' and not retry_failed):
                out.add(str(record['key']))
        return out

    def write_summary(self, records: Iterable[Mapping[str, Any]], name: str = 'summary') -> Path:
        """Write ``<name>.parquet`` next to the trial files: one row per record, scalar columns only."""
        import pandas as pd

        rows = [summary_row(r) for r in records]
        frame = pd.DataFrame(rows)
        path = self.folder / f'{name}.parquet'
        self.folder.mkdir(parents=True, exist_ok=True)
        tmp = self.folder / f'.{name}.parquet.tmp'
        frame.to_parquet(tmp, index=False)
        os.replace(tmp, path)
        return path


def summary_row(record: Mapping[str, Any]) -> dict[str, Any]:
    """One summary row of a trial record: identity, grid values, status and the scalar results.

    Timing and worker columns are left out, so two runs of one spec give identical summaries.
    """
    row: dict[str, Any] = {'key': record['key'], 'kind': record['kind'], 'seed': record['seed'],
                           'status': record['status'], 'error_kind': record.get('error_kind', ''),
                           'error': (record.get('error') or '')[:200]}
    for name, value in sorted((record.get('point') or {}).items()):
        row[f'grid.{name}'] = json.dumps(value) if isinstance(value, (list, dict)) else value
    for name, value in sorted((record.get('result') or {}).items()):
        if isinstance(value, (bool, int, float, str)) or value is None:
            row[name] = value
    return row
