"""The engine: Dask distributed runs every trial that the store does not hold yet, one task per trial.

By default an embedded ``LocalCluster`` (one worker process per core, one thread each); with a scheduler
address the same tasks go to an existing cluster (``dask scheduler`` / ``dask worker``, or
dask-jobqueue on SLURM; docs/experiments.md). Each task is :func:`execute_trial`, a pure function of
(kind, typed parameters, seed) that catches a trial's exception and returns it as a 'failed' record, so a trial
that raises costs only itself. The client stores each record as soon as its future completes; a
worker killed mid-trial makes the scheduler run that task again elsewhere (``allowed-failures`` worker
deaths per task), and ``retries`` covers errors of the task machinery itself.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import sys
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any

from .errors import SchedulerError
from .kind import KindParams
from .kinds import run_kind, stored_params, trial_params
from .spec import Trial
from .store import ResultStore
from .trials import code_versions

#: Seconds to wait for an existing scheduler before giving up.
CONNECT_TIMEOUT = 5.0


def execute_trial(kind: str, params: Mapping[str, Any] | KindParams, seed: int, key: str, point: Mapping[str, Any],
                  code: Mapping[str, str]) -> dict[str, Any]:
    """Run one trial on a worker and return its full store record (a trial that raises: status 'failed').
    ``params`` are a registered kind's typed parameters (unpickling them imports the kind's module, which
    registers the kind on the worker) or a ``module:function`` kind's mapping."""
    started = datetime.now(timezone.utc).isoformat(timespec='seconds')
    unix0, wall0, cpu0 = time.time(), time.perf_counter(), time.process_time()
    record: dict[str, Any] = {'key': key, 'kind': kind, 'params': stored_params(params), 'seed': seed,
                              'point': dict(point),
                              'code': dict(code), 'started': started,
                              'worker': {'host': socket.gethostname(), 'pid': os.getpid(), **code_versions()}}
    try:
        record['result'] = run_kind(kind, params, seed)
        record['status'] = 'ok'
    except Exception as exc:   # the trial's failure is its result: stored with its traceback
        record.update(status='failed', error_kind='trial', error=f'{type(exc).__name__}: {exc}'.split('\n')[0],
                      traceback=traceback.format_exc())
    record['wall_s'] = time.perf_counter() - wall0
    record['cpu_s'] = time.process_time() - cpu0
    record['start_unix'], record['end_unix'] = unix0, unix0 + record['wall_s']
    return record


def engine_failure(trial: Trial, code: Mapping[str, str], exc: BaseException) -> dict[str, Any]:
    """The record of a task the engine lost (e.g. KilledWorker): rerun on the next run."""
    return {'key': trial.key, 'kind': trial.kind, 'params': dict(trial.params), 'seed': trial.seed,
            'point': dict(trial.point), 'code': dict(code), 'status': 'failed', 'error_kind': 'engine',
            'error': f'{type(exc).__name__}: {exc}'.split('\n')[0],
            'traceback': ''.join(traceback.format_exception(type(exc), exc, exc.__traceback__))}


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A distributed Client: to ``scheduler`` (SchedulerError if it does not answer) or an embedded LocalCluster."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=f'{CONNECT_TIMEOUT}s')
        except (OSError, TimeoutError, ValueError) as exc:
            raise SchedulerError(f'scheduler {scheduler} does not answer ({str(exc).splitlines()[0][:120]})') from None
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


@dataclass
class RunStats:
    """What one run did."""

    total: int          # trials of the spec
    skipped: int        # already in the store
    ok: int             # finished now
    failed: int         # trial raised (stored with traceback)
    lost: int           # engine failures (stored; rerun next time)
    wall_s: float
    workers: int


class Progress:
    """Progress bar: trials done, running, failed, and tqdm's estimate of the time left."""

    def __init__(self, total: int, slots: int, enabled: bool) -> None:
        self.total, self.slots, self.done, self.failed = total, slots, 0, 0
        self.bar: Any = None
        if enabled and total:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit='trial', dynamic_ncols=True, file=sys.stderr)
            self._post()

    def _post(self) -> None:
        running = min(self.slots, self.total - self.done)
        self.bar.set_postfix_str(f'done {self.done - self.failed}, running {running}, failed {self.failed}')

    def step(self, failed: bool) -> None:
        """Count one finished trial."""
        self.done += 1
        self.failed += int(failed)
        if self.bar is not None:
            self._post()
            self.bar.update(1)

    def close(self) -> None:
        """Close the bar."""
        if self.bar is not None:
            self.bar.close()


def run_trials(trials: Sequence[Trial], store: ResultStore, client: Any, code: Mapping[str, str],
               retries: int = 2, retry_failed: bool = False, progress: bool = True,
               on_record: Callable[[dict[str, Any]], None] | None = None) -> RunStats:
    """Submit every trial not yet in ``store`` to ``client``; store each record as soon as it is done."""
    from distributed import as_completed

    wall0 = time.perf_counter()
    done = store.done(retry_failed)
    todo = [t for t in trials if t.key not in done]
    unique = list({t.key: t for t in todo}.values())   # a grid may list one trial twice: run it once
    slots = sum(client.nthreads().values()) or 1
    stats = RunStats(len(trials), len(trials) - len(todo), 0, 0, 0, 0.0, len(client.nthreads()))
    futures = {client.submit(execute_trial, t.kind, trial_params(t.kind, t.params), t.seed, t.key, dict(t.point),
                             dict(code), key=f'trial-{t.key}', pure=False, retries=retries): t for t in unique}
    bar = Progress(len(unique), slots, progress)
    try:
        for future in as_completed(futures):
            trial = futures[future]
            try:
                record = future.result()
            except Exception as exc:   # KilledWorker, CancelledError, ...: stored as an engine failure
                record = engine_failure(trial, code, exc)
            store.write(record)
            if record['status'] == 'ok':
                stats.ok += 1
            elif record.get('error_kind') == 'engine':
                stats.lost += 1
            else:
                stats.failed += 1
            bar.step(record['status'] != 'ok')
            if on_record is not None:
                on_record(record)
            future.release()
    finally:
        bar.close()
        for future in futures:
            future.cancel()
    stats.wall_s = time.perf_counter() - wall0
    return stats
