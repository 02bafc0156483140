"""Numerical stability of the smarticle simulation: where does it end, and does the sim say so?

50 robots densely packed (hexagonal lattice, seeded headings, all in phase; the plate is enlarged to
hold them) run up to ``--periods`` gait periods for every combination of physics time step (up to
1/60 s, one step per control tick), gait amplitude alpha_max (up to 120 deg) and servo speed (x1, x3).
The Runner's trouble checks run as usual (every ``trouble_every`` ticks); at each check this script also
reads the ground truth and keeps (including the value that fired a SimTrouble): the largest contact
penetration, the largest body speed, and an
energy-like indicator (total translational kinetic energy of the bodies; its max, and the mean over
the last quarter of the run against the first quarter: growth >> 1 would be runaway energy).

Outcome per setting: ``ok``; ``trouble: <quantity>`` (SimTrouble fired: what and when); ``NaN`` (the
trouble was a non-finite state). A run that ends ``ok`` is checked independently for silent garbage
(finite, on the plate, upright, no two footprints overlapping by more than the penetration bound): a
failure there is reported as ``SILENT GARBAGE`` -- the case the trouble detector must never allow.

Writes ``out/benchmarks/sim_stability.csv``.

    .venv/bin/python tests/benchmarks/bench_sim_stability.py --quick
    .venv/bin/python tests/benchmarks/bench_sim_stability.py
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import Progress, machine_line, markdown_table, out_path, write_csv
from smarticle_common.gait import GaitConfig, GaitError
from smarticle_sim.errors import SceneError, SimTrouble
from smarticle_sim.geometry import robot_rects, robots_overlap
from smarticle_sim.scenes import dense_scene
from smarticle_sim.settings import SimConfig
from smarticle_sim.physics import Physics
from smarticle_sim.runner import Runner


def silent_garbage(world: Physics) -> str:
    """'' if the final state is sane, else what is wrong (a check independent of the trouble detector)."""
    s = world.state()
    ph, spec = world.config.physics, world.config.robot
    if not (np.isfinite(s.positions).all() and np.isfinite(s.arm_angles).all()):
        return 'non-finite state'
    if np.abs(s.positions[:, :2]).max() > ph.plate_size / 2.0:
        return 'robot off the plate'
    if (np.abs(s.positions[:, 2] - spec.body_height / 2.0) > spec.body_height / 2.0).any():
        return 'body height out of range'
    if (s.tilt > ph.max_tilt).any():
        return 'robot tipped over'
    rects = [robot_rects(spec, p[0], p[1], p[2], a[0], a[1]) for p, a in zip(s.poses, s.arm_angles, strict=True)]
    for i in range(len(rects)):
        for j in range(i + 1, len(rects)):
            if robots_overlap(rects[i], rects[j], -ph.max_penetration):
                return f'robots {i} and {j} overlap by > {ph.max_penetration * 1e3:g} mm (tunnelled)'
    return ''


def run_setting(base: SimConfig, n: int, seed: int, rate: float, alpha_deg: float, speed_factor: float,
                periods: float, plate: float) -> dict[str, object]:
    """Run one stress setting; return its row."""
    robot = replace(base.robot, servo_speed=base.robot.servo_speed * speed_factor)
    config = replace(base, robot=robot).with_physics(time_step=1.0 / rate, plate_size=plate)
    row: dict[str, object] = {'rate_hz': rate, 'time_step_s': 1.0 / rate, 'alpha_max_deg': alpha_deg,
                              'servo_speed_x': speed_factor, 'robots': n}
    try:
        gait = GaitConfig.from_degrees(alpha_deg, servo_speed=robot.servo_speed)
        scene = dense_scene(robot, gait, n, seed=seed)
    except (GaitError, SceneError) as error:
        row.update(outcome=f'invalid: {error}')
        return row
    body_mass = robot.body_mass
    pen_max = speed_max = ke_max = 0.0
    kes: list[float] = []
    outcome = 'ok'
    start = time.perf_counter()
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        ticks = world.ticks_for(periods * gait.period)
        every = config.physics.trouble_every
        run.gaits.start(0.0)
        try:
            for i in range(1, ticks + 1):
                run.tick()
                if i % every == 0:
                    s = world.state()
                    _, depth = world.max_penetration()
                    pen_max = max(pen_max, depth)
                    speed_max = max(speed_max, float(s.speed.max()))
                    ke = float(0.5 * body_mass * (s.speed ** 2).sum())
                    kes.append(ke)
                    ke_max = max(ke_max, ke)
        except SimTrouble as trouble:
            quantity = trouble.quantity.split(' (')[0]
            outcome = 'NaN' if 'not finite' in str(trouble) else f'trouble: {quantity} = {trouble.value:.4g}'
            if 'penetration' in trouble.quantity and math.isfinite(trouble.value):
                pen_max = max(pen_max, trouble.value)
            if 'speed' in trouble.quantity and math.isfinite(trouble.value):
                speed_max = max(speed_max, trouble.value)
            row.update(trouble_robot=trouble.robot, trouble_time_s=trouble.time, trouble_value=trouble.value)
        else:
            garbage = silent_garbage(world)
            if garbage:
                outcome = f'SILENT GARBAGE: {garbage}'
        sim_time = world.time
    q = max(1, len(kes) // 4)
    growth = (np.mean(kes[-q:]) / np.mean(kes[:q])) if len(kes) >= 4 and np.mean(kes[:q]) > 0 else math.nan
    row.update(outcome=outcome, sim_time_s=sim_time, wall_s=time.perf_counter() - start,
               max_penetration_mm=pen_max * 1e3, max_speed_m_s=speed_max, max_ke_uj=ke_max * 1e6,
               ke_growth=float(growth))
    return row


def main(argv: list[str] | None = None) -> int:
    """Run the stress grid and print the table."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true', help='10 periods per setting instead of 300 (~1.5 min)')
    parser.add_argument('--periods', type=float, default=None, help='gait periods per setting (default 300)')
    parser.add_argument('--robots', type=int, default=50)
    parser.add_argument('--rates', type=float, nargs='+', default=[240.0, 120.0, 60.0],
                        help='physics rates (Hz), each a divisor of 60 Hz times a whole number')
    parser.add_argument('--alpha-max', type=float, nargs='+', default=[90.0, 120.0], help='degrees')
    parser.add_argument('--speed', type=float, nargs='+', default=[1.0, 3.0], help='servo speed factors')
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--out-dir', type=Path, default=None)
    parser.add_argument('--no-progress', action='store_true')
    args = parser.parse_args(argv)
    periods = args.periods or (10.0 if args.quick else 300.0)
    base = SimConfig()
    probe = dense_scene(base.robot, GaitConfig.from_degrees(90.0), args.robots, seed=args.seed)
    extent = max(max(abs(r.x), abs(r.y)) for r in probe.robots)
    plate = round(max(base.physics.plate_size, 2.0 * (extent + 6.0 * base.robot.reach)), 3)
    grid = list(itertools.product(args.alpha_max, args.speed, sorted(args.rates, reverse=True)))
    print(f'# stability: {args.robots} robots dense (seed {args.seed}), {periods:g} periods, plate {plate} m, '
          f'trouble bounds: penetration {base.physics.max_penetration * 1e3:g} mm, speed '
          f'{base.physics.max_speed:g} m/s, tilt {math.degrees(base.physics.max_tilt):g} deg; {machine_line()}')
    progress = Progress(len(grid), 'stability', not args.no_progress)
    rows = []
    for alpha, factor, rate in grid:
        row = run_setting(base, args.robots, args.seed, rate, alpha, factor, periods, plate)
        rows.append(row)
        progress.step(f'{rate:g} Hz, alpha {alpha:g}, speed x{factor:g}: {row["outcome"]}')
    for row in rows:
        row['setting'] = f'1/{row["rate_hz"]:g} s, {row["alpha_max_deg"]:g} deg, x{row["servo_speed_x"]:g}'
        if 'trouble_time_s' in row:
            row['outcome'] = f'{row["outcome"]} at {float(row["trouble_time_s"]):.1f} s'  # type: ignore[arg-type]
    print(markdown_table(rows, [('setting', 'time step, alpha_max, servo speed', ''), ('outcome', 'outcome', ''),
                                ('sim_time_s', 'sim s reached', '.1f'),
                                ('max_penetration_mm', 'max penetration (mm)', '.2f'),
                                ('max_speed_m_s', 'max speed (m/s)', '.3f'), ('max_ke_uj', 'max KE (uJ)', '.1f'),
                                ('ke_growth', 'KE last/first quarter', '.2f'), ('wall_s', 'wall (s)', '.1f')]))
    write_csv(out_path('sim_stability.csv', args.out_dir), rows)
    bad = [r for r in rows if str(r['outcome']).startswith('SILENT')]
    print(f'\n{sum(r["outcome"] == "ok" for r in rows)} ok, '
          f'{sum(str(r["outcome"]).startswith(("trouble", "NaN")) for r in rows)} stopped by the trouble '
          f'detector, {len(bad)} silent garbage')
    print(f'wrote {out_path("sim_stability.csv", args.out_dir)}')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
