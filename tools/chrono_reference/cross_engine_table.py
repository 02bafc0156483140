"""The cross-engine table (docs/chrono_reference.md): Bullet and MuJoCo against Chrono over a ring of pair starts and a
lone robot's headings, with intervals and the verdicts of the rules fixed in the doc.

Reads what the runs wrote and runs nothing:
  * the pair rows of ``reference_check.py`` (``--out`` JSON files, one per start: the ring);
  * the lone robot's trials of the specs ``single_chrono``, ``single_bullet_40`` and ``single_mujoco_40``
    (their result stores).

A run with the authors' published masses is a column of its own (``chrono, authors' masses``), set against the
same engine's default masses and against Chrono's authors' masses. A run at a step other than its engine's
default (Bullet 1/960 s, Chrono 1e-4 s, MuJoCo 1/9600 s) is a column of its own, labelled with its step
('bullet 1/3840 s'); Bullet at 1/3840 and 1/7680 s gets verdicts against
Bullet at 1/960 s and Chrono, and a convergence verdict (the gliding share agrees by Fisher's test at both finer
steps and the gliders' mean speed is within 25 % of 1/960 s's).

Usage:
  python tools/chrono_reference/cross_engine_table.py --ring out/cross/ring_*.json \
      --single-chrono out/cross/store/single_chrono --single-bullet out/cross/store/single_bullet_40 \
      --single-mujoco out/cross/store/single_mujoco_40

Intervals: 95 % Wilson for shares (scipy.stats.binomtest), 95 % percentile bootstrap for means (10 000
resamples of the starts, numpy seed 0); shares compared by Fisher's exact test (two-sided).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import bootstrap
from smarticle_common.cli import closed_pipe_safe
from smarticle_experiments import stats
from smarticle_experiments.stats import fisher_p

#: The rules' thresholds (docs/chrono_reference.md, "The cross-engine table").
STILL_TRAVEL_W = 0.1          # W over the run: a still pair travels less
STILL_PHI_DEG = 20.0          # deg from 180: a still pair ends within this
GLIDE_TAIL = 10               # periods bound at the end
GLIDE_SPEED = 1.0             # W per 100 periods
FISHER_P = 0.05
SPEED_FACTOR = 2.0
LONE_STILL_UM = 54.0          # um per cycle (0.1 W per 100 periods)
ENGINES = ('bullet', 'chrono', 'mujoco')
#: Each engine's default step (s): a run at another step is labelled with its step ('bullet 1/3840 s').
DEFAULT_STEPS = {'bullet': 1.0 / 960.0, 'chrono': 1e-4, 'mujoco': 1.0 / 9600.0}
#: Bullet's finer steps over the offset pair's ring (steps per second) and the rule of its convergence there:
#: at every finer step the gliding share agrees with the default step's (Fisher) and the gliders' mean speed is
#: within this fraction of it.
FINE_BULLET = (3840, 7680)
CONVERGED_SPEED = 0.25
#: The engine pairs a verdict is given for (where both ran).
#: A run with the authors' published masses (``reference_check.py --mass-model authors``) is a column of its own,
#: its engine's label with this suffix ('chrono, authors' masses'): it is set against the same engine with the
#: default masses and against Chrono with the authors' masses.
AUTHORS = ", authors' masses"
VERSUS = (('bullet', 'chrono'), ('mujoco', 'chrono'), ('bullet', 'mujoco'),
          *((f'bullet 1/{n} s', 'bullet') for n in FINE_BULLET), *((f'bullet 1/{n} s', 'chrono') for n in FINE_BULLET),
          *((e + AUTHORS, e) for e in ENGINES), ('bullet' + AUTHORS, 'chrono' + AUTHORS),
          ('mujoco' + AUTHORS, 'chrono' + AUTHORS), ('bullet' + AUTHORS, 'mujoco' + AUTHORS))


def record_missing(out: Path, starts: Iterable[tuple[int, Any]], engines: Sequence[str],
                   run: Callable[[str, Any], Any]) -> None:
    """Run each (seed, start) in each engine into ``out/<engine>_seed<seed>.npz``, one line per run.

    A recording already on disk is kept (a run can be resumed); an engine that is not built (Chrono) is
    skipped with its one line. ``run(engine, start)`` returns a ``Recording``.
    """
    from smarticle_common.runs import save_npz
    from smarticle_sim.chrono_reference import ChronoUnavailable

    out.mkdir(parents=True, exist_ok=True)
    for seed, start in starts:
        for engine in engines:
            path = out / f'{engine}_seed{seed}.npz'
            if path.exists():
                continue
            wall = time.perf_counter()
            try:
                rec = run(engine, start)
            except ChronoUnavailable as exc:
                print(f'skipped: {exc}', file=sys.stderr)
                continue
            save_npz(rec, path)
            print(f'{engine} seed {seed}: {len(rec.time)} samples, trouble {rec.trouble or "none"}, '
                  f'{time.perf_counter() - wall:.0f} s', flush=True)


def label(engine: str, step: float) -> str:
    """The engine's name at its default step, else the name with the step ('bullet 1/3840 s', 'chrono 5e-05 s')."""
    default = DEFAULT_STEPS.get(engine)
    if default is None or math.isclose(step, default, rel_tol=1e-6):
        return engine
    if engine in ('bullet', 'mujoco'):
        return f'{engine} 1/{round(1.0 / step)} s'
    return f'{engine} {step:g} s'


