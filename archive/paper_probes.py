"""Calibration of the sim against the paper (SPEC section 6): P7 drift, pair binding/transport, P1 sample.

The exploratory probes of the calibration passes (docs/history/sim_calibration_first_passes.md); the paper
experiments proper run as specs through ``smarticle-experiments``. Every experiment is seeded and
deterministic; trials run in parallel (``--procs``, at most 2 here).
Tables are printed; each experiment appends rows to ``out/calibration/<experiment>.csv`` and draws
``out/calibration/<experiment>.png``. Run from the repository root, e.g.::

    smarticle-paper-probes drift
    smarticle-paper-probes pairs --periods 100
    smarticle-paper-probes basin --periods 30 --step 30
    smarticle-paper-probes knobs --periods 40
    smarticle-paper-probes dense --seeds 10 --periods 300
    smarticle-paper-probes dt --periods 40
    smarticle-paper-probes phase --periods 100 --phase2 0.1

Physics overrides for any experiment: ``--set friction_robot_robot=0.1 --set servo_torque=0.2`` (a
PhysicsConfig or RobotSpec field); ``--servo-speed 7.854`` runs the gait at the paper's Chrono speed
(pi rad per 0.4 s quarter; at alpha_max 90 deg the stroke then fills the whole quarter).

Pair metrics: ``touch`` = periods with a robot-robot contact; ``tail`` = consecutive touching periods
at the end; ``bound_K`` / ``life`` / ``class`` / ``dist_W`` from ``smarticle_tracking.gliders``
(``analyse_gliders`` with contacts and r_bind = 1.6 BL, K = 10 for pairs); ``late_W`` = net travel of
the centre of mass over the second half of the run (W), which excludes the first, transient pushes.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import fields, replace
from multiprocessing import Pool
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import R_BIND_BL, RobotSpec
from smarticle_common.gait import GaitConfig
from smarticle_common.pairs import one_pair
from smarticle_common.runs import Recording

from smarticle_experiments.assignments import parse_assignments
from smarticle_sim.batch import run_trial
from smarticle_sim.errors import SceneError
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene, pair_scene
from smarticle_sim.settings import PhysicsConfig, SimConfig
from smarticle_tracking.gliders import GliderClass, GliderConfig, analyse_gliders

OUT = Path('out/calibration')

# ------------------------------------------------------------------ configuration


def make_config(overrides: dict[str, float] | None = None) -> SimConfig:
    """SimConfig() with PhysicsConfig / RobotSpec field overrides (name -> value)."""
    config = SimConfig()
    if not overrides:
        return config
    physics_names = {f.name for f in fields(PhysicsConfig)}
    robot_names = {f.name for f in fields(RobotSpec)}
    physics: dict[str, Any] = {k: v for k, v in overrides.items() if k in physics_names}
    robot: dict[str, Any] = {k: v for k, v in overrides.items() if k in robot_names}
    unknown = set(overrides) - physics_names - robot_names
    if unknown:
        raise SystemExit(f'unknown setting(s) {sorted(unknown)}')
    if 'time_step' in physics and 'control_tick' not in physics:
        physics['time_step'] = 1.0 / round(1.0 / physics['time_step'])
    return replace(config, robot=replace(config.robot, **robot), physics=replace(config.physics, **physics))


def make_gait(config: SimConfig, alpha_deg: float, servo_speed: float | None,
              phase: float = 0.0) -> GaitConfig:
    """The square gait at ``alpha_deg`` (servo speed: given or the robot's)."""
    return GaitConfig.from_degrees(alpha_deg, servo_speed=servo_speed or config.robot.servo_speed,
                                   phase=phase)


# ------------------------------------------------------------------ metrics


def pair_contacts(rec: Recording) -> np.ndarray:
    """(S, P) contact table in ``pair_indices`` order from a recording's (S, N, N) contacts."""
    n = rec.contacts.shape[1]
    iu = np.triu_indices(n, 1)
    return rec.contacts[:, iu[0], iu[1]]


def glider_config(config: SimConfig, period: float, min_periods: int) -> GliderConfig:
    """Glider analysis settings for a sim recording."""
    bl = config.robot.body_length
    return GliderConfig(period=period, r_bind=R_BIND_BL * bl, min_periods=min_periods, body_length=bl,
                        width=bl)


def pair_metrics(config: SimConfig, rec: Recording, period: float, min_periods: int = 10) -> dict[str, Any]:
    """Contact, binding and transport figures of a two-robot recording."""
    bl = config.robot.body_length
    per = max(1, round(period / (config.physics.control_tick * rec.meta['sample_every'])))
    touching = rec.contacts[:, 0, 1]
    n_periods = len(touching) // per
    touched = np.array([touching[q * per:(q + 1) * per].any() for q in range(n_periods)], dtype=bool)
    tail = 0
    for t in touched[::-1]:
        if not t:
            break
        tail += 1
    com = rec.poses[::per, :, :2].mean(axis=1)
    half = len(com) // 2
    end_r, end_theta, end_phi = one_pair(rec.poses[-1, 0], rec.poses[-1, 1])
    analysis = analyse_gliders(rec.time, rec.poses, glider_config(config, period, min_periods),
                               contacts=pair_contacts(rec))
    best = max(analysis.gliders, key=lambda g: g.lifetime_periods, default=None)
    return {
        'periods_run': n_periods, 'touch': int(touched.sum()), 'tail': tail,
        'r_end': end_r / bl, 'theta_end': math.degrees(end_theta), 'phi_end': math.degrees(end_phi),
        'travel_W': float(np.linalg.norm(com[-1] - com[0]) / bl),
        'late_W': float(np.linalg.norm(com[-1] - com[half]) / bl),
        'life': best.lifetime_periods if best else 0,
        'class': best.glider_class.value if best else '',
        'dist_W': best.distance / bl if best else 0.0,
        'trouble': rec.trouble[:60],
    }


# ------------------------------------------------------------------ trials (picklable jobs)


def single_job(args: tuple[dict, float, float | None, int]) -> dict[str, Any]:
    """One robot alone: mean displacement per cycle and net drift per cycle (um)."""
    overrides, alpha, speed, periods = args
    config = make_config(overrides)
    gait = make_gait(config, alpha, speed)
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, math.pi / 2, a, a, gait),), name='single')
    rec = run_trial(config, scene, periods, sample_every=1, record_fsr=False, record_contacts=False)
    per = round(gait.period / config.physics.control_tick)
    xy = rec.poses[::per, 0, :2]
    step = float(np.linalg.norm(np.diff(xy, axis=0), axis=1).mean())
    net = float(np.linalg.norm(xy[-1] - xy[0]) / (len(xy) - 1))
    return {'alpha': alpha, 'step_um': step * 1e6, 'net_um': net * 1e6, 'trouble': rec.trouble[:60]}


