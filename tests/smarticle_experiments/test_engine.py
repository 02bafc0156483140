"""The engine end to end on a LocalCluster: a tiny experiment, a trial that raises, a killed worker, a
killed client that resumes, and two runs of one spec that give identical summaries."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
import yaml

from smarticle_experiments.cli import main
from smarticle_experiments.engine import dask_client, run_trials
from smarticle_experiments.spec import spec_from_mapping
from smarticle_experiments.store import ResultStore, code_version

ROOT = Path(__file__).resolve().parents[2]
FAKE = 'tests.smarticle_experiments.fake_trials'
#: A tiny real experiment: 3 robots densely packed, 2 periods, 2 seeds.
TINY = {'name': 'tiny', 'description': 'tiny', 'kind': 'dense', 'periods': 2, 'params': {'robots': 3},
        'analysis': {'min_periods': 1, 'positive_periods': 2}, 'seeds': 2,
        'report': ['p1', 'trajectories', 'configurations', 'lifetimes']}

pytestmark = pytest.mark.slow


def write_spec(path: Path, data: dict[str, Any]) -> str:
    """Write a spec YAML; return its path as a string."""
    path.write_text(yaml.safe_dump(data))
    return str(path)


def stored(folder: Path) -> dict[str, dict[str, Any]]:
    """Every trial record in a store folder, by key (each file must be whole JSON)."""
    return {p.stem: json.loads(p.read_text()) for p in (folder / 'trials').glob('*.json')}


def test_a_tiny_experiment_runs_end_to_end_resumes_and_repeats(tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    spec = write_spec(tmp_path / 'tiny.yaml', TINY)
    first, second = tmp_path / 'a', tmp_path / 'b'
    assert main(['run', spec, '--out', str(first), '--workers', '2', '--no-progress', '--report']) == 0
    records = stored(first / 'tiny')
    assert len(records) == 2 and all(r['status'] == 'ok' for r in records.values())
    rec = next(iter(records.values()))
    assert rec['code']['source'] and rec['code']['pybullet'] and rec['code']['numpy']
    assert rec['result']['periods_run'] == pytest.approx(2.0)
    report = (first / 'tiny' / 'report-tiny' / 'report.md').read_text()
    assert '| P1 trials with an isolated pair bound >= 2 periods' in report and 'Wilson' in report
    assert (first / 'tiny' / 'report-tiny' / 'trajectories.png').stat().st_size > 0
    mtimes = {p: p.stat().st_mtime_ns for p in (first / 'tiny' / 'trials').glob('*.json')}
    capsys.readouterr()
    assert main(['run', spec, '--out', str(first), '--workers', '1', '--no-progress']) == 0   # nothing to do
    assert '2 already stored, 0 done now' in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in mtimes} == mtimes
    assert main(['run', spec, '--out', str(second), '--workers', '1', '--no-progress']) == 0
    a = pd.read_parquet(first / 'tiny' / 'summary.parquet')
    b = pd.read_parquet(second / 'tiny' / 'summary.parquet')
    pd.testing.assert_frame_equal(a, b)
    assert {k: r['result'] for k, r in records.items()} == {k: r['result'] for k, r in stored(second / 'tiny').items()}
    assert main(['status', spec, '--out', str(first)]) == 0
    assert '2 done' in capsys.readouterr().out


def test_a_trial_that_raises_is_stored_with_its_traceback_and_the_others_go_on(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'flaky', 'kind': f'{FAKE}:flaky', 'params': {'fail': [1]}, 'seeds': 4})
    code = code_version()
    store = ResultStore(tmp_path / 'flaky')
    with dask_client(workers=2) as client:
        stats = run_trials(spec.trials(code), store, client, code, progress=False)
    assert (stats.ok, stats.failed, stats.lost) == (3, 1, 0)
    failed = [r for r in store.records() if r['status'] == 'failed']
    assert len(failed) == 1 and failed[0]['seed'] == 1 and failed[0]['error_kind'] == 'trial'
    assert 'seed 1 fails on purpose' in failed[0]['traceback'] and 'Traceback' in failed[0]['traceback']


def test_a_worker_killed_mid_trial_costs_that_trial_only(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'sleepy', 'kind': f'{FAKE}:sleepy', 'params': {'sleep': 3.0}, 'seeds': 3})
    code = code_version()
    trials = spec.trials(code)
    store = ResultStore(tmp_path / 'sleepy')
    killed: dict[str, Any] = {}
    with dask_client(workers=2) as client:
        def kill_one() -> None:
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                busy = {w: keys for w, keys in client.processing().items() if keys}
                if busy:
                    worker, keys = next(iter(busy.items()))
                    time.sleep(0.5)   # the trial is running on it now
                    pid = client.run(os.getpid, workers=[worker])[worker]
                    killed.update(pid=pid, keys=[str(k) for k in keys])
                    os.kill(pid, signal.SIGKILL)
                    return
                time.sleep(0.1)

        killer = threading.Thread(target=kill_one)
        killer.start()
        stats = run_trials(trials, store, client, code, retries=2, progress=False)
        killer.join()
    assert killed, 'no worker was found running a trial'
    records = stored(tmp_path / 'sleepy')
    assert sorted(records) == sorted(t.key for t in trials)                    # every trial once, none lost
    assert all(r['status'] == 'ok' for r in records.values())
    assert (stats.ok, stats.failed, stats.lost) == (3, 0, 0)
    rerun = [records[k.removeprefix('trial-')] for k in killed['keys']]
    assert all(r['result']['pid'] != killed['pid'] for r in rerun)           # finished on another process
    assert sorted(r['result']['value'] for r in records.values()) == [0, 10, 20]


def test_a_killed_client_resumes_where_it_stopped(tmp_path: Path) -> None:
    spec = write_spec(tmp_path / 'slow.yaml', {'name': 'slow', 'kind': f'{FAKE}:sleepy', 'params': {'sleep': 1.0},
                                                'seeds': 8})
    out = tmp_path / 'out'
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join([str(ROOT), os.environ.get('PYTHONPATH', '')])}
    cmd = [sys.executable, '-m', 'smarticle_experiments.cli', 'run', spec, '--out', str(out), '--workers', '2',
           '--no-progress']
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    trials_dir = out / 'slow' / 'trials'
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and len(list(trials_dir.glob('*.json'))) < 2:
            time.sleep(0.1)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)   # the client and its LocalCluster, mid-run
        proc.wait(timeout=30)
    before = stored(out / 'slow')
    assert 2 <= len(before) < 8, 'the client was to be killed mid-run'
    mtimes = {k: (trials_dir / f'{k}.json').stat().st_mtime_ns for k in before}
    done = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert f'{len(before)} already stored, {8 - len(before)} done now' in done.stdout
    after = stored(out / 'slow')
    assert len(after) == 8 and all(r['status'] == 'ok' for r in after.values())
    assert {k: (trials_dir / f'{k}.json').stat().st_mtime_ns for k in before} == mtimes   # not run again
    assert len(pd.read_parquet(out / 'slow' / 'summary.parquet')) == 8


def test_the_same_trials_go_to_an_existing_scheduler(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from distributed import LocalCluster

    spec = write_spec(tmp_path / 'tiny.yaml', {**TINY, 'report': []})
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main(['run', spec, '--out', str(tmp_path / 'remote'), '--scheduler', cluster.scheduler_address,
                     '--no-progress']) == 0
    assert '0 already stored, 2 done now' in capsys.readouterr().out
    local = tmp_path / 'local'
    assert main(['run', spec, '--out', str(local), '--workers', '1', '--no-progress']) == 0
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / 'remote' / 'tiny' / 'summary.parquet'),
                                  pd.read_parquet(local / 'tiny' / 'summary.parquet'))
