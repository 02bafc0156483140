"""Run time against error of the smarticle simulation: physics time step x solver iterations.

For every (rate, solver iterations) setting, from the same seeded starts:

* a bound pair (C1-like: phi = 180 deg) runs ``--pair-periods`` gait periods; error = mean over the two
  robots of the body-centre position distance to the reference run after 1 and after 10 periods (BL),
  and |mean r - mean r_ref| of the pair separation r over the whole run (BL);
* a single robot runs ``--single-periods`` periods; drift per cycle = net displacement / periods (um);
  error = |drift - drift_ref| / drift_ref;
* wall time per simulated second of the pair run (Runner ticks, poses read at 20 Hz; best of two runs,
  which must give bit-identical trajectories: column ``repeatable``).

Full mode also runs the single robot at ``--drift-rates`` (default 7680 Hz) to show whether its drift
per cycle has converged.

The reference is the finest setting of the sweep (highest rate, most solver iterations). Prints a
Markdown table, writes ``out/benchmarks/sim_accuracy.csv`` and ``sim_accuracy.png`` (error against wall
time, one curve per solver-iteration count) and names the knee setting (rule printed with it).

    .venv/bin/python tests/benchmarks/bench_sim_accuracy.py --quick
    .venv/bin/python tests/benchmarks/bench_sim_accuracy.py
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import Progress, add_clock_argument, clock_of, figure, machine_line, markdown_table, out_path, write_csv
from smarticle_common.gait import GaitConfig
from smarticle_sim.errors import SimTrouble
from smarticle_sim.scenes import RobotPlacement, Scene, pair_scene
from smarticle_sim.settings import SimConfig
from smarticle_sim.runner import Runner

#: Tolerances of the knee rule (see ``knee``).
TOL_POS10_BL = 0.05
TOL_DRIFT_REL = 0.10
TOL_R_BL = 0.02


def run_pair(config: SimConfig, scene: Scene, periods: int, sample_every: int,
             clock: Callable[[], float] = time.perf_counter) -> dict[str, object]:
    """Run the pair; return xy at 1 and 10 periods, r samples, wall seconds per sim second, trouble."""
    bl = config.robot.body_length
    period = scene.robots[0].gait.period  # type: ignore[union-attr]
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        ticks = world.ticks_for(periods * period)
        per = world.ticks_for(period)
        marks = {per: 'xy1', min(10, periods) * per: 'xy10'}
        out: dict[str, object] = {'trouble': ''}
        rs = []
        run.gaits.start(0.0)
        start = clock()
        try:
            for i in range(1, ticks + 1):
                run.tick()
                if i % sample_every == 0 or i in marks:
                    poses = world.poses()
                    rs.append(math.hypot(*(poses[1, :2] - poses[0, :2])) / bl)
                    if i in marks:
                        out[marks[i]] = poses[:, :2].copy()
        except SimTrouble as trouble:
            out['trouble'] = str(trouble)
        wall = clock() - start
        out['wall_per_sim_s'] = wall / max(world.time, 1e-12)
        out['r'] = np.array(rs)
        return out


def run_single(config: SimConfig, gait: GaitConfig, periods: int) -> tuple[float, str]:
    """Net drift per gait cycle (m) of one robot alone, and the trouble message ('' if none)."""
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, math.pi / 2.0, a, a, gait),), name='single')
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        start = world.poses()[0, :2].copy()
        run.gaits.start(0.0)
        try:
            run.run(world.ticks_for(periods * gait.period))
        except SimTrouble as trouble:
            return math.nan, str(trouble)
        return float(np.linalg.norm(world.poses()[0, :2] - start)) / periods, ''


def knee(rows: list[dict[str, object]], with_drift: bool) -> tuple[dict[str, object] | None, str]:
    """The cheapest non-reference setting within every tolerance, and the rule as text."""
    rule = (f'the cheapest setting (least wall time per simulated second) with position error after '
            f'10 periods <= {TOL_POS10_BL} BL and mean-r error <= {TOL_R_BL} BL'
            + (f' and drift error <= {TOL_DRIFT_REL:.0%}' if with_drift else ''))
    ok = [r for r in rows if not r['reference'] and not r['trouble']
          and float(r['pos10_bl']) <= TOL_POS10_BL and float(r['r_err_bl']) <= TOL_R_BL
          and (not with_drift or float(r['drift_rel_err']) <= TOL_DRIFT_REL)]
    best = min(ok, key=lambda r: float(r['wall_per_sim_s'])) if ok else None
    return best, rule


def main(argv: list[str] | None = None) -> int:
    """Sweep, print the table, write CSV and PNG."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true',
                        help='rates 240-1920 Hz, iterations 5/10/50, 10 pair and 5 single periods (~1 min)')
    parser.add_argument('--rates', type=float, nargs='+', default=None,
                        help='physics rates in Hz (default 240 480 960 1920 3840)')
    parser.add_argument('--iterations', type=int, nargs='+', default=None,
                        help='solver iterations (default 5 10 20 50)')
    parser.add_argument('--pair-periods', type=int, default=None, help='pair run length (default 20)')
    parser.add_argument('--single-periods', type=int, default=None, help='single robot run (default 10)')
    parser.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude (deg)')
    parser.add_argument('--pair', type=float, nargs=5, default=(1.4, 60.0, 180.0, 0.0, 0.5),
                        metavar=('R', 'THETA', 'PHI', 'P1', 'P2'),
                        help='pair start: r (BL), theta, phi (deg), gait phases (default 1.4 60 180 0 0.5)')
    parser.add_argument('--drift-rates', type=float, nargs='*', default=None,
                        help='extra rates (Hz) for a single-robot drift convergence check (default 7680; '
                             'quick: none)')
    parser.add_argument('--out-dir', type=Path, default=None, help='output folder (default out/benchmarks)')
    parser.add_argument('--no-progress', action='store_true')
    add_clock_argument(parser)
    args = parser.parse_args(argv)
    rates = args.rates or ([240.0, 480.0, 960.0, 1920.0] if args.quick else [240.0, 480.0, 960.0, 1920.0, 3840.0])
    iterations = args.iterations or ([5, 10, 50] if args.quick else [5, 10, 20, 50])
    pair_periods = args.pair_periods or (10 if args.quick else 20)
    single_periods = args.single_periods or (5 if args.quick else 10)
    extra_rates = args.drift_rates if args.drift_rates is not None else ([] if args.quick else [7680.0])
    # one control tick for every setting, a whole number of steps at every rate: 1/60 s if possible
    tick = 1.0 / 60.0 if all(abs(r / 60.0 - round(r / 60.0)) < 1e-9 for r in rates) else 0.05
    base = SimConfig()
    clock = clock_of(args.clock)
    default_rate, default_iters = 1.0 / base.physics.time_step, base.physics.solver_iterations
    gait = GaitConfig.from_degrees(args.alpha_max, servo_speed=base.robot.servo_speed)
    r0, th, ph, p1, p2 = args.pair
    scene = pair_scene(base.robot, gait, r0, math.radians(th), math.radians(ph), (p1, p2))
    sample_every = max(1, round(0.05 / tick))
    settings = [(rate, it) for it in sorted(iterations) for rate in sorted(rates)]
    ref_key = (max(rates), max(iterations))
    print(f'# run time against error: pair r={r0} theta={th} phi={ph} phases {p1} {p2}, alpha_max '
          f'{args.alpha_max:g} deg, {pair_periods} pair periods, {single_periods} single periods, control '
          f'tick {tick:.4g} s, {args.clock} time; {machine_line()}')
    progress = Progress(len(settings), 'accuracy', not args.no_progress)
    raw: dict[tuple[float, int], dict[str, object]] = {}
    # reference first, so a crash there shows at once
    for key in [ref_key] + [s for s in settings if s != ref_key]:
        rate, it = key
        config = base.with_physics(time_step=1.0 / rate, control_tick=tick, solver_iterations=it)
        pair = run_pair(config, scene, pair_periods, sample_every, clock)
        again = run_pair(config, scene, pair_periods, sample_every, clock)   # timing: best of two
        pair['wall_per_sim_s'] = min(float(pair['wall_per_sim_s']), float(again['wall_per_sim_s']))  # type: ignore[arg-type]
        pair['repeatable'] = bool(np.array_equal(pair['r'], again['r']))  # type: ignore[arg-type]
        drift, single_trouble = run_single(config, gait, single_periods)
        pair['drift'] = drift
        pair['trouble'] = '; '.join(t for t in (str(pair['trouble']), single_trouble) if t)
        raw[key] = pair
        progress.step(f'{rate:g} Hz, {it} iterations: {1.0 / float(pair["wall_per_sim_s"]):.1f}x real time')
    ref = raw[ref_key]
    bl = base.robot.body_length
    rows: list[dict[str, object]] = []
    for key in settings:
        rate, it = key
        res = raw[key]

        def pos_err(mark: str, res: dict[str, object] = res) -> float:
            if mark not in res or mark not in ref:
                return math.nan
            return float(np.linalg.norm(res[mark] - ref[mark], axis=1).mean()) / bl  # type: ignore[operator]

        r_mean = float(np.mean(res['r'])) if len(res['r']) else math.nan  # type: ignore[arg-type]
        r_ref = float(np.mean(ref['r']))  # type: ignore[arg-type]
        drift, drift_ref = float(res['drift']), float(ref['drift'])  # type: ignore[arg-type]
        rows.append({
            'rate_hz': rate, 'time_step_s': 1.0 / rate, 'solver_iterations': it,
            'reference': key == ref_key, 'default': abs(rate - default_rate) < 1e-6 and it == default_iters,
            'wall_per_sim_s': float(res['wall_per_sim_s']),  # type: ignore[arg-type]
            'real_time_factor': 1.0 / float(res['wall_per_sim_s']),  # type: ignore[arg-type]
            'pos1_bl': pos_err('xy1'), 'pos10_bl': pos_err('xy10'),
            'r_mean_bl': r_mean, 'r_err_bl': abs(r_mean - r_ref),
            'drift_um_per_cycle': drift * 1e6, 'drift_rel_err': abs(drift - drift_ref) / drift_ref
            if drift_ref > 0 else math.nan,
            'repeatable': res['repeatable'], 'trouble': str(res['trouble']),
        })
    for row in rows:
        row['setting'] = (f'{row["rate_hz"]:g} Hz / {row["solver_iterations"]}'
                          + (' (ref)' if row['reference'] else '') + (' (default)' if row['default'] else ''))
    columns = [('setting', 'rate / iterations', ''), ('real_time_factor', 'x real time (pair)', '.1f'),
               ('wall_per_sim_s', 'wall s per sim s', '.4f'), ('pos1_bl', 'pos err 1 T (BL)', '.4f'),
               ('pos10_bl', 'pos err 10 T (BL)', '.4f'), ('r_mean_bl', 'mean r (BL)', '.3f'),
               ('r_err_bl', 'r err (BL)', '.4f'), ('drift_um_per_cycle', 'drift (um/cycle)', '.1f'),
               ('drift_rel_err', 'drift err', '.1%'), ('repeatable', 'repeatable', ''),
               ('trouble', 'trouble', '')]
    print(markdown_table(rows, columns))
    csv_path = write_csv(out_path('sim_accuracy.csv', args.out_dir), rows)
    png_path = plot(rows, out_path('sim_accuracy.png', args.out_dir))
    for with_drift, name in ((False, 'pair knee'), (True, 'knee with drift')):
        best, rule = knee(rows, with_drift)
        pick = 'none' if best is None else \
            f'{best["setting"]} ({float(best["real_time_factor"]):.1f}x real time for the pair)'
        print(f'{name}: {pick}  [rule: {rule}]')
    default = next((r for r in rows if r['default']), None)
    if default is not None:
        print(f'default {default["setting"]}: pos err 10 T {float(default["pos10_bl"]):.4f} BL, r err '
              f'{float(default["r_err_bl"]):.4f} BL, drift err {float(default["drift_rel_err"]):.0%}')
    if extra_rates:
        drift_rows = [{'rate_hz': r['rate_hz'], 'solver_iterations': r['solver_iterations'],
                       'drift_um_per_cycle': r['drift_um_per_cycle']}
                      for r in rows if r['solver_iterations'] == max(iterations)]
        for rate in extra_rates:
            config = base.with_physics(time_step=1.0 / rate, control_tick=tick,
                                       solver_iterations=max(iterations))
            drift, _ = run_single(config, gait, single_periods)
            drift_rows.append({'rate_hz': rate, 'solver_iterations': max(iterations),
                               'drift_um_per_cycle': drift * 1e6})
        print(f'\nsingle-robot drift convergence ({single_periods} periods, {max(iterations)} iterations):')
        print(markdown_table(drift_rows, [('rate_hz', 'rate (Hz)', 'g'),
                                          ('drift_um_per_cycle', 'drift (um/cycle)', '.1f')]))
        write_csv(out_path('sim_accuracy_drift.csv', args.out_dir), drift_rows)
    print(f'wrote {csv_path} and {png_path}')
    return 0