def pair_job(args: tuple[dict, float, float, float, tuple[float, float], float, float | None, int]
             ) -> dict[str, Any]:
    """One pair trial from pair coordinates (r in BL, theta and phi in degrees)."""
    overrides, r, theta, phi, phases, alpha, speed, periods = args
    config = make_config(overrides)
    gait = make_gait(config, alpha, speed)
    row: dict[str, Any] = {'r0': r, 'theta0': theta, 'phi0': phi, 'phase2': phases[1], 'alpha': alpha}
    try:
        scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases)
    except SceneError:
        row['admissible'] = False
        return row
    t0 = time.perf_counter()
    rec = run_trial(config, scene, periods, sample_every=2, record_fsr=False, record_contacts=True)
    row.update(admissible=True, wall_s=time.perf_counter() - t0, **pair_metrics(config, rec, gait.period))
    for frac in (0.25, 0.5, 0.75):   # phi along the run: does the pair settle or keep turning?
        frame = rec.poses[int(frac * (len(rec.time) - 1))]
        row[f'phi_{round(100 * frac)}'] = math.degrees(one_pair(frame[0], frame[1])[2])
    return row


def dense_job(args: tuple[dict, int, int, float, float | None, float]) -> dict[str, Any]:
    """One dense 7-robot trial (paper P1): the longest glider and its class and travel."""
    overrides, seed, periods, alpha, speed, phase_jitter = args
    config = make_config(overrides)
    gait = make_gait(config, alpha, speed)
    scene = dense_scene(config.robot, gait, n=7, seed=seed, phase_jitter=phase_jitter)
    t0 = time.perf_counter()
    rec = run_trial(config, scene, periods, sample_every=4, record_fsr=False, record_contacts=True)
    wall = time.perf_counter() - t0
    analysis = analyse_gliders(rec.time, rec.poses, glider_config(config, gait.period, 30),
                               contacts=pair_contacts(rec))
    bl = config.robot.body_length
    gl = sorted(analysis.gliders, key=lambda g: -g.lifetime_periods)
    best = gl[0] if gl else None
    return {'seed': seed, 'periods': periods, 'wall_s': wall, 'x_real_time': rec.time[-1] / wall,
            'gliders_30': len(gl), 'gliders_100': sum(g.lifetime_periods >= 100 for g in gl),
            'best_life': best.lifetime_periods if best else 0,
            'best_class': best.glider_class.value if best else '',
            'best_dist_W': best.distance / bl if best else 0.0,
            'best_phi': math.degrees(best.phi_mean) if best else math.nan,
            'best_r_BL': best.r_mean / bl if best else math.nan,
            'c1_lives': [g.lifetime_periods for g in gl if g.glider_class is GliderClass.C1],
            'c2_lives': [g.lifetime_periods for g in gl if g.glider_class is GliderClass.C2],
            'trouble': rec.trouble[:60]}


