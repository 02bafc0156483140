"""P6 in the authors' engine (docs/chrono_reference.md, "P6 in the authors' engine"): the feedback robot's held C2
pairs, open loop, in Chrono and in Bullet from the same at-rest starts, and whether they break.

The starts are the shipped held-C2 rows (``smarticle_experiments/config/p6_held_c2.csv``, the ``held`` start of
P6): one per harvest seed, that seed's earliest row (smallest period, then the pair i, j). Each robot starts at
the row's x, y and heading, the pair centred on the plate, at rest and flat, arms where the gait starts (the
rows sit at period boundaries of in-phase runs with velocities near 0, so both gaits start at phase 0, as
P6's ``held_scene`` starts them); the feedback robot at 90 deg, no feedback, no noise.

Two steps:
  * ``run``: each start in each engine asked for, one run after the other; ``ENGINE_seedN.npz`` (the run
    format) in ``--out``; a recording already there is not run again;
  * ``table``: the lifetime of each pair by P6's own rule (``smarticle_experiments.p6.pair_lifetime``: the bound
    run from period 0, bound = r < 1.6 BL in some frame of a period), the share broken by the end (Wilson)
    and Fisher's test between the engines (markdown).

Usage:
  nice -n 10 python tools/chrono_reference/p6_chrono.py run --engines chrono bullet --periods 100 --out out/p6
  python tools/chrono_reference/p6_chrono.py table out/p6

Chrono needs the driver at .chrono/driver/smarticle_chrono or SMARTICLE_CHRONO_DRIVER.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from smarticle_common.cli import closed_pipe_safe
from smarticle_common.gait import GaitConfig
from smarticle_common.pairs import one_pair
from smarticle_common.runs import Recording, load_npz
from smarticle_experiments.p6 import load_held_starts, pair_lifetime
from smarticle_experiments.stats import fisher_p
from smarticle_sim.batch import run_trial
from smarticle_sim.chrono_reference import ChronoSettings, at_rest_scene, run_chrono
from smarticle_sim.scenes import Scene, state_scene
from smarticle_sim.config_builder import build_config
from smarticle_sim.settings import SimConfig

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cross_engine_table import FISHER_P, fmt, record_missing, wilson

ENGINES = ('chrono', 'bullet')
PRESET = 'feedback'
ALPHA_MAX_DEG = 90.0
#: Samples every 3 control ticks (0.05 s), as P6's trials.
SAMPLE_EVERY = 3


def config_and_gait() -> tuple[SimConfig, GaitConfig]:
    """The feedback robot's default config and its 90 deg gait (phase 0)."""
    config = build_config(PRESET)
    return config, GaitConfig.from_degrees(ALPHA_MAX_DEG, servo_speed=config.robot.servo_speed)


def held_rows(samples: Sequence[Any] | None = None) -> list[Any]:
    """One held-C2 row per harvest seed (``C2Sample`` with a state): the seed's earliest row (smallest period,
    then the pair i, j), in ascending seed order."""
    samples = list(load_held_starts() if samples is None else samples)
    first: dict[int, Any] = {}
    for s in samples:
        if s.state is None:
            continue
        best = first.get(s.seed)
        if best is None or (s.period, s.i, s.j) < (best.period, best.i, best.j):
            first[s.seed] = s
    return [first[k] for k in sorted(first)]


def row_scene(sample: Any, gait: GaitConfig) -> tuple[Scene, float]:
    """The at-rest pair scene of a held-C2 row (both gaits at ``gait``'s phase) and the largest arm correction
    (rad) that put the arms where the gait starts."""
    scene = state_scene(sample.state, [gait, gait], name='held-c2-at-rest', seed=int(sample.seed))
    return at_rest_scene(scene)


