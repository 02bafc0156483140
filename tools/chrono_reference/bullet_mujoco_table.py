"""Bullet against MuJoCo (docs/chrono_reference.md, "Bullet against MuJoCo: P7, P6 and P1"): the rows of the
rules fixed in the doc, read from the stores the runs wrote; it runs nothing.

Each row reads the summary tables of its two shipped specs (``summary-xengine_<row>_<engine>.parquet`` in the
store ``xengine_<row>``), one per engine, and applies the row's rule:

  * P7 drift: per amplitude, the mean drift per cycle of each engine; agree if within a factor of 2 of each
    other, or both below 54 um per cycle; the row agrees if every amplitude does;
  * P6 open loop against feedback: per engine and condition the mean lifetime and the share censored; per
    engine the feedback's effect (mean with feedback minus open loop); the effect agrees if both intervals
    exclude 0 with the same sign or both include it; the lifetimes agree per condition if the intervals overlap;
    not decided for an engine whose feedback trials have no halt;
  * P1 reduced: per engine the share of positive trials and the mean bound pairs per trial; the share agrees if
    Fisher's exact test gives p >= 0.05, the bound pairs if the intervals overlap.

Trials that ended in sim trouble are left out and counted; a row with more than 10 % of an engine's trials in
trouble is not decided. Intervals: 95 % Wilson for shares, 95 % percentile bootstrap for means and differences
(10 000 resamples, numpy seed 0, each condition resampled apart).

Usage:
  python tools/chrono_reference/bullet_mujoco_table.py --store out/experiments
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from smarticle_common.cli import closed_pipe_safe
from smarticle_experiments.stats import fisher_p, wilson

ENGINES = ('bullet', 'mujoco')
#: Both drifts below this (um per cycle: 0.1 W per 100 periods of the small robot) agree whatever their ratio.
STILL_UM = 54.0
#: More than this share of an engine's trials in sim trouble leaves a row undecided.
TROUBLE_LIMIT = 0.10
RESAMPLES, SEED = 10_000, 0


def bootstrap_mean(values: Sequence[float]) -> tuple[float, float, float]:
    """Mean and its 95 % percentile bootstrap interval (10 000 resamples, numpy seed 0)."""
    x = np.asarray(values, dtype=float)
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    rng = np.random.default_rng(SEED)
    means = x[rng.integers(0, len(x), size=(RESAMPLES, len(x)))].mean(axis=1)
    return float(x.mean()), float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))


def bootstrap_difference(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float]:
    """Mean of ``b`` minus mean of ``a`` and its 95 % percentile bootstrap interval, each resampled apart."""
    x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(x) == 0 or len(y) == 0:
        return math.nan, math.nan, math.nan
    rng = np.random.default_rng(SEED)
    mx = x[rng.integers(0, len(x), size=(RESAMPLES, len(x)))].mean(axis=1)
    my = y[rng.integers(0, len(y), size=(RESAMPLES, len(y)))].mean(axis=1)
    d = my - mx
    return float(y.mean() - x.mean()), float(np.percentile(d, 2.5)), float(np.percentile(d, 97.5))


def text(estimate: tuple[float, float, float], fmt: str = '.1f') -> str:
    """``mean [low, high]``."""
    m, lo, hi = estimate
    return f'{m:{fmt}} [{lo:{fmt}}, {hi:{fmt}}]'


def overlap(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
    """True if the two intervals overlap."""
    return a[1] <= b[2] and b[1] <= a[2]


def summary(store: Path, row: str, engine: str) -> pd.DataFrame | None:
    """The summary table of ``xengine_<row>_<engine>``, or None if it has not run."""
    path = store / f'xengine_{row}' / f'summary-xengine_{row}_{engine}.parquet'
    return pd.read_parquet(path) if path.is_file() else None


def usable(frame: pd.DataFrame) -> tuple[pd.DataFrame, int, int]:
    """The trials that ran without trouble, the number in trouble, the number of trials."""
    ok = frame[frame['status'] == 'ok']
    trouble = ok['trouble'].fillna('').astype(str).str.len() > 0 if 'trouble' in ok else pd.Series(False, ok.index)
    return ok[~trouble], int(trouble.sum()), len(frame)


def decided(counts: dict[str, tuple[int, int]]) -> str:
    """'' if every engine's trouble share is within the limit, else the reason the row is not decided."""
    over = [f'{e}: {k} of {n} in trouble' for e, (k, n) in counts.items() if n and k / n > TROUBLE_LIMIT]
    return '; '.join(over)


def p7_rows(store: Path) -> list[str]:
    """The P7 drift row, per amplitude."""
    frames = {e: summary(store, 'p7', e) for e in ENGINES}
    if any(f is None for f in frames.values()):
        return ['| P7 drift | not run | | |']
    used, counts = {}, {}
    for e, f in frames.items():
        assert f is not None
        used[e], k, n = usable(f)
        counts[e] = (k, n)
    lines, verdicts = [], []
    for alpha in sorted(set(used['bullet']['grid.alpha_max_deg']), reverse=True):
        drifts = {e: used[e].loc[used[e]['grid.alpha_max_deg'] == alpha, 'drift_um_per_cycle'] for e in ENGINES}
        est = {e: bootstrap_mean(drifts[e]) for e in ENGINES}
        b, m = est['bullet'][0], est['mujoco'][0]
        ratio = m / b if b else math.inf
        agree = (max(b, m) <= 2 * min(b, m)) or (b < STILL_UM and m < STILL_UM)
        verdicts.append(agree)
        lines.append(f'| P7 drift per cycle at {alpha:g} deg (um), {len(drifts["bullet"])} and '
                     f'{len(drifts["mujoco"])} seeds | '
                     f'{text(est["bullet"])} | {text(est["mujoco"])} | '
                     f'{"agree" if agree else "disagree"} (x {ratio:.2f}) |')
    why = decided(counts)
    verdict = f'not decided ({why})' if why else ('agrees' if all(verdicts) else 'disagrees')
    lines.append(f'| P7 drift, the row | | | **{verdict}** ({sum(verdicts)} of {len(verdicts)} amplitudes agree) |')
    return lines