# ------------------------------------------------------------------ output


def run_jobs(func: Any, jobs: list, procs: int) -> list[dict[str, Any]]:
    """Map ``func`` over ``jobs`` with a pool of ``procs`` processes (1: in this process)."""
    if procs <= 1:
        return [func(j) for j in jobs]
    with Pool(procs) as pool:
        return pool.map(func, jobs, chunksize=1)


def fmt(value: Any) -> str:
    """A table cell."""
    if isinstance(value, float):
        return f'{value:.3g}' if abs(value) < 1000 else f'{value:.0f}'
    return str(value)


def print_table(rows: list[dict[str, Any]], columns: list[str]) -> None:
    """A Markdown table of ``columns`` of ``rows``."""
    print('| ' + ' | '.join(columns) + ' |')
    print('|' + ' --- |' * len(columns))
    for row in rows:
        print('| ' + ' | '.join(fmt(row.get(c, '')) for c in columns) + ' |', flush=True)


def write_csv(name: str, rows: list[dict[str, Any]], extra: dict[str, Any]) -> Path:
    """Append ``rows`` (plus ``extra`` columns) to out/calibration/<name>.csv."""
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f'{name}.csv'
    full = [{**extra, **r} for r in rows]
    keys: list[str] = []
    for r in full:
        keys += [k for k in r if k not in keys]
    new = not path.exists()
    if not new:
        with path.open() as fh:
            header = next(csv.reader(fh), [])
        if header != keys:
            path = OUT / f'{name}-{int(time.time())}.csv'
            new = True
    with path.open('a', newline='') as fh:
        writer = csv.DictWriter(fh, fieldnames=keys)
        if new:
            writer.writeheader()
        writer.writerows(full)
    return path


