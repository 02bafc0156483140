"""The validation of smarticle-calibrate without lab data (docs/calibration_from_bags.md, "Validation rules").

    python tools/calibration_validation.py stack  --out out/calibration_validation   # rule (a)
    python tools/calibration_validation.py mujoco --out out/calibration_validation   # rule (b)

``stack`` records one pair bag per true friction through the stack (sim.launch.xml, the sim bridge given the
true value in a preset file, feedback off, record:=true record_robots:=true), calibrates each alone and prints
the recovery table. ``mujoco`` runs MuJoCo's pair starts in the batch core, writes them as pose bags,
calibrates Bullet on the first half and prints the held-out table (default against calibrated, with bootstrap
intervals). Each prints a Markdown table and whether its rule passes.
"""

from __future__ import annotations

import argparse
import math
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
PARAM = 'friction_body_plate'
#: Rule (a): the true values (kept out of the fit), the stated error, the run's length.
TRUTHS = (0.25, 0.40, 0.55)
STATED_ERROR = 0.05
STACK_SECONDS = 20.0
#: Rule (b): MuJoCo's pair starts (theta, phi in degrees) at r = 1.3 BL, 12 periods each; first half fits.
MUJOCO_STARTS = ((0.0, 180.0), (0.0, 160.0), (330.0, 200.0), (0.0, 0.0))
MUJOCO_PERIODS = 12
RESAMPLES = 2000


def calibrate(bags: list[Path], out: Path) -> dict:
    """Run smarticle-calibrate on ``bags`` (fit PARAM) and return its preset file's calibration block."""
    cmd = [sys.executable, '-m', 'smarticle_experiments.calibrate_cli', *map(str, bags), '--fit', PARAM,
           '--out', str(out)]
    print('$', ' '.join(cmd[2:]), flush=True)
    subprocess.run(cmd, check=True)
    return yaml.safe_load((out / 'preset.yaml').read_text())['calibration']


def stack(out: Path) -> int:
    """Rule (a): record through the stack at each true friction, calibrate each bag, print the table."""
    rows, inside, within = [], 0, 0
    for truth in TRUTHS:
        folder = out / f'stack_{truth:.2f}'
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        preset = folder / 'truth.yaml'
        preset.write_text(yaml.safe_dump({'preset': 'small', 'physics': {PARAM: truth}}))
        params = folder / 'params.yaml'
        params.write_text(yaml.safe_dump({'/sim_bridge': {'ros__parameters': {
            'preset': str(preset), 'pair_r': 1.3, 'pair_theta_deg': 0.0, 'pair_phi_deg': 180.0}}}))
        bag = folder / 'bag'
        cmd = [str(Path(sys.executable).parent / 'smarticle-launch'), 'smarticle_bringup', 'sim.launch.xml',
               'robots:=2', 'scene:=pair', 'feedback:=false', f'duration:={STACK_SECONDS}', 'record:=true',
               'record_robots:=true', f'bag:={bag}', f'params_file:={params}']
        print('$ smarticle-launch', ' '.join(cmd[1:]), flush=True)
        t0 = time.time()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        print(f'recorded in {time.time() - t0:.0f} s', flush=True)
        cal = calibrate([bag], folder / 'fit')
        fitted = cal['fitted'][PARAM]
        lo, hi = fitted['interval_95']
        ok_in = lo <= truth <= hi
        ok_err = abs(fitted['value'] - truth) <= STATED_ERROR
        inside += ok_in
        within += ok_err
        rows.append(f'| {truth:.2f} | {fitted["value"]:.3f} | [{lo:.3f}, {hi:.3f}] | '
                    f'{fitted["value"] - truth:+.3f} | {"yes" if ok_err else "no"} | {"yes" if ok_in else "no"} | '
                    f'{cal["distance_default"]:.1f} | {cal["distance_fit"]:.1f} |')
    print(f'| true {PARAM} | fitted | 95 % interval | error | within {STATED_ERROR} | true inside | '
          'D default | D fitted |')
    print('|---|---|---|---|---|---|---|---|')
    print('\n'.join(rows))
    passed = within == len(TRUTHS) and inside >= 2
    print(f'rule (a): {within}/3 within the stated error, {inside}/3 inside the interval: '
          f'{"passes" if passed else "fails"}')
    return 0


