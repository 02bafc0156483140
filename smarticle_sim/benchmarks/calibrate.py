"""First calibration pass against the paper (SPEC section 6): single-robot drift (P7) and a C1 pair.

Prints tables; run ``.venv/bin/python smarticle_sim/benchmarks/calibrate.py [--periods 75]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from smarticle_driver.gait import GaitConfig

from smarticle_sim.batch import run_trial
from smarticle_sim.errors import SceneError
from smarticle_sim.geometry import pair_coordinates
from smarticle_sim.scenes import RobotPlacement, Scene, pair_scene
from smarticle_sim.settings import SimConfig


def single_drift(config: SimConfig, alpha_deg: float, periods: int) -> tuple[float, float]:
    """Mean displacement per gait cycle (m) and net drift per cycle (m) of one robot alone."""
    gait = GaitConfig.from_degrees(alpha_deg, servo_speed=config.robot.servo_speed)
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, math.pi / 2, a, a, gait),), name='single')
    rec = run_trial(config, scene, periods, record_fsr=False, record_contacts=False)
    per = round(gait.period / config.physics.control_tick)
    xy = rec.poses[::per, 0, :2]
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    return float(steps.mean()), float(np.linalg.norm(xy[-1] - xy[0]) / (len(xy) - 1))


def pair_run(config: SimConfig, r: float, theta: float, phi: float, phases: tuple[float, float],
             periods: int) -> tuple[float, float, float, float, float] | None:
    """(r start, r mean over the last 10 periods, r end, phi end, centre-of-mass travel) in BL/deg."""
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    try:
        scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases)
    except SceneError:
        return None
    rec = run_trial(config, scene, periods, record_fsr=False, record_contacts=False)
    bl = config.robot.body_length
    coords = np.array([pair_coordinates(p[0], p[1], bl) for p in rec.poses])
    per = round(gait.period / config.physics.control_tick)
    com = rec.poses[:, :, :2].mean(axis=1)
    return (float(coords[0, 0]), float(coords[-10 * per:, 0].mean()), float(coords[-1, 0]),
            math.degrees(float(coords[-1, 2])), float(np.linalg.norm(com[-1] - com[0]) / bl))


def main() -> None:
    """Run the calibration table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--periods', type=int, default=75)
    parser.add_argument('--friction', type=float, nargs='*', default=[0.35])
    args = parser.parse_args()
    for mu in args.friction:
        config = SimConfig().with_physics(friction_body_plate=mu)
        print(f'## body-plate friction {mu}')
        for alpha in (90.0, 45.0, 10.0):
            t0 = time.perf_counter()
            step, net = single_drift(config, alpha, 20)
            print(f'single robot alpha_max {alpha:4.0f} deg: mean |step| per cycle {step * 1e6:8.1f} um, '
                  f'net drift per cycle {net * 1e6:8.1f} um  ({time.perf_counter() - t0:.1f} s)')
    config = SimConfig()
    print(f'## pairs, phi = 180 (C1-like), alpha_max 90, {args.periods} periods; '
          'r in BL, travel of the COM in BL')
    print('| r0 | theta | phases | r mean (last 10) | r end | phi end | COM travel |')
    print('| --- | --- | --- | --- | --- | --- | --- |')
    for r in (1.3, 1.5):
        for theta in (30.0, 60.0, 120.0, 150.0):
            for phases in ((0.0, 0.0), (0.0, 0.25)):
                res = pair_run(config, r, theta, 180.0, phases, args.periods)
                if res is None:
                    print(f'| {r} | {theta:.0f} | {phases} | inadmissible (overlap) | | | |')
                    continue
                print(f'| {res[0]:.2f} | {theta:.0f} | {phases} | {res[1]:.2f} | {res[2]:.2f} | '
                      f'{res[3]:.0f} | '
                      f'{res[4]:.2f} |', flush=True)


if __name__ == '__main__':
    main()