def figure(name: str) -> tuple[Any, Any]:
    """A matplotlib (Agg) figure and axes."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 5), dpi=100)
    return fig, fig.add_subplot(1, 1, 1)


def scatter_by_class(ax: Any, rows: list[dict[str, Any]], x: str, y: str) -> None:
    """Scatter ``rows[x]`` against ``rows[y]``, one colour per glider class (black: no glider)."""
    for cls, colour in (('C1', 'tab:red'), ('C2', 'tab:blue'), ('unclassified', 'tab:gray'), ('', 'k')):
        sel = [r for r in rows if r['class'] == cls]
        ax.scatter([r[x] for r in sel], [r[y] for r in sel], c=colour, label=cls or 'none')


def save(fig: Any, name: str) -> Path:
    """Write a figure to out/calibration/<name>.png."""
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f'{name}.png'
    fig.tight_layout()
    fig.savefig(path)
    return path


# ------------------------------------------------------------------ experiments


def exp_drift(args: argparse.Namespace) -> None:
    """P7: single-robot drift per cycle at three amplitudes."""
    alphas = (90.0, 45.0, 10.0)
    jobs = [(args.overrides, a, args.servo_speed if a == 90.0 else None, args.periods) for a in alphas]
    rows = run_jobs(single_job, jobs, args.procs)
    print(f'## P7 single-robot drift, {args.periods} periods (paper ~75 um/cycle)')
    print_table(rows, ['alpha', 'step_um', 'net_um', 'trouble'])
    print('csv:', write_csv('drift', rows, {'settings': args.label}))
    fig, ax = figure('drift')
    ax.bar([str(r['alpha']) for r in rows], [r['net_um'] for r in rows])
    ax.axhline(75.0, color='k', ls='--', label='paper ~75 um')
    ax.set_xlabel('alpha_max (deg)')
    ax.set_ylabel('net drift per cycle (um)')
    ax.legend()
    print('png:', save(fig, 'drift'))


#: Pair starts of the pairs experiment: (r BL, theta deg, phi deg, phase of robot 2).
PAIR_STARTS = [(1.3, t, p, ph) for t in (0.0, 30.0, 330.0, 300.0) for p in (165.0, 180.0, 195.0, 0.0, 15.0, 345.0)
               for ph in (0.0, 0.25)]


def exp_pairs(args: argparse.Namespace) -> None:
    """C1 and C2 pairs from a set of starts near the paper's configurations: binding and transport."""
    jobs = [(args.overrides, r, t, p, (0.0, ph), args.alpha, args.servo_speed, args.periods)
            for r, t, p, ph in PAIR_STARTS]
    rows = [r for r in run_jobs(pair_job, jobs, args.procs) if r['admissible']]
    cols = ['r0', 'theta0', 'phi0', 'phase2', 'touch', 'tail', 'life', 'class', 'dist_W', 'late_W',
            'r_end', 'phi_end', 'trouble']
    print(f'## pairs, alpha_max {args.alpha}, {args.periods} periods ({args.label})')
    print_table(rows, cols)
    print('csv:', write_csv('pairs', rows, {'settings': args.label, 'periods': args.periods}))
    fig, ax = figure('pairs')
    scatter_by_class(ax, rows, 'life', 'dist_W')
    ax.set_xlabel('longest bound run (periods)')
    ax.set_ylabel('distance travelled while bound (W)')
    ax.set_title(f'pairs, {args.periods} periods, {args.label}', fontsize=9)
    ax.legend()
    print('png:', save(fig, 'pairs'))


def exp_basin(args: argparse.Namespace) -> None:
    """P4-style basin scan at r = 1.3 BL: which (theta, phi) starts end touching, and how far they go."""
    grid = np.arange(0.0, 360.0, args.step)
    rows = []
    for phase in (0.0, 0.25):
        jobs = [(args.overrides, 1.3, float(t), float(p), (0.0, phase), args.alpha, args.servo_speed,
                 args.periods) for t in grid for p in grid]
        rows += run_jobs(pair_job, jobs, args.procs)
    adm = [r for r in rows if r['admissible']]
    bound = [r for r in adm if r['tail'] >= 5]
    print(f'## basin scan r = 1.3 BL, {args.periods} periods ({args.label}): {len(adm)} admissible, '
          f'{len(bound)} touching at the end')
    print_table(sorted(bound, key=lambda r: -r['late_W'])[:15],
                ['theta0', 'phi0', 'phase2', 'tail', 'late_W', 'travel_W', 'r_end', 'phi_end', 'theta_end'])
    print('csv:', write_csv('basin', rows, {'settings': args.label, 'periods': args.periods}))
    fig, ax = figure('basin')
    for phase, marker in ((0.0, 'o'), (0.25, 's')):
        sel = [r for r in adm if r['phase2'] == phase]
        colours = ['tab:red' if r['tail'] >= 5 else 'tab:blue' for r in sel]
        ax.scatter([r['theta0'] + (4 if phase else -4) for r in sel], [r['phi0'] for r in sel], c=colours,
                   marker=marker, s=20 + 400 * np.array([r['late_W'] for r in sel]))
    ax.set_xlabel('theta (deg)')
    ax.set_ylabel('phi (deg)')
    ax.set_title(f'touching at end (red) vs apart (blue); size ~ late travel; o p=0, s p=0.25; '
                 f'{args.label}', fontsize=8)
    print('png:', save(fig, 'basin'))


#: Knob variants of the knobs experiment (label, overrides).
KNOBS: list[tuple[str, dict[str, float]]] = [
    ('defaults', {}),
    ('servo_torque 0.01', {'servo_torque': 0.01}),
    ('servo_torque 1.0', {'servo_torque': 1.0}),
    ('arm_mass 1 g', {'arm_mass': 0.001}),
    ('arm_mass 8 g', {'arm_mass': 0.008}),
    ('mu_rr 0.1', {'friction_robot_robot': 0.1}),
    ('mu_rr 0.6', {'friction_robot_robot': 0.6}),
    ('mu_bp 0.2', {'friction_body_plate': 0.2}),
    ('mu_bp 0.5', {'friction_body_plate': 0.5}),
    ('restitution 0.85, cbt 0.5 mm', {'restitution': 0.85, 'contact_breaking_threshold': 0.0005}),
    ('position_gain 1.0', {'position_gain': 1.0}),
    ('dt 1/480', {'time_step': 1 / 480}),
]
#: C1-like starts of the knobs experiment.
KNOB_STARTS = [(1.3, t, p, ph) for t in (0.0, 30.0, 60.0, 300.0, 330.0) for p in (150.0, 180.0, 210.0)
               for ph in (0.0, 0.25)]