def present(rows: dict[tuple[str, float], list[dict[str, Any]]]) -> list[str]:
    """The engine labels of ``rows``: the default steps first (bullet, chrono, mujoco), then the others."""
    names = {k[0] for k in rows}
    first = [e for e in ENGINES if e in names] + [e + AUTHORS for e in ENGINES if e + AUTHORS in names]
    return first + sorted(names - set(first))


def wilson(k: int, n: int) -> tuple[float, float, float]:
    """k/n and its 95 % Wilson interval, as the (value, low, high) that ``fmt`` takes."""
    est = stats.wilson(k, n)
    return est.value, est.low, est.high


def boot(values: Sequence[float]) -> tuple[float, float, float]:
    """The mean and its 95 % percentile bootstrap interval (NaN interval for fewer than 2 values)."""
    arr = np.asarray(values, dtype=float)
    if arr.size == 0:
        return math.nan, math.nan, math.nan
    if arr.size < 2 or np.all(arr == arr[0]):
        return float(arr.mean()), (float(arr[0]) if arr.size > 1 else math.nan), (float(arr[0]) if arr.size > 1
                                                                                 else math.nan)
    res = bootstrap((arr,), np.mean, confidence_level=0.95, n_resamples=10_000, method='percentile',
                    rng=np.random.default_rng(0))
    return float(arr.mean()), float(res.confidence_interval.low), float(res.confidence_interval.high)


def fmt(est: tuple[float, float, float], digits: str = '.3g', share: bool = False) -> str:
    """``v [lo, hi]`` (shares as k/n-free percentages)."""
    v, lo, hi = est
    if share:
        return f'{100 * v:.0f} % [{100 * lo:.0f}, {100 * hi:.0f}]'
    if not math.isfinite(v):
        return 'n/a'
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f'{format(v, digits)} (no interval)'
    return f'{format(v, digits)} [{format(lo, digits)}, {format(hi, digits)}]'


def still(row: dict[str, Any]) -> bool:
    """Rule (a): the pair travels under 0.1 W and ends within 20 deg of phi 180."""
    return row['travel_w'] < STILL_TRAVEL_W and abs(row['phi_end_deg'] - 180.0) <= STILL_PHI_DEG


def glides(row: dict[str, Any]) -> bool:
    """Rule (b): bound in each of the last 10 periods and over 1 W per 100 periods."""
    return row['bound_tail_periods'] >= GLIDE_TAIL and row['travel_w_per_100'] > GLIDE_SPEED


def ring_rows(paths: Sequence[Path]) -> dict[tuple[str, float], list[dict[str, Any]]]:
    """The pair rows by (engine label, robot 2's phase), each with its start's theta; a start run twice in one
    engine at one step (two files) counts once."""
    out: dict[tuple[str, float], list[dict[str, Any]]] = {}
    seen: set[tuple[str, float, float]] = set()
    for path in paths:
        data = json.loads(path.read_text())
        theta = float(data['args']['theta'])
        for row in data['rows']:
            name = label(row['engine'], float(row['step'])) + (AUTHORS if row.get('mass_model') == 'authors' else '')
            if (name, float(row['phase2']), theta) in seen:
                continue
            seen.add((name, float(row['phase2']), theta))
            out.setdefault((name, float(row['phase2'])), []).append({**row, 'theta': theta})
    for rows in out.values():
        rows.sort(key=lambda r: r['theta'])
    return out


