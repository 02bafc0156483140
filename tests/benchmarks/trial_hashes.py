"""Hashes of stored trial results: the check that a refactor of the experiments package keeps its outputs.

Short versions of the paper's specs (few seeds, starts and periods; ``CHECKS``) run through
``smarticle-experiments run`` into a store of their own; each stored trial's ``result`` is then hashed
canonically (JSON with sorted keys, no spaces, as the store writes it) and listed by
(spec, grid point, seed), which does not depend on the code version that is part of a trial's key. Two
hash tables of runs from different commits compare line by line: the same hash is the same numbers to the
last digit.

    .venv/bin/python tests/benchmarks/trial_hashes.py run --out out/hashcheck/before
    .venv/bin/python tests/benchmarks/trial_hashes.py hash --out out/hashcheck/before > out/hashcheck/before.md
    .venv/bin/python tests/benchmarks/trial_hashes.py compare out/hashcheck/before out/hashcheck/after

Run it with ``nice -n 10`` on a shared machine: the short versions cost a few minutes on one worker.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[2]
SPEC_DIR = ROOT / 'smarticle_experiments' / 'config' / 'experiments'

#: Each check: the shipped spec it shortens and the keys it replaces (grid, seeds, periods).
CHECKS: dict[str, dict[str, Any]] = {
    'p1': {'seeds': [1000, 1001, 1002], 'periods': 40},
    'p4': {'grid': {'phase2': [0.0, 0.25], 'theta_deg': [0, 30, 150, 300, 330], 'phi_deg': [180]},
           'seeds': [0], 'periods': 20},
    'p5': {'grid': {'alpha_max_deg': [10, 45, 90]}, 'seeds': 2, 'periods': 30},
    'p7': {'seeds': 2, 'periods': 10},
    'p6': {'grid': [{'alpha_max_deg': [90], 'feedback': [False]}, {'alpha_max_deg': [90], 'feedback': [True]}],
           'seeds': 2, 'periods': 30},
}


def canonical(value: Any) -> str:
    """JSON with sorted keys and no spaces (the text that is hashed)."""
    return json.dumps(value, sort_keys=True, separators=(',', ':'), allow_nan=False)


def digest(value: Any) -> str:
    """The first 16 hex digits of the SHA-256 of ``canonical(value)``."""
    return hashlib.sha256(canonical(value).encode()).hexdigest()[:16]


def short_spec(name: str, spec_dir: Path = SPEC_DIR) -> dict[str, Any]:
    """The shipped spec ``name`` (of ``spec_dir``) with the replacements of ``CHECKS[name]``, named
    ``check-<name>``."""
    path = next(spec_dir.rglob(f'{name}.yaml'))
    data = yaml.safe_load(path.read_text())
    data.update(CHECKS[name], name=f'check-{name}', store=f'check-{name}')
    return data


def cmd_run(args: argparse.Namespace) -> int:
    """Write the short specs and run each through ``smarticle-experiments run`` into ``--out``."""
    spec_dir = args.out / 'specs'
    spec_dir.mkdir(parents=True, exist_ok=True)
    for name in args.only or CHECKS:
        path = spec_dir / f'check-{name}.yaml'
        path.write_text(yaml.safe_dump(short_spec(name, args.specs), sort_keys=False))
        command = [sys.executable, '-m', 'smarticle_experiments.cli', 'run', str(path), '--out',
                   str(args.out / 'store'), '--workers', str(args.workers), '--no-progress']
        print(' '.join(command[1:]), flush=True)
        done = subprocess.run(command, check=False)
        if done.returncode:
            return done.returncode
    return 0


def hashes(store_root: Path) -> list[dict[str, Any]]:
    """One row per stored trial of the checks: spec, grid point, seed, status and the hash of its result."""
    rows = []
    for folder in sorted(store_root.glob('check-*')):
        for path in sorted((folder / 'trials').glob('*.json')):
            record = json.loads(path.read_text())
            rows.append({'spec': folder.name.removeprefix('check-'), 'point': canonical(record.get('point') or {}),
                         'seed': int(record['seed']), 'status': record['status'],
                         'params': digest(record.get('params')), 'result': digest(record.get('result'))})
    return sorted(rows, key=lambda r: (r['spec'], r['point'], r['seed']))


def table(rows: list[Mapping[str, Any]]) -> str:
    """The hash table as Markdown."""
    out = ['| spec | grid point | seed | status | params hash | result hash |',
           '| --- | --- | ---: | --- | --- | --- |']
    out += [f"| {r['spec']} | `{r['point']}` | {r['seed']} | {r['status']} | {r['params']} | {r['result']} |"
            for r in rows]
    return '\n'.join(out)


def cmd_hash(args: argparse.Namespace) -> int:
    """Print the hash table of ``--out``'s store (and write hashes.json beside it)."""
    rows = hashes(args.out / 'store')
    (args.out / 'hashes.json').write_text(json.dumps(rows, indent=1))
    print(table(rows))
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    """Compare two runs' hash tables; exit 1 listing every trial whose result differs or is missing."""
    a = {(r['spec'], r['point'], r['seed']): r for r in hashes(args.before / 'store')}
    b = {(r['spec'], r['point'], r['seed']): r for r in hashes(args.after / 'store')}
    bad = 0
    for key in sorted(a.keys() | b.keys()):
        ra, rb = a.get(key), b.get(key)
        if ra is None or rb is None or ra['result'] != rb['result'] or ra['status'] != rb['status']:
            bad += 1
            print(f'DIFFERS {key}: {ra and ra["result"]} -> {rb and rb["result"]}')
    print(f'{len(a)} trials before, {len(b)} after, {bad} differ')
    return 1 if bad or not a else 0


def main(argv: list[str] | None = None) -> int:
    """Entry point."""
    parser = argparse.ArgumentParser(description=(__doc__ or '').split('\n')[0])
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='run the short specs into --out/store')
    run.add_argument('--out', type=Path, required=True)
    run.add_argument('--workers', type=int, default=1)
    run.add_argument('--only', nargs='*', choices=list(CHECKS))
    run.add_argument('--specs', type=Path, default=SPEC_DIR, help='folder of the shipped specs (default: this tree)')
    h = sub.add_parser('hash', help='print the hash table of --out/store')
    h.add_argument('--out', type=Path, required=True)
    c = sub.add_parser('compare', help='compare two runs')
    c.add_argument('before', type=Path)
    c.add_argument('after', type=Path)
    args = parser.parse_args(argv)
    return {'run': cmd_run, 'hash': cmd_hash, 'compare': cmd_compare}[args.command](args)


if __name__ == '__main__':
    sys.exit(main())