def exp_knobs(args: argparse.Namespace) -> None:
    """One knob at a time over C1-like starts: how many end touching, and their late travel."""
    rows = []
    for label, knob in KNOBS:
        overrides = {**args.overrides, **knob}
        jobs = [(overrides, r, t, p, (0.0, ph), args.alpha, args.servo_speed, args.periods)
                for r, t, p, ph in KNOB_STARTS]
        t0 = time.perf_counter()
        res = [r for r in run_jobs(pair_job, jobs, args.procs) if r['admissible']]
        bound = [r for r in res if r['tail'] >= 5]
        late = sorted((r['late_W'] for r in bound), reverse=True)
        rows.append({'knob': label, 'admissible': len(res), 'touching_end': len(bound),
                     'late_W_max': late[0] if late else 0.0,
                     'late_W_mean': float(np.mean(late)) if late else 0.0,
                     'r_end_median': float(np.median([r['r_end'] for r in bound])) if bound else math.nan,
                     'trouble': sum(1 for r in res if r['trouble']), 'wall_s': time.perf_counter() - t0})
        print_table(rows[-1:], list(rows[-1]))
    print(f'## knobs, C1-like starts, {args.periods} periods, late = second half ({args.label})')
    print_table(rows, list(rows[0]))
    print('csv:', write_csv('knobs', rows, {'settings': args.label, 'periods': args.periods}))
    fig, ax = figure('knobs')
    ax.barh([r['knob'] for r in rows], [r['late_W_mean'] for r in rows])
    ax.set_xlabel(f'mean late travel of touching pairs (W per {args.periods // 2} periods)')
    print('png:', save(fig, 'knobs'))


def exp_dense(args: argparse.Namespace) -> None:
    """P1 sample: dense 7-robot starts, ``--seeds`` seeds x ``--periods`` periods."""
    jobs = [(args.overrides, seed, args.periods, args.alpha, args.servo_speed, args.phase_jitter)
            for seed in range(args.seeds)]
    rows = run_jobs(dense_job, jobs, args.procs)
    print(f'## P1 dense 7 robots, {args.seeds} seeds x {args.periods} periods ({args.label}, '
          f'phase jitter {args.phase_jitter}); '
          'glider = bound >= 30 periods (contacts or r < 1.6 BL)')
    print_table(rows, ['seed', 'gliders_30', 'gliders_100', 'best_life', 'best_class', 'best_dist_W',
                       'best_phi', 'best_r_BL', 'c1_lives', 'c2_lives', 'x_real_time', 'trouble'])
    hits = sum(r['gliders_100'] > 0 for r in rows)
    print(f'trials with a pair bound >= 100 periods: {hits}/{len(rows)} (paper 97/151 = 64 %)')
    print('csv:', write_csv('dense', rows, {'settings': args.label, 'phase_jitter': args.phase_jitter}))
    fig, ax = figure('dense')
    ax.scatter([r['best_life'] for r in rows], [r['best_dist_W'] for r in rows])
    ax.set_xlabel('longest glider lifetime (periods)')
    ax.set_ylabel('its distance travelled (W)')
    ax.set_title(f'P1 sample, {args.label}', fontsize=9)
    print('png:', save(fig, 'dense'))


