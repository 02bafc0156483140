"""Dense 7-robot scenes in three engines (docs/chrono_reference.md, "Dense 7-robot scenes"): the same P1
starts run in Bullet (default), MuJoCo (default ``MujocoSettings``) and Chrono (1e-4 s, the authors' model),
and the figures and verdicts of the rules fixed in the doc.

Two steps:
  * ``run``: each seed's scene (``smarticle_sim.scenes.dense_scene``: 7 small robots densely packed, in phase,
    the dense kind's builder, so a seed gives the same start in every engine) in each engine asked for,
    one run after the other; each recording saved as ``ENGINE_seedN.npz`` (the run format) in ``--out``,
    a recording already there is not run again;
  * ``table``: reads those recordings and prints the per-scene figures, the per-engine rows with intervals
    and the verdicts (markdown).

Usage:
  nice -n 10 python tools/chrono_reference/dense_scenes.py run --engines chrono --seeds 0..7 --periods 60 \
      --out out/dense
  python tools/chrono_reference/dense_scenes.py table out/dense

Chrono needs the driver at .chrono/driver/smarticle_chrono or SMARTICLE_CHRONO_DRIVER
(tools/chrono_reference/build_chrono.sh); without it the Chrono runs are skipped with one line.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from smarticle_common.cli import seeds_argument, closed_pipe_safe
from smarticle_common.facts import R_BIND_BL
from smarticle_common.gait import GaitConfig
from smarticle_common.runs import Recording, load_npz
from smarticle_experiments.stats import fisher_p
from smarticle_sim.batch import run_trial
from smarticle_sim.chrono_reference import ChronoSettings, run_chrono
from smarticle_sim.mujoco_engine import MujocoSettings, run_mujoco
from smarticle_sim.scenes import Scene, dense_scene
from smarticle_sim.config_builder import build_config
from smarticle_sim.settings import SimConfig
from smarticle_tracking.gliders import GliderConfig, analyse_gliders

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cross_engine_table import FISHER_P, SPEED_FACTOR, boot, fmt, overlap, record_missing, wilson

ENGINES = ('bullet', 'mujoco', 'chrono')
#: The rules' figures (docs/chrono_reference.md, "Dense 7-robot scenes").
ROBOTS = 7
MIN_BOUND_PERIODS = 30        # a bound pair: bound (r < 1.6 BL in some frame of a period) this many periods in a row
ISOLATION_W = 2.0             # isolated: no third robot's centre within this of either robot's, in >= 90 % of them
STILL_W_PER_100 = 0.1         # two travels both under this are both still
#: Samples every 3 control ticks (0.05 s): a whole number of Chrono steps (the dense kind's 4 ticks is not).
SAMPLE_EVERY = 3
#: The versus pairs of the verdicts.
VERSUS = (('bullet', 'chrono'), ('mujoco', 'chrono'), ('bullet', 'mujoco'))


def scene_of(seed: int, config: SimConfig | None = None, alpha_max_deg: float = 90.0) -> tuple[Scene, GaitConfig]:
    """The seed's dense scene (P1's start: ``ROBOTS`` robots, in phase) and its gait."""
    config = config or build_config()
    gait = GaitConfig.from_degrees(alpha_max_deg, servo_speed=config.robot.servo_speed)
    return dense_scene(config.robot, gait, n=ROBOTS, seed=seed), gait


def run_engine(engine: str, seed: int, periods: float) -> Recording:
    """One dense scene in ``engine`` (ChronoUnavailable for chrono without the build)."""
    config = build_config()
    scene, _ = scene_of(seed, config)
    if engine == 'chrono':
        return run_chrono(config, scene, periods, SAMPLE_EVERY, ChronoSettings())
    if engine == 'mujoco':
        return run_mujoco(config, scene, periods, SAMPLE_EVERY, MujocoSettings())
    if engine == 'bullet':
        return run_trial(config, scene, periods, sample_every=SAMPLE_EVERY, record_contacts=True)
    raise ValueError(f'engine must be one of {", ".join(ENGINES)}, got {engine!r}')


def largest_cluster(xy: np.ndarray, link: float) -> int:
    """The size of the largest group of robots at positions ``xy`` (N, 2) linked by centre distances < ``link``."""
    n = len(xy)
    parent = list(range(n))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    for i in range(n):
        for j in range(i + 1, n):
            if d[i, j] < link:
                parent[root(i)] = root(j)
    sizes: dict[int, int] = {}
    for k in range(n):
        sizes[root(k)] = sizes.get(root(k), 0) + 1
    return max(sizes.values(), default=0)


def scene_figures(rec: Recording, period: float) -> dict[str, Any]:
    """A dense recording's figures by the rules: its bound pairs (>= 30 periods; isolated or in a cluster; travel
    per 100 periods of their bound run, W), the largest cluster at the end, trouble."""
    bl = rec.body_length
    cfg = GliderConfig(period=period, r_bind=R_BIND_BL * bl, min_periods=MIN_BOUND_PERIODS,
                       isolation_distance=ISOLATION_W * bl, body_length=bl, width=bl)
    analysis = analyse_gliders(rec.time, rec.poses, cfg)
    pairs = [{'i': g.i, 'j': g.j, 'start_period': g.start_period, 'periods': g.lifetime_periods,
              'isolated': bool(g.isolated), 'isolation': float(g.isolation),
              'travel_w': float(g.distance / bl),
              'travel_w_per_100': float(100.0 * g.distance / bl / g.lifetime_periods)}
             for g in analysis.gliders if g.lifetime_periods >= MIN_BOUND_PERIODS]
    per = max(1, round(period / float(np.median(np.diff(rec.time))))) if len(rec.time) > 1 else 1
    return {'trouble': rec.trouble, 'periods_run': (len(rec.time) - 1) // per, 'bound_pairs': pairs,
            'largest_cluster_end': largest_cluster(rec.poses[-1, :, :2], ISOLATION_W * bl),
            'peak_tilt_deg': rec.meta.get('peak_tilt_deg')}


def engine_summary(scenes: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One engine's row: counts and estimates over its scenes (figures of sound scenes; trouble of all)."""
    sound = [s for s in scenes if not s['trouble']]
    pairs = [p for s in sound for p in s['bound_pairs']]
    with_pairs = [s for s in sound if s['bound_pairs']]
    return {
        'scenes': len(scenes), 'sound': len(sound),
        'trouble': (len(scenes) - len(sound), len(scenes)),
        'with_bound': (len(with_pairs), len(sound)),
        'with_isolated': (sum(any(p['isolated'] for p in s['bound_pairs']) for s in sound), len(sound)),
        'isolated_pairs': (sum(p['isolated'] for p in pairs), len(pairs)),
        'bound_per_scene': boot([len(s['bound_pairs']) for s in sound]),
        'largest_cluster': boot([s['largest_cluster_end'] for s in sound]),
        'travel': boot([float(np.mean([p['travel_w_per_100'] for p in s['bound_pairs']])) for s in with_pairs]),
        'travel_range': ((min(p['travel_w_per_100'] for p in pairs), max(p['travel_w_per_100'] for p in pairs))
                         if pairs else None),
    }