def run_engine(engine: str, sample: Any, periods: float) -> Recording:
    """One held row in ``engine`` (ChronoUnavailable for chrono without the build)."""
    config, gait = config_and_gait()
    scene, _ = row_scene(sample, gait)
    if engine == 'chrono':
        return run_chrono(config, scene, periods, SAMPLE_EVERY, ChronoSettings())
    if engine == 'bullet':
        return run_trial(config, scene, periods, sample_every=SAMPLE_EVERY, record_contacts=True)
    raise ValueError(f'engine must be one of {", ".join(ENGINES)}, got {engine!r}')


def pair_outcome(rec: Recording, period: float, periods: float) -> dict[str, Any]:
    """A held pair's figures: lifetime (P6's rule), broken (ended before the run's end, without trouble),
    r and phi at the end, travel of the pair's centre per 100 periods (W)."""
    bl = rec.body_length
    lifetime, ongoing = pair_lifetime(rec.time, rec.poses, period, bl)
    per = max(1, round(period / float(np.median(np.diff(rec.time)))))
    run = (len(rec.time) - 1) // per
    com = rec.poses[:, :, :2].mean(axis=1) / bl
    travel = float(np.linalg.norm(com[run * per] - com[0])) if run else 0.0
    r_end = float(np.hypot(*(rec.poses[-1, 1, :2] - rec.poses[-1, 0, :2])) / bl)
    _, _, phi = one_pair(rec.poses[-1, 0], rec.poses[-1, 1])
    broken = not ongoing and lifetime < run and not rec.trouble
    return {'lifetime': lifetime, 'broken': broken, 'periods_run': run, 'trouble': rec.trouble,
            'r_end_bl': r_end, 'phi_end_deg': math.degrees(phi) % 360.0,
            'travel_w_per_100': 100.0 * travel / run if run else 0.0,
            'contact_periods_last_10': sum(bool(rec.contacts[q * per + 1:(q + 1) * per + 1, 0, 1].any())
                                           for q in range(max(0, run - 10), run)),
            'peak_overlap_mm': rec.meta.get('peak_overlap_mm')}


def engine_lines(outcomes: Mapping[tuple[str, int], Mapping[str, Any]], periods: float) -> list[str]:
    """Per engine: broken by the end (Wilson), the broken ones' lifetimes, Kaplan-Meier at 25/50/75 periods,
    Fisher between the engines."""
    lines = [f'| engine | starts | broken by period {periods:g} | lifetimes of the broken (periods) | '
             'still bound at 25 / 50 / 75 periods (Kaplan-Meier) | trouble | mean travel per 100 periods (W) |',
             '| --- | ---: | --- | --- | --- | ---: | ---: |']
    counts: dict[str, tuple[int, int]] = {}
    for engine in ENGINES:
        rows = [o for k, o in sorted(outcomes.items()) if k[0] == engine]
        if not rows:
            continue
        sound = [o for o in rows if not o['trouble']]
        k = sum(o['broken'] for o in sound)
        counts[engine] = (k, len(sound))
        km = ' / '.join(f'{kaplan_meier(sound, t):.2f}' for t in (25, 50, 75)) if sound else '-'
        lives = ', '.join(str(o['lifetime']) for o in sorted(sound, key=lambda o: o['lifetime']) if o['broken']) or '-'
        share = f'{k}/{len(sound)} = {fmt(wilson(k, len(sound)), share=True)}' if sound else '0/0'
        lines.append(f'| {engine} | {len(rows)} | {share} | {lives} | {km} | {len(rows) - len(sound)} | '
                     f'{np.mean([o["travel_w_per_100"] for o in sound]):.2g} |')
    if set(counts) == set(ENGINES) and all(n for _, n in counts.values()):
        p = fisher_p(counts['chrono'], counts['bullet'])
        lines += ['', f'- chrono vs bullet, broken share: Fisher p = {p:.2g}: '
                      f'**{"agree" if p >= FISHER_P else "differ"}**.']
    return lines