def plot(rows: list[dict[str, object]], path: Path) -> Path:
    """Errors against wall time per simulated second, one curve per solver-iteration count."""
    fig = figure(11.0, 4.2)
    panels = [('pos10_bl', 'position error after 10 periods (BL)'), ('drift_rel_err', 'drift error (relative)'),
              ('r_err_bl', '|mean r - ref| (BL)')]
    for idx, (key, label) in enumerate(panels):
        ax = fig.add_subplot(1, 3, idx + 1)
        for it in sorted({int(r['solver_iterations']) for r in rows}):  # type: ignore[call-overload]
            pts = [(float(r['wall_per_sim_s']), float(r[key]), float(r['rate_hz']))  # type: ignore[arg-type]
                   for r in rows if r['solver_iterations'] == it and not r['reference']]
            pts = [p for p in pts if p[1] == p[1]]
            if not pts:
                continue
            pts.sort()
            line, = ax.plot([p[0] for p in pts], [max(p[1], 1e-6) for p in pts], 'o-', label=f'{it} iter.')
            for x, y, rate in pts:
                ax.annotate(f'{rate:g}', (x, max(y, 1e-6)), fontsize=6, color=line.get_color(),
                            xytext=(2, 2), textcoords='offset points')
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_xlabel('time (s) per simulated s')
        ax.set_title(label, fontsize=9)
        ax.grid(True, which='both', lw=0.3)
        if idx == 0:
            ax.legend(fontsize=7)
    fig.suptitle('error against run time (labels: physics rate in Hz; reference = finest setting)', fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    return path


if __name__ == '__main__':
    sys.exit(main())
