"""Which assumed values of the feedback robot move the open-loop C2 lifetime (``FEEDBACK_ASSUMED``).

Each row changes one assumed ``RobotSpec`` field of the ``feedback`` preset (the others at their
defaults) and runs the P6 open-loop C2 trial (``p6.run_pair_trial``: the harvested start with the cited
noise, as ``smarticle-p6`` runs it) for the same seeds; the table gives
the mean lifetime (periods, censored at the end of the run) +- SE, the censored count and the final r.
Command line: ``smarticle-p6-sensitivity --seeds 10 --periods 200 --out out/feedback/sensitivity``.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from smarticle_common.facts import FEEDBACK

from .p6 import Condition, p6_noise, run_pair_trial

#: (field, value) of each row; None = the preset itself. Heights change with their clearance kept; the
#: servo speed stays high enough for a 90 deg amplitude's 180 deg stroke to end within a 0.4 s quarter.
VARIANTS: tuple[tuple[str, float] | None, ...] = (
    None,
    ('servo_torque', 0.15), ('servo_torque', 0.6),
    ('arm_mass', 0.010), ('arm_mass', 0.030),
    ('servo_speed', FEEDBACK.servo_speed * 0.8), ('servo_speed', FEEDBACK.servo_speed * 1.25),
    ('body_height', 0.050), ('arm_height', 0.025),
)


def label(variant: tuple[str, float] | None) -> str:
    """Row name of a variant."""
    if variant is None:
        return 'preset'
    name, value = variant
    default = getattr(FEEDBACK, name)
    return f'{name} {value:.4g} (preset {default:.4g})'


def run(seeds: Sequence[int], periods: float, alpha_max_deg: float = 90.0,
        variants: Sequence[tuple[str, float] | None] = VARIANTS) -> list[dict[str, object]]:
    """One row per variant: n, mean lifetime +- SE, censored, mean final r (BL)."""
    rows: list[dict[str, object]] = []
    for variant in variants:
        changes = {} if variant is None else {variant[0]: variant[1]}
        trials = [run_pair_trial(Condition(alpha_max_deg, False), s, periods, robot_changes=changes,
                                 noise=p6_noise('paper')) for s in seeds]
        life = np.array([t.lifetime_periods for t in trials], dtype=float)
        rows.append({'variant': label(variant), 'n': len(trials), 'mean_lifetime': float(life.mean()),
                     'se_lifetime': float(life.std(ddof=1) / math.sqrt(life.size)) if life.size > 1 else math.nan,
                     'censored': sum(t.censored for t in trials),
                     'final_r_bl': float(np.mean([t.r[-1] for t in trials])),
                     'trouble': sum(bool(t.trouble) for t in trials)})
        sys.stderr.write(f'{rows[-1]}\n')
    return rows


def format_rows(rows: Sequence[dict[str, object]], periods: float) -> str:
    """Markdown table of ``run`` rows."""
    out = [f'| assumed value | n | open-loop C2 lifetime mean +- SE (periods) | reached the end ({periods:g}) | '
           'final r (BL) | trouble |', '| --- | ---: | ---: | ---: | ---: | ---: |']
    for row in rows:
        out.append(f'| {row["variant"]} | {row["n"]} | {row["mean_lifetime"]:.1f} +- {row["se_lifetime"]:.1f} | '
                   f'{row["censored"]} | {row["final_r_bl"]:.2f} | {row["trouble"]} |')
    return '\n'.join(out)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of `smarticle-p6-sensitivity`: table on stdout, CSV in --out."""
    parser = argparse.ArgumentParser(prog='smarticle-p6-sensitivity', description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--periods', type=float, default=200.0)
    parser.add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    parser.add_argument('--out', default='out/feedback/sensitivity')
    args = parser.parse_args(argv)
    rows = run(range(args.seeds), args.periods, args.alpha)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with (out / 'p6_sensitivity.csv').open('w', newline='') as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    sys.stdout.write(format_rows(rows, args.periods) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