def kaplan_meier(rows: Sequence[Mapping[str, Any]], t: float) -> float:
    """The Kaplan-Meier estimate of still being bound after ``t`` periods (a broken pair's event at its lifetime;
    an unbroken one censored at its run's end)."""
    survival = 1.0
    for event in sorted({o['lifetime'] for o in rows if o['broken'] and o['lifetime'] <= t}):
        at_risk = sum(1 for o in rows if (o['lifetime'] if o['broken'] else o['periods_run']) >= event)
        dead = sum(1 for o in rows if o['broken'] and o['lifetime'] == event)
        survival *= 1.0 - dead / at_risk if at_risk else 1.0
    return survival


def start_lines(outcomes: Mapping[tuple[str, int], Mapping[str, Any]], rows: Sequence[Any]) -> list[str]:
    """Every start: the row, then per engine lifetime (broken or reached the end), r and phi at the end, travel."""
    lines = ['| harvest seed | row (pair, period, r BL, theta, phi deg) | '
             + ' | '.join(f'{e}: lifetime; r_end / phi_end; W per 100; contact periods of the last 10' for e in ENGINES)
             + ' |', '| ---: | --- |' + ' --- |' * len(ENGINES)]
    for s in rows:
        cells = []
        for e in ENGINES:
            o = outcomes.get((e, int(s.seed)))
            if o is None:
                cells.append('-')
                continue
            life = f'{o["lifetime"]} (broke)' if o['broken'] else f'{o["lifetime"]} (to the end)'
            if o['trouble']:
                life = f'trouble at {o["periods_run"]}: {o["trouble"]}'
            cells.append(f'{life}; {o["r_end_bl"]:.2f} / {o["phi_end_deg"]:.0f}; {o["travel_w_per_100"]:.2g}; '
                         f'{o["contact_periods_last_10"]}')
        if any(c != '-' for c in cells):
            lines.append(f'| {s.seed} | {s.i}-{s.j}, {s.period}, {s.r_bl:.3f}, {s.theta_deg:.1f}, {s.phi_deg:.1f} | '
                         + ' | '.join(cells) + ' |')
    return lines


def main() -> int:
    """``run`` or ``table``."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='run the held starts, one recording per engine and start')
    run.add_argument('--engines', nargs='+', choices=ENGINES, default=list(ENGINES))
    run.add_argument('--periods', type=float, default=100.0)
    run.add_argument('--count', type=int, help='only the first COUNT starts (ascending harvest seed)')
    run.add_argument('--out', type=Path, required=True, help='folder of the recordings')
    tab = sub.add_parser('table', help='the figures of the recordings in a folder')
    tab.add_argument('folder', type=Path)
    args = parser.parse_args()
    rows = held_rows()
    _, gait = config_and_gait()
    if args.command == 'run':
        record_missing(args.out, [(s.seed, s) for s in rows[:args.count]], args.engines,
                       lambda engine, start: run_engine(engine, start, args.periods))
        return 0
    outcomes = {}
    periods = 0.0
    for path in sorted(args.folder.glob('*_seed*.npz')):
        engine, _, seed = path.stem.partition('_seed')
        if engine in ENGINES:
            rec = load_npz(path)
            periods = max(periods, float(rec.meta.get('periods') or 0.0))
            outcomes[(engine, int(seed))] = pair_outcome(rec, gait.period, periods)
    seeds = set.intersection(*({k[1] for k in outcomes if k[0] == e} for e in ENGINES)) if outcomes else set()
    outcomes = {k: v for k, v in outcomes.items() if k[1] in seeds}
    if not outcomes:
        print(f'no start run in both engines in {args.folder}', file=sys.stderr)
        return 1
    corrections = [row_scene(s, gait)[1] for s in rows if s.seed in seeds]
    print('\n'.join(engine_lines(outcomes, periods)))
    print()
    print('\n'.join(start_lines(outcomes, rows)))
    print(f'\nlargest arm correction to the gait start: {max(corrections):.2g} rad')
    return 0


if __name__ == '__main__':
    sys.exit(closed_pipe_safe(main)())