def share_verdict(a: tuple[int, int], b: tuple[int, int]) -> str:
    """Fisher's exact test on two shares (k, n): 'agree (p = ..)' or 'differ (p = ..)'."""
    if a[1] == 0 or b[1] == 0:
        return 'not decided (no scenes)'
    p = fisher_p(a, b)
    return f'{"agree" if p >= FISHER_P else "differ"} (p = {p:.2g})'


def mean_verdict(a: tuple[float, float, float], b: tuple[float, float, float]) -> str:
    """Two bootstrap intervals of a mean: 'agree (overlap)' or 'differ (apart)'."""
    if not all(math.isfinite(v) for v in (*a, *b)):
        return 'not decided (fewer than 2 scenes)'
    return 'agree (overlap)' if overlap(a, b) else 'differ (apart)'


def travel_verdict(a: Mapping[str, Any], b: Mapping[str, Any]) -> str:
    """Bound pairs' travel: within a factor of 2, or both still (< 0.1 W per 100 periods)."""
    if a['with_bound'][0] < 2 or b['with_bound'][0] < 2:
        return 'not decided (fewer than 2 scenes with a bound pair)'
    va, vb = a['travel'][0], b['travel'][0]
    if va < STILL_W_PER_100 and vb < STILL_W_PER_100:
        return 'agree (both still)'
    ratio = va / vb if vb > 0 else math.inf
    return f'{"agree" if 1 / SPEED_FACTOR <= ratio <= SPEED_FACTOR else "differ"} (x {ratio:.2f})'


def share_text(kn: tuple[int, int]) -> str:
    """``k/n = p % [lo, hi]`` (Wilson), or ``0/0``."""
    k, n = kn
    return f'{k}/{n} = {fmt(wilson(k, n), share=True)}' if n else '0/0'


ROWS: tuple[tuple[str, str, str], ...] = (
    ('scenes with a bound pair (>= 30 periods)', 'with_bound', 'share'),
    ('bound pairs that are isolated', 'isolated_pairs', 'share'),
    ('scenes with an isolated bound pair', 'with_isolated', 'share'),
    ('bound pairs per scene', 'bound_per_scene', 'mean'),
    ('largest cluster at the end (robots)', 'largest_cluster', 'mean'),
    ("bound pairs' travel per 100 periods (W; scene means)", 'travel', 'travel'),
    ('scenes with trouble (tipped or non-finite)', 'trouble', 'share'),
)