def overlap(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
    """True if the two intervals overlap."""
    return a[1] <= b[2] and b[1] <= a[2]


def in_phase(rows: dict[tuple[str, float], list[dict[str, Any]]]) -> list[str]:
    """Row (a): the in-phase pair over the ring."""
    lines = ['| engine | starts | still at phi 180 | mean r_end (BL) | mean travel per 100 periods (W) |',
             '| --- | ---: | --- | --- | --- |']
    counts, r_ends = {}, {}
    for engine in present(rows):
        rs = rows.get((engine, 0.0), [])
        if not rs:
            continue
        k = sum(still(r) for r in rs)
        counts[engine] = (k, len(rs))
        r_ends[engine] = boot([r['r_end_bl'] for r in rs])
        lines.append(f'| {engine} | {len(rs)} | {k}/{len(rs)} = {fmt(wilson(k, len(rs)), share=True)} | '
                     f'{fmt(r_ends[engine])} | {fmt(boot([r["travel_w_per_100"] for r in rs]))} |')
    lines.append('')
    for a, b in VERSUS:
        if a not in counts or b not in counts:
            continue
        p = fisher_p(counts[a], counts[b])
        both = overlap(r_ends[a], r_ends[b])
        lines.append(f'- {a} vs {b}: state: Fisher p = {p:.3g}: **{"agree" if p >= FISHER_P else "differ"}**; '
                     f'r_end: intervals {"overlap" if both else "do not overlap"}: '
                     f'**{"agree" if both else "differ"}**.')
    return lines


def offset(rows: dict[tuple[str, float], list[dict[str, Any]]]) -> list[str]:
    """Row (b): the 0.1-offset pair over the ring."""
    lines = ['| engine | starts | gliding | travel per 100 periods of the gliders (W) | phi_end of the gliders (deg) |',
             '| --- | ---: | --- | --- | --- |']
    counts, speeds = {}, {}
    for engine in present(rows):
        rs = rows.get((engine, 0.1), [])
        if not rs:
            continue
        g = [r for r in rs if glides(r)]
        counts[engine] = (len(g), len(rs))
        speeds[engine] = [r['travel_w_per_100'] for r in g]
        phis = ', '.join(f'{r["phi_end_deg"]:.0f}' for r in g) or '-'
        lines.append(f'| {engine} | {len(rs)} | {len(g)}/{len(rs)} = {fmt(wilson(len(g), len(rs)), share=True)} | '
                     f'{fmt(boot(speeds[engine]))} | {phis} |')
    lines.append('')
    for a, b in VERSUS:
        if a not in counts or b not in counts:
            continue
        p = fisher_p(counts[a], counts[b])
        text = f'- {a} vs {b}: share: Fisher p = {p:.3g}: **{"agree" if p >= FISHER_P else "differ"}**; speed: '
        if min(len(speeds[a]), len(speeds[b])) < 2:
            text += '**not decided** (fewer than 2 gliders in an engine).'
        else:
            ratio = float(np.mean(speeds[a]) / np.mean(speeds[b]))
            text += (f'{a} / {b} = {ratio:.2f}: '
                     f'**{"agree" if 1 / SPEED_FACTOR <= ratio <= SPEED_FACTOR else "differ"}**.')
        lines.append(text)
    fine = [f'bullet 1/{n} s' for n in FINE_BULLET]
    if 'bullet' in counts and all(f in counts for f in fine):
        verdicts = []
        for f in fine:
            p = fisher_p(counts[f], counts['bullet'])
            ratio = (float(np.mean(speeds[f]) / np.mean(speeds['bullet'])) if speeds[f] and speeds['bullet']
                     else math.nan)
            verdicts.append(p >= FISHER_P and abs(ratio - 1.0) <= CONVERGED_SPEED)
        lines.append(f'- Bullet at 1/960 s on the ring: **{"converged" if all(verdicts) else "not converged"}** '
                     f'(share agrees at both finer steps and speed within {100 * CONVERGED_SPEED:.0f} %).')
    return lines


def per_start(rows: dict[tuple[str, float], list[dict[str, Any]]]) -> list[str]:
    """Every run: theta, phase, engine, r_end, phi_end, travel per 100, bound tail, the rule's label."""
    names = present(rows)
    lines = ['| theta (deg) | phase2 | ' + ' | '.join(f'{e}: r_end / phi_end / per 100 / tail' for e in names) + ' |',
             '| ---: | ---: |' + ' --- |' * len(names)]
    for phase in (0.0, 0.1):
        by_theta: dict[float, dict[str, dict[str, Any]]] = {}
        for engine in names:
            for r in rows.get((engine, phase), []):
                by_theta.setdefault(r['theta'], {})[engine] = r
        for theta in sorted(by_theta):
            cells = []
            for engine in names:
                run = by_theta[theta].get(engine)
                if run is None:
                    cells.append('-')
                    continue
                label = ('still' if still(run) else '') if phase == 0.0 else ('glides' if glides(run) else '')
                cells.append(f'{run["r_end_bl"]:.2f} / {run["phi_end_deg"]:.0f} / {run["travel_w_per_100"]:.2g} / '
                             f'{run["bound_tail_periods"]}{" " + label if label else ""}')
            lines.append(f'| {theta:.0f} | {phase:g} | ' + ' | '.join(cells) + ' |')
    return lines


def single_results(folder: Path) -> list[dict[str, Any]]:
    """The ok results of a spec's store (every record file), by seed."""
    out = []
    for path in sorted(folder.glob('**/*.json')):
        try:
            rec = json.loads(path.read_text())
        except (ValueError, OSError):
            continue
        if isinstance(rec, dict) and rec.get('status') == 'ok' and 'drift_um_per_cycle' in rec.get('result', {}):
            out.append({'seed': rec['seed'], **rec['result']})
    return sorted(out, key=lambda r: r['seed'])


def lone(folders: dict[str, Path | None]) -> list[str]:
    """Row (c): a lone robot's drift per cycle."""
    lines = ['| engine | seed: heading (deg) -> drift (um per cycle) | mean drift (um per cycle) |',
             '| --- | --- | --- |']
    means = {}
    for engine in ENGINES:
        folder = folders.get(engine)
        if folder is None:
            continue
        rs = single_results(folder)
        if not rs:
            continue
        means[engine] = boot([r['drift_um_per_cycle'] for r in rs])
        each = '; '.join(f'{r["seed"]}: {r["heading_deg"]:.0f} -> {r["drift_um_per_cycle"]:.0f}'
                         + (f' ({r["trouble"]})' if r.get('trouble') else '') for r in rs)
        lines.append(f'| {engine} | {each} | {fmt(means[engine])} |')
    lines.append('')
    for a, b in VERSUS:
        if a not in means or b not in means:
            continue
        va, vb = means[a][0], means[b][0]
        both_still = va < LONE_STILL_UM and vb < LONE_STILL_UM
        ratio = va / vb if vb > 0 else math.inf
        ok = both_still or 1 / SPEED_FACTOR <= ratio <= SPEED_FACTOR
        lines.append(f'- {a} / {b} = {ratio:.2f}{", both under 54 um" if both_still else ""}: '
                     f'**{"agree" if ok else "differ"}**.')
    return lines


def main() -> int:
    """Print the table's sections (markdown)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--ring', type=Path, nargs='*', default=[], help="reference_check.py's JSON files")
    parser.add_argument('--single-chrono', type=Path, help="the store folder of the spec single_chrono")
    parser.add_argument('--single-bullet', type=Path, help="the store folder of the spec single_bullet_40")
    parser.add_argument('--single-mujoco', type=Path, help="the store folder of the spec single_mujoco_40")
    args = parser.parse_args()
    rows = ring_rows(args.ring)
    for title, lines in (('(a) in phase', in_phase(rows)), ('(b) 0.1 period apart', offset(rows)),
                         ('every start', per_start(rows)),
                         ('(c) a lone robot', lone({'bullet': args.single_bullet, 'chrono': args.single_chrono,
                                                    'mujoco': args.single_mujoco}))):
        print(f'#### {title}\n')
        print('\n'.join(lines))
        print()
    return 0


if __name__ == '__main__':
    sys.exit(closed_pipe_safe(main)())