def mujoco(out: Path) -> int:
    """Rule (b): MuJoCo's bags as the robots; Bullet calibrated on half predicts the other half."""
    from smarticle_common.gait import GaitConfig
    from smarticle_experiments import calibrate as cal
    from smarticle_sim.batch import run_trial
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.engines import engine_factory
    from smarticle_sim.scenes import pair_scene

    config = build_config('small', engine='mujoco')
    gait = GaitConfig.from_degrees(90.0)
    bags = []
    for theta, phi in MUJOCO_STARTS:
        bag = out / f'mujoco_{theta:.0f}_{phi:.0f}'
        shutil.rmtree(bag, ignore_errors=True)
        scene = pair_scene(config.robot, gait, 1.3, math.radians(theta), math.radians(phi))
        rec = run_trial(config, scene, MUJOCO_PERIODS, engine=engine_factory('mujoco'))
        cal.write_pose_bag(rec.time, rec.poses, bag, f'MuJoCo pair theta {theta:g} phi {phi:g} deg')
        bags.append(bag)
    half = len(bags) // 2
    fitted = calibrate(bags[:half], out / 'mujoco_fit')
    value = fitted['fitted'][PARAM]['value']
    runs = [cal.load_run(b) for b in bags[half:]]
    bl = config.robot.body_length

    def per_segment(friction: float) -> dict[str, np.ndarray]:
        """Each held-out segment's residuals (segments, components) per observable, the runs stacked."""
        sim_config = build_config('small', physics={PARAM: friction})
        out: dict[str, list[np.ndarray]] = {}
        for run in runs:
            sim, bag = cal.simulate(run, sim_config), cal.bag_observables(run, bl)
            for n in bag:
                d = sim[n] - bag[n]
                if n == 'phi':
                    d = (d + math.pi) % (2 * math.pi) - math.pi
                out.setdefault(n, []).append(d)
        return {n: np.concatenate(v) for n, v in out.items()}

    res_d = per_segment(float(build_config('small').physics.friction_body_plate))
    res_c = per_segment(float(value))
    names = list(res_d)
    segments = len(res_d[names[0]])
    rng = np.random.default_rng(0)
    draws_d, draws_c, draws_diff = [], [], []
    gap_d: dict[str, list[float]] = {n: [] for n in names}
    gap_c: dict[str, list[float]] = {n: [] for n in names}
    for _ in range(RESAMPLES):
        idx = rng.integers(0, segments, segments)      # the same segments for both, every observable
        dd = float(sum(cal.soft_l1(res_d[n][idx] / cal.SCALES[n]).sum() for n in names))
        dc = float(sum(cal.soft_l1(res_c[n][idx] / cal.SCALES[n]).sum() for n in names))
        draws_d.append(dd)
        draws_c.append(dc)
        draws_diff.append(dd - dc)
        for n in names:
            gap_d[n].append(float(np.sqrt(np.mean(res_d[n][idx] ** 2))))
            gap_c[n].append(float(np.sqrt(np.mean(res_c[n][idx] ** 2))))
    flat_d = {n: r.ravel() for n, r in res_d.items()}
    flat_c = {n: r.ravel() for n, r in res_c.items()}
    res_d, res_c = flat_d, flat_c

    def ci(x: list[float]) -> str:
        lo, hi = np.percentile(x, [2.5, 97.5])
        return f'[{lo:.4g}, {hi:.4g}]'

    gd, gc = cal.gaps(res_d), cal.gaps(res_c)
    print(f'fitted on {", ".join(b.name for b in bags[:half])}: {PARAM} = {value:.3f} '
          f'{fitted["fitted"][PARAM]["interval_95"]}; held out: {", ".join(b.name for b in bags[half:])}')
    print('| held-out | default (0.30) | 95 % interval | calibrated | 95 % interval |')
    print('|---|---|---|---|---|')
    print(f'| D | {cal.distance(res_d):.4g} | {ci(draws_d)} | {cal.distance(res_c):.4g} | {ci(draws_c)} |')
    for n in names:
        print(f'| gap {n} ({cal.UNITS[n]}) | {gd[n]:.4g} | {ci(gap_d[n])} | {gc[n]:.4g} | {ci(gap_c[n])} |')
    lo = float(np.percentile(draws_diff, 2.5))
    passed = cal.distance(res_c) < cal.distance(res_d) and lo > 0.0
    print(f'D default - D calibrated: {cal.distance(res_d) - cal.distance(res_c):.4g} {ci(draws_diff)}')
    print(f'rule (b): {"passes" if passed else "fails"}')
    return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('rule', choices=('stack', 'mujoco'))
    parser.add_argument('--out', type=Path, default=ROOT / 'out' / 'calibration_validation')
    ns = parser.parse_args()
    ns.out.mkdir(parents=True, exist_ok=True)
    sys.exit(stack(ns.out) if ns.rule == 'stack' else mujoco(ns.out))


if __name__ == '__main__':
    main()