def exp_dt(args: argparse.Namespace) -> None:
    """Time-step convergence of a few pair starts: does the outcome change with dt?"""
    rows = []
    starts = [(1.3, 0.0, 180.0, 0.0), (1.3, 330.0, 195.0, 0.0), (1.3, 300.0, 180.0, 0.25)]
    for dt in (1 / 240, 1 / 480, 1 / 960):
        jobs = [({**args.overrides, 'time_step': dt}, r, t, p, (0.0, ph), args.alpha, args.servo_speed,
                 args.periods) for r, t, p, ph in starts]
        for row in run_jobs(pair_job, jobs, args.procs):
            rows.append({'dt': f'1/{round(1 / dt)}', **row})
    print(f'## time-step convergence, {args.periods} periods ({args.label})')
    print_table(rows, ['dt', 'theta0', 'phi0', 'phase2', 'touch', 'tail', 'r_end', 'phi_end', 'late_W',
                       'travel_W', 'wall_s'])
    print('csv:', write_csv('dt', rows, {'settings': args.label, 'periods': args.periods}))
    fig, ax = figure('dt')
    for start in starts:
        sel = [r for r in rows if (r['theta0'], r['phi0'], r['phase2']) == start[1:]]
        ax.plot([r['dt'] for r in sel], [r.get('r_end', math.nan) for r in sel], 'o-', label=str(start))
    ax.set_xlabel('time step')
    ax.set_ylabel('final r (BL)')
    ax.legend(fontsize=7)
    print('png:', save(fig, 'dt'))


#: Pair starts of the phase experiment: (r BL, theta deg, phi deg); C1-like then C2-like.
PHASE_STARTS = [(1.3, t, p) for t in (0.0, 330.0, 340.0) for p in (170.0, 180.0, 190.0)] + \
    [(1.3, t, p) for t in (30.0, 330.0) for p in (345.0, 15.0)]


def exp_phase(args: argparse.Namespace) -> None:
    """Pairs whose gaits are offset by a fraction of a period (the experiments' phase drift).

    With equal phases a pair relaxes to a symmetric, stationary state; with robot 2 ``--phase2``
    periods ahead (default 0.1) the symmetry is broken. Reports binding, class and travel while bound.
    """
    phases = [float(p) for p in args.phase2]
    jobs = [(args.overrides, r, t, p, (0.0, ph), args.alpha, args.servo_speed, args.periods)
            for ph in phases for r, t, p in PHASE_STARTS]
    rows = [r for r in run_jobs(pair_job, jobs, args.procs) if r['admissible']]
    cols = ['theta0', 'phi0', 'phase2', 'touch', 'tail', 'life', 'class', 'dist_W', 'late_W', 'r_end',
            'phi_25', 'phi_50', 'phi_75', 'phi_end', 'trouble']
    print(f'## phase-offset pairs, alpha_max {args.alpha}, {args.periods} periods ({args.label})')
    print_table(rows, cols)
    print('csv:', write_csv('phase', rows, {'settings': args.label, 'periods': args.periods}))
    fig, ax = figure('phase')
    scatter_by_class(ax, rows, 'phase2', 'dist_W')
    ax.set_xlabel('phase of robot 2 (periods)')
    ax.set_ylabel('distance travelled while bound (W)')
    ax.set_title(f'phase-offset pairs, {args.periods} periods, {args.label}', fontsize=9)
    ax.legend()
    print('png:', save(fig, 'phase'))


EXPERIMENTS = {'drift': exp_drift, 'pairs': exp_pairs, 'basin': exp_basin, 'knobs': exp_knobs,
               'dense': exp_dense, 'dt': exp_dt, 'phase': exp_phase}


def main() -> None:
    """Parse the command line and run one experiment."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('experiment', choices=sorted(EXPERIMENTS))
    parser.add_argument('--periods', type=int, default=40)
    parser.add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    parser.add_argument('--servo-speed', type=float, default=None,
                        help='gait servo speed (rad/s); default the robot spec (10.47)')
    parser.add_argument('--seeds', type=int, default=4)
    parser.add_argument('--step', type=float, default=30.0, help='basin grid step (deg)')
    parser.add_argument('--phase2', nargs='+', default=['0.1'], metavar='P',
                        help='phase experiment: gait phase(s) of robot 2 (periods)')
    parser.add_argument('--phase-jitter', type=float, default=0.0,
                        help='dense experiment: uniform gait-phase offsets in +-P periods (0: in phase)')
    parser.add_argument('--procs', type=int, default=2)
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE')
    args = parser.parse_args()
    try:
        args.overrides = parse_assignments(args.set)
    except ValueError as err:
        parser.error(f'--set {err}')
    args.label = ' '.join(args.set) or 'defaults'
    if args.servo_speed:
        args.label += f' servo_speed={args.servo_speed}'
    t0 = time.perf_counter()
    EXPERIMENTS[args.experiment](args)
    print(f'({time.perf_counter() - t0:.0f} s)')


if __name__ == '__main__':
    main()