def table(summaries: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """The per-engine rows with the verdicts against Chrono (and Bullet against MuJoCo)."""
    present = [e for e in ENGINES if e in summaries]
    versus = [(a, b) for a, b in VERSUS if a in summaries and b in summaries]
    lines = ['| row | ' + ' | '.join(present) + ' | ' + ' | '.join(f'{a} vs {b}' for a, b in versus) + ' |',
             '| --- |' + ' --- |' * (len(present) + len(versus))]
    for title, key, how in ROWS:
        cells = []
        for e in present:
            value = summaries[e][key]
            cells.append(share_text(value) if how == 'share' else fmt(value))
        verdicts = []
        for a, b in versus:
            sa, sb = summaries[a], summaries[b]
            if how == 'share':
                verdicts.append(share_verdict(sa[key], sb[key]))
            elif how == 'mean':
                verdicts.append(mean_verdict(sa[key], sb[key]))
            else:
                verdicts.append(travel_verdict(sa, sb))
        lines.append(f'| {title} | ' + ' | '.join(cells) + ' | ' + ' | '.join(f'**{v}**' for v in verdicts) + ' |')
    return lines


def scene_lines(figures: Mapping[tuple[str, int], Mapping[str, Any]]) -> list[str]:
    """Every scene: per engine, bound pairs (periods, isolated or cluster, travel per 100), largest cluster, trouble."""
    present = [e for e in ENGINES if any(k[0] == e for k in figures)]
    lines = ['| seed | ' + ' | '.join(f'{e}: bound pairs (periods, I/C, W per 100); largest cluster' for e in present)
             + ' |', '| ---: |' + ' --- |' * len(present)]
    for seed in sorted({k[1] for k in figures}):
        cells = []
        for e in present:
            f = figures.get((e, seed))
            if f is None:
                cells.append('-')
                continue
            pairs = ', '.join(f'{p["i"]}-{p["j"]} ({p["periods"]}, {"I" if p["isolated"] else "C"}, '
                              f'{p["travel_w_per_100"]:.2g})' for p in f['bound_pairs']) or 'none'
            trouble = f'; trouble at period {f["periods_run"]}: {f["trouble"]}' if f['trouble'] else ''
            cells.append(f'{pairs}; {f["largest_cluster_end"]}{trouble}')
        lines.append(f'| {seed} | ' + ' | '.join(cells) + ' |')
    return lines


def read_folder(folder: Path) -> dict[tuple[str, int], dict[str, Any]]:
    """The figures of every ``ENGINE_seedN.npz`` in ``folder``, by (engine, seed)."""
    out: dict[tuple[str, int], dict[str, Any]] = {}
    for path in sorted(folder.glob('*_seed*.npz')):
        engine, _, seed = path.stem.partition('_seed')
        if engine not in ENGINES:
            continue
        rec = load_npz(path)
        out[(engine, int(seed))] = scene_figures(rec, float(rec.meta.get('period') or scene_period_default()))
    return out


def scene_period_default() -> float:
    """The 90 deg gait's period (s), for a recording whose meta does not carry it."""
    return scene_of(0)[1].period


def common(figures: Mapping[tuple[str, int], dict[str, Any]]) -> dict[tuple[str, int], dict[str, Any]]:
    """The figures of the seeds run in every engine present (the rules' scene set)."""
    present = {k[0] for k in figures}
    seeds = set.intersection(*({k[1] for k in figures if k[0] == e} for e in present)) if present else set()
    return {k: v for k, v in figures.items() if k[1] in seeds}


def main() -> int:
    """``run`` or ``table``."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='command', required=True)
    run = sub.add_parser('run', help='run the scenes, one recording per engine and seed')
    run.add_argument('--engines', nargs='+', choices=ENGINES, default=list(ENGINES))
    run.add_argument('--seeds', type=seeds_argument, default=list(range(8)), help='scene seeds (7, 0..7, 0,3)')
    run.add_argument('--periods', type=float, default=60.0)
    run.add_argument('--out', type=Path, required=True, help='folder of the recordings')
    tab = sub.add_parser('table', help='the figures and verdicts of the recordings in a folder')
    tab.add_argument('folder', type=Path)
    args = parser.parse_args()
    if args.command == 'run':
        record_missing(args.out, [(seed, seed) for seed in args.seeds], args.engines,
                       lambda engine, seed: run_engine(engine, seed, args.periods))
        return 0
    figures = common(read_folder(args.folder))
    if not figures:
        print(f'no recordings in {args.folder}', file=sys.stderr)
        return 1
    summaries = {e: engine_summary([f for k, f in sorted(figures.items()) if k[0] == e])
                 for e in ENGINES if any(k[0] == e for k in figures)}
    print('#### Dense scenes, per engine\n')
    print('\n'.join(table(summaries)))
    print('\n#### Dense scenes, every scene\n')
    print('\n'.join(scene_lines(figures)))
    for e, s in summaries.items():
        if s['travel_range']:
            print(f'\n{e}: bound pairs travel {s["travel_range"][0]:.2g}-{s["travel_range"][1]:.2g} W per 100 periods')
    return 0


if __name__ == '__main__':
    sys.exit(closed_pipe_safe(main)())
