"""Throughput and overhead of the experiments engine (smarticle_experiments on Dask LocalCluster).

For each worker count (default 1 and 2) a fresh LocalCluster (one process per worker, one thread each)
runs the same dense trials into a fresh temporary store; the cluster's start-up is not timed. Reports:

* throughput = trials / wall time of the run (submit of the first task to the last record stored), in
  trials per hour, and the speed-up of each worker count against one worker (target: 2 workers >= 1.8x);
* engine overhead per task = the mean gap between one trial's end and the next trial's start on the same
  worker process (scheduling, transfer of the task and its result), against the mean trial time (target
  < 2 %); the trial's own time is measured inside the task. Separately: the slot time not spent in trials
  at all, (workers x wall - sum of trial times) / trials, which adds the start-up and the idle tail of the
  last round (fewer trials left than workers).

On a shared machine both numbers depend on the load (printed with the table); the tiny ``--quick``
trials make the per-task overhead look larger than it is for real 300-period trials.

    .venv/bin/python tests/benchmarks/bench_experiments.py --quick
    .venv/bin/python tests/benchmarks/bench_experiments.py --trials 16 --robots 7 --periods 20
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_line, markdown_table, out_path, write_csv
from smarticle_experiments.engine import dask_client, run_trials
from smarticle_experiments.spec import spec_from_mapping
from smarticle_experiments.store import ResultStore, code_version


def measure(workers: int, trials: int, robots: int, periods: float) -> dict[str, object]:
    """Run ``trials`` dense trials on a LocalCluster of ``workers`` processes; return the figures."""
    spec = spec_from_mapping({'name': 'bench', 'kind': 'dense', 'periods': periods,
                              'params': {'robots': robots, 'trajectory': False}, 'seeds': trials})
    code = code_version()
    with tempfile.TemporaryDirectory() as folder, dask_client(workers=workers) as client:
        client.wait_for_workers(workers)
        store = ResultStore(Path(folder) / 'bench')
        start = time.perf_counter()
        stats = run_trials(spec.trials(code), store, client, code, progress=False)
        wall = time.perf_counter() - start
        records = store.records()
    own = [float(r['wall_s']) for r in records]
    busy = sum(own)
    by_worker: dict[int, list[tuple[float, float]]] = {}
    for r in records:
        by_worker.setdefault(int(r['worker']['pid']), []).append((float(r['start_unix']), float(r['end_unix'])))
    gaps = [b[0] - a[1] for spans in map(sorted, by_worker.values())
            for a, b in zip(spans, spans[1:], strict=False)]
    overhead = sum(gaps) / len(gaps) if gaps else float('nan')
    mean_trial = busy / len(own)
    idle = max(workers * wall - busy, 0.0) / len(own)
    return {'workers': workers, 'trials': len(own), 'failed': stats.failed + stats.lost, 'wall_s': wall,
            'trials_per_hour': len(own) / wall * 3600.0, 'mean_trial_s': mean_trial,
            'overhead_per_task_s': overhead, 'overhead_pct': 100.0 * overhead / mean_trial,
            'idle_per_task_s': idle, 'idle_pct': 100.0 * idle / mean_trial}


def main(argv: list[str] | None = None) -> int:
    """Measure, print the table, write CSV."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true', help='8 trials of 3 robots x 3 periods')
    parser.add_argument('--trials', type=int, default=None, help='trials per worker count (default 16)')
    parser.add_argument('--robots', type=int, default=None, help='robots per dense trial (default 7)')
    parser.add_argument('--periods', type=float, default=None, help='periods per trial (default 20)')
    parser.add_argument('--workers', type=int, nargs='+', default=[1, 2], help='worker counts (default 1 2)')
    parser.add_argument('--out-dir', type=Path, default=None, help='output folder (default out/benchmarks)')
    args = parser.parse_args(argv)
    trials = args.trials or (8 if args.quick else 16)
    robots = args.robots or (3 if args.quick else 7)
    periods = args.periods or (3.0 if args.quick else 20.0)
    print(f'# experiments engine: {trials} dense trials of {robots} robots x {periods:g} periods per worker count; '
          f'{machine_line()}')
    rows = [measure(w, trials, robots, periods) for w in args.workers]
    base = next((r for r in rows if r['workers'] == 1), rows[0])
    for row in rows:
        row['speedup'] = float(row['trials_per_hour']) / float(base['trials_per_hour'])  # type: ignore[arg-type]
    print(markdown_table(rows, [('workers', 'workers', 'd'), ('trials', 'trials', 'd'), ('failed', 'failed', 'd'),
                                ('wall_s', 'wall (s)', '.1f'), ('trials_per_hour', 'trials / hour', '.0f'),
                                ('speedup', 'speed-up vs 1', '.2f'), ('mean_trial_s', 'mean trial (s)', '.2f'),
                                ('overhead_per_task_s', 'engine gap / task (s)', '.4f'),
                                ('overhead_pct', 'engine gap (% of trial)', '.2f'),
                                ('idle_per_task_s', 'slot time not in trials / task (s)', '.3f'),
                                ('idle_pct', 'not in trials (% of trial)', '.1f')]))
    print('targets: 2 workers >= 1.8x one; overhead < 2 % of the trial time')
    print(f'wrote {write_csv(out_path("experiments_engine.csv", args.out_dir), rows)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