def p6_rows(store: Path) -> list[str]:
    """The P6 row: lifetimes per condition and the feedback's effect per engine."""
    frames = {e: summary(store, 'p6', e) for e in ENGINES}
    if any(f is None for f in frames.values()):
        return ['| P6 open loop against feedback | not run | | |']
    life, censored, halts, effect, counts = {}, {}, {}, {}, {}
    for e, f in frames.items():
        assert f is not None
        ok, k, n = usable(f)
        counts[e] = (k, n)
        for fb in (False, True):
            sel = ok[ok['grid.feedback'] == fb]
            life[e, fb] = bootstrap_mean(sel['lifetime_periods'])
            censored[e, fb] = (int(sel['censored'].sum()), len(sel))
            if fb:
                halts[e] = int(sel['halts'].sum())
        effect[e] = bootstrap_difference(ok.loc[ok['grid.feedback'] == False, 'lifetime_periods'],  # noqa: E712
                                         ok.loc[ok['grid.feedback'] == True, 'lifetime_periods'])  # noqa: E712
    lines = []
    for fb, name in ((False, 'open loop'), (True, 'feedback')):
        agree = overlap(life['bullet', fb], life['mujoco', fb])
        shares = ', '.join(f'{e} censored {censored[e, fb][0]}/{censored[e, fb][1]} '
                           f'({wilson(*censored[e, fb]).text(".2f")})' for e in ENGINES)
        lines.append(f'| P6 mean lifetime, {name} (periods of 200) | {text(life["bullet", fb])} | '
                     f'{text(life["mujoco", fb])} | {"agree" if agree else "disagree"} ({shares}) |')

    def sign(est: tuple[float, float, float]) -> int:
        return 0 if est[1] <= 0 <= est[2] else (1 if est[1] > 0 else -1)

    why = decided(counts)
    no_halts = [e for e in ENGINES if halts[e] == 0]
    if why or no_halts:
        verdict = 'not decided (' + '; '.join([why] * bool(why) + [f'{e}: no halt' for e in no_halts]) + ')'
    else:
        verdict = 'agrees' if sign(effect['bullet']) == sign(effect['mujoco']) else 'disagrees'
    lines.append(f'| P6 feedback minus open loop (periods) | {text(effect["bullet"])}, {halts["bullet"]} halts | '
                 f'{text(effect["mujoco"])}, {halts["mujoco"]} halts | **effect {verdict}** |')
    return lines


def p1_rows(store: Path) -> list[str]:
    """The P1 reduced row: positive share and bound pairs per trial."""
    frames = {e: summary(store, 'p1', e) for e in ENGINES}
    if any(f is None for f in frames.values()):
        return ['| P1 reduced | not run | | |']
    share, pairs, counts = {}, {}, {}
    for e, f in frames.items():
        assert f is not None
        ok, k, n = usable(f)
        counts[e] = (k, n)
        share[e] = (int(ok['positive'].sum()), len(ok))
        pairs[e] = bootstrap_mean(ok['n_gliders'])
    p = fisher_p(share['bullet'], share['mujoco'])
    why = decided(counts)
    share_verdict = f'not decided ({why})' if why else ('agrees' if p >= 0.05 else 'disagrees')
    pairs_verdict = 'agree' if overlap(pairs['bullet'], pairs['mujoco']) else 'disagree'
    return [f'| P1 reduced, trials with a pair bound >= 100 periods | {share["bullet"][0]}/{share["bullet"][1]} '
            f'({wilson(*share["bullet"]).text(".2f")}) | {share["mujoco"][0]}/{share["mujoco"][1]} '
            f'({wilson(*share["mujoco"]).text(".2f")}) | **share {share_verdict}** (Fisher p = {p:.2f}) |',
            f'| P1 reduced, bound pairs per trial | {text(pairs["bullet"], ".2f")} | {text(pairs["mujoco"], ".2f")} '
            f'| {pairs_verdict} |']


@closed_pipe_safe
def main(argv: list[str] | None = None) -> int:
    """Print the table's rows from the stores."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--store', type=Path, default=Path('out/experiments'), help='the stores\' root')
    args = parser.parse_args(argv)
    if not args.store.is_dir():
        print(f'bullet_mujoco_table: no store folder {args.store}', file=sys.stderr)
        return 2
    print('| row | Bullet | MuJoCo | verdict |')
    print('| --- | --- | --- | --- |')
    for rows in (p7_rows, p6_rows, p1_rows):
        for line in rows(args.store):
            print(line)
    return 0


if __name__ == '__main__':
    sys.exit(main())
