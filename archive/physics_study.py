"""Physics study for issue #11: collision mechanism, time-step convergence, stability (docs/physics_study.md).

Run from the repository root with the project's venv, ONE process at a time (the machine has 2 shared
cores); every run is deterministic (seeded scenes, Bullet's deterministic pair ordering). Results are
appended to ``out/physics/<experiment>.csv`` (one row per trial, written as soon as it ends) and figures
go to ``out/physics/<experiment>.png``::

    smarticle-physics-study collide --model default --theta 150 --phi 180
    smarticle-physics-study mechanism --periods 20
    smarticle-physics-study drift --model authors --dt 240 480 960 1920
    smarticle-physics-study pair --model authors --dt 240 480 960
    smarticle-physics-study basin --model authors --periods 75
    smarticle-physics-study dense --model authors --seeds 0-9 --periods 300
    smarticle-physics-study impact --pairs 0.6:0.85 0.2:0.76 --dt 960 480 --speeds 0.3 0.1

A *model* is a named set of settings (``MODELS``): PhysicsConfig / RobotSpec field overrides, plus the
gait's servo speed. ``--set name=value`` changes one field on top of the model. Extra Bullet knobs that
are not settings fields yet are applied after the ``Physics`` is built by ``apply_extras`` (names starting with
``x_``: ``x_split_impulse``, ``x_split_threshold``, ``x_rvt`` restitution velocity threshold,
``x_ccd`` swept-sphere radius in m, ``x_plate_restitution``).
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import GAIT_PERIOD, R_BIND_BL, RobotSpec
from smarticle_common.gait import GaitConfig
from smarticle_common.pairs import one_pair

from smarticle_experiments import stats
from smarticle_experiments.assignments import parse_assignments
from smarticle_sim.errors import SceneError, SimTrouble
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene, pair_scene
from smarticle_sim.settings import PhysicsConfig, SimConfig
from smarticle_sim.physics import ARM_JOINTS, Physics
from smarticle_sim.runner import Runner

OUT = Path('out/physics')
BL = 0.054
CHRONO_SPEED = math.pi / 0.4   # rad/s: the authors' motors turn pi rad per 0.4 s quarter

#: The defaults shipped until the study (1/240 s, 10 solver iterations, arm-arm friction 1.5, restitution 0,
#: contact ERP 0.6, per-step servo gain 0.3, 0.15 N m, 3.5 g arms): every model below is written on top of
#: them, so the study's tables stay reproducible after the defaults changed. 'default' in the study's tables
#: is this set.
OLD_DEFAULT: dict[str, Any] = {
    'time_step': 1.0 / 240, 'friction_arm_arm': 1.5, 'friction_robot_robot': 0.3, 'friction_body_plate': 0.35,
    'restitution': 0.0, 'restitution_body_plate': None, 'restitution_velocity_threshold': None,
    'servo_bandwidth': None, 'position_gain': 0.3, 'tilt_inertia_scale': 1.0, 'arm_mass': 0.0035,
    'servo_torque': 0.15, 'solver_iterations': 10, 'contact_erp': 0.6}

#: Named settings. 'default' = the defaults shipped until the study. 'authors' = the authors' Chrono model as far as
#: PyBullet can take it: friction 0.3 on every pair (body-plate 0.3), restitution 0.85 between robots,
#: rigid speed-driven motors (position gain 1: the arm reaches its target in one step at full speed,
#: torque limit far above any contact load), Chrono speed pi rad / 0.4 s, 24.8 g body (arms 5 g each).
MODELS: dict[str, dict[str, Any]] = {
    'default': dict(OLD_DEFAULT),
    'rigid': {**OLD_DEFAULT, 'position_gain': 1.0, 'servo_torque': 10.0},
    'authors': {**OLD_DEFAULT, 'friction_arm_arm': None, 'friction_robot_robot': 0.3, 'friction_body_plate': 0.3,
                'restitution': 0.85, 'restitution_body_plate': 0.0, 'restitution_velocity_threshold': 0.01,
                'position_gain': 1.0, 'servo_torque': 10.0, 'arm_mass': 0.005, 'gait_speed': CHRONO_SPEED},
}
#: The candidate: the authors' model with a servo of fixed bandwidth 72 /s (the shipped servo's final
#: approach at 1/240 s, now the same at every step), which sets P7's drift (docs/physics_study.md).
MODELS['candidate'] = {**MODELS['authors'], 'servo_bandwidth': 72.0}
#: The candidate with robots that stay flat (roll / pitch inertia x 100): restitution 0.85 tips robots in
#: dense in-phase clusters otherwise (docs/physics_study.md, section C).
MODELS['flat'] = {**MODELS['candidate'], 'tilt_inertia_scale': 100.0}
#: The default the study proposed (docs/sim_calibration.md): flat robots, a 0.05 N m servo of bandwidth 200 /s
#: at 1/480 s, contact ERP 0.6, 10 iterations. ``SimConfig()`` shipped it then and has moved on since (1/960 s,
#: 10 iterations, ERP 0.1 with restitution 0.80, the robots' own inertia); 'shipped' is whatever ``SimConfig()``
#: ships now.
#: The gait runs at the servo's top speed as the SPEC says (the authors' Chrono speed is dropped).
MODELS['proposed'] = {**{k: v for k, v in MODELS['flat'].items() if k != 'gait_speed'},
                      'servo_torque': 0.05, 'servo_bandwidth': 200.0, 'time_step': 1.0 / 480}
MODELS['shipped'] = {}
#: The proposed model with compliant contacts (Bullet contact stiffness and damping on robot links, no
#: restitution impulse), closer to a smooth-contact (penalty) model: e = 0.85 for a 30 g pair at k 2000 N/m.
MODELS['proposed soft'] = {**MODELS['proposed'], 'restitution': 0.0, 'x_contact_stiffness': 2000.0,
                           'x_contact_damping': 0.8}


def model_settings(name: str, sets: list[str] | None = None) -> dict[str, Any]:
    """The model's settings with ``name=value`` overrides."""
    try:
        return {**MODELS[name], **parse_assignments(sets or [])}
    except ValueError as err:
        raise SystemExit(f'--set {err}') from None


def make_config(settings: dict[str, Any]) -> tuple[SimConfig, float, dict[str, Any]]:
    """(SimConfig, gait servo speed, extras) from a settings dict."""
    physics_names = {f.name for f in fields(PhysicsConfig)}
    robot_names = {f.name for f in fields(RobotSpec)}
    physics = {k: v for k, v in settings.items() if k in physics_names}
    robot = {k: v for k, v in settings.items() if k in robot_names}
    extras = {k: v for k, v in settings.items() if k.startswith('x_')}
    unknown = set(settings) - physics_names - robot_names - set(extras) - {'gait_speed'}
    if unknown:
        raise SystemExit(f'unknown setting(s) {sorted(unknown)}')
    if 'time_step' in physics:
        dt = physics['time_step']
        physics['time_step'] = dt = 1.0 / round(1.0 / dt)
        if 'control_tick' not in physics:   # a tick must be a whole number of steps: 1/60 s or one step
            physics['control_tick'] = 1.0 / 60.0 if round(1.0 / dt) % 60 == 0 else dt
    base = SimConfig()
    robot_spec = replace(base.robot, **robot)
    gait_speed = float(settings.get('gait_speed', robot_spec.servo_speed))
    if gait_speed > robot_spec.servo_speed:
        robot_spec = replace(robot_spec, servo_speed=gait_speed)
    return SimConfig(robot_spec, replace(base.physics, **physics)), gait_speed, extras


def apply_extras(world: Physics, extras: dict[str, Any]) -> None:
    """Bullet knobs that are not settings fields (yet), applied after the world is built."""
    c = world.client
    params: dict[str, Any] = {}
    if 'x_split_impulse' in extras:
        params['useSplitImpulse'] = int(bool(extras['x_split_impulse']))
    if 'x_split_threshold' in extras:
        params['splitImpulsePenetrationThreshold'] = float(extras['x_split_threshold'])
    if 'x_rvt' in extras:
        params['restitutionVelocityThreshold'] = float(extras['x_rvt'])
    if 'x_cfm' in extras:
        params['globalCFM'] = float(extras['x_cfm'])
    if 'x_cone' in extras:
        params['enableConeFriction'] = int(bool(extras['x_cone']))
    if 'x_friction_erp' in extras:
        params['frictionERP'] = float(extras['x_friction_erp'])
    if params:
        c.setPhysicsEngineParameter(**params)
    if 'x_plate_restitution' in extras:
        c.changeDynamics(world.plate_id, -1, restitution=float(extras['x_plate_restitution']))
    if extras.get('x_tilt_inertia'):
        # robots that stay flat: the body's roll / pitch inertia times this factor (yaw and mass unchanged)
        for body in world.body_ids:
            info = c.getDynamicsInfo(body, -1)
            ixx, iyy, izz = info[2]
            k = float(extras['x_tilt_inertia'])
            c.changeDynamics(body, -1, localInertiaDiagonal=[ixx * k, iyy * k, izz])
    if extras.get('x_contact_stiffness'):
        for body in world.body_ids:
            for link in (-1, *ARM_JOINTS):
                c.changeDynamics(body, link, contactStiffness=float(extras['x_contact_stiffness']),
                                 contactDamping=float(extras.get('x_contact_damping', 0.0)))
    if extras.get('x_ccd'):
        for body in world.body_ids:
            for link in (-1, *ARM_JOINTS):
                c.changeDynamics(body, link, ccdSweptSphereRadius=float(extras['x_ccd']))


def make_world(settings: dict[str, Any], scene: Scene) -> Runner:
    """The runner (physics + gait controller) of ``scene`` with the settings and extras applied."""
    config, _, extras = make_config(settings)
    run = Runner.with_gaits(config, scene)
    apply_extras(run.physics, extras)
    return run


def gait_for(settings: dict[str, Any], alpha_deg: float = 90.0, phase: float = 0.0) -> GaitConfig:
    """The square gait of a model."""
    config, speed, _ = make_config(settings)
    return GaitConfig.from_degrees(alpha_deg, servo_speed=speed, phase=phase)


def append_csv(name: str, row: dict[str, Any]) -> None:
    """Append one row to out/physics/<name>.csv (header from the first row's keys)."""
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f'{name}.csv'
    new = not path.exists()
    with path.open('a', newline='') as fh:
        writer = csv.DictWriter(fh, fieldnames=list(row), extrasaction='ignore')
        if new:
            writer.writeheader()
        writer.writerow(row)


def read_csv(name: str) -> list[dict[str, str]]:
    """Rows of out/physics/<name>.csv."""
    path = OUT / f'{name}.csv'
    if not path.exists():
        return []
    with path.open() as fh:
        return list(csv.DictReader(fh))


def wilson(k: int, n: int) -> tuple[float, float]:
    """95 % Wilson interval (low, high) of a proportion k / n (``stats.wilson``); (0, 1) when n is 0."""
    if n == 0:
        return (0.0, 1.0)
    est = stats.wilson(k, n)
    return (est.low, est.high)


# ------------------------------------------------------------------ collision instrumentation


def _link_kind(link: int) -> str:
    return 'body' if link == -1 else 'arm'


def collide(settings: dict[str, Any], theta: float, phi: float, phases: tuple[float, float] = (0.0, 0.0),
            periods: float = 10.0, r: float = 1.3, alpha: float = 90.0) -> dict[str, Any]:
    """Run a pair step by step and measure every collision's impulses and the motion they cause.

    Per physics step: robot-robot contact forces (normal and friction, as impulses force x dt) resolved
    along the unit vector u from robot 1's centre to robot 2's (positive = pushes the pair apart), and
    the body-plate friction impulse on each body along the same axis (sign as for that robot: positive
    = moving it away from the other). A collision is a run of steps with a robot-robot contact (gaps of
    up to 3 steps merged). Per collision: its duration, the separating impulses, dr during the contact,
    dr in the contact-free time that follows (coasting), the largest body speed after it.
    """
    config, _, extras = make_config(settings)
    gait = gait_for(settings, alpha)
    scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases)
    world = make_world(settings, scene)
    c = world.physics.client
    b1, b2 = world.physics.body_ids
    plate = world.physics.plate_id
    dt = config.physics.time_step
    ticks = world.ticks_for(periods * gait.period)
    assert world.gaits is not None
    world.gaits.start(0.0)
    rows = []
    trouble = ''

    def measure(run: Runner) -> None:
        p1 = np.array(c.getBasePositionAndOrientation(b1)[0])
        p2 = np.array(c.getBasePositionAndOrientation(b2)[0])
        d = p2[:2] - p1[:2]
        dist = float(np.hypot(*d))
        u = np.array([d[0] / dist, d[1] / dist, 0.0])
        normal = friction = 0.0
        kinds = set()
        depth = 0.0
        for pt in c.getContactPoints(bodyA=b1, bodyB=b2):
            n_on_b = np.array(pt[7])           # points from B (robot 2) toward A (robot 1)
            f_a = pt[9] * n_on_b + pt[10] * np.array(pt[11]) + pt[12] * np.array(pt[13])
            # the impulse on robot 2 is -f_a; along u (+ = apart); robot 1 gets f_a along -u (+ = apart)
            normal += 2.0 * float(np.dot(-pt[9] * n_on_b, u)) * dt   # both robots' share
            friction += 2.0 * float(np.dot(-(f_a - pt[9] * n_on_b), u)) * dt
            kinds.add(f'{_link_kind(pt[3])}{pt[3] if pt[3] >= 0 else ""}-{_link_kind(pt[4])}'
                      f'{pt[4] if pt[4] >= 0 else ""}')
            depth = max(depth, -pt[8])
        plate_imp = 0.0
        for body, sign in ((b1, -1.0), (b2, 1.0)):
            for pt in c.getContactPoints(bodyA=body, bodyB=plate):
                f = pt[10] * np.array(pt[11]) + pt[12] * np.array(pt[13])   # friction on A = the robot
                plate_imp += sign * float(np.dot(f, u)) * dt
        v1 = np.array(c.getBaseVelocity(b1)[0])
        v2 = np.array(c.getBaseVelocity(b2)[0])
        rows.append((run.time, dist, normal, friction, plate_imp, bool(kinds), '+'.join(sorted(kinds)),
                     float(np.hypot(*v1[:2])), float(np.hypot(*v2[:2])), float(np.dot(v2 - v1, u)), depth))

    world.step_hooks.append(measure)
    try:
        world.run(ticks)
    except SimTrouble as exc:
        trouble = str(exc)[:80]
    finally:
        world.close()
    return {'rows': rows, 'trouble': trouble, 'dt': dt, 'period': gait.period}


def collisions(trace: dict[str, Any], merge: int = 3) -> list[dict[str, Any]]:
    """Group a ``collide`` trace into collision events (see ``collide``)."""
    rows = trace['rows']
    events: list[dict[str, Any]] = []
    i, n = 0, len(rows)
    while i < n:
        if not rows[i][5]:
            i += 1
            continue
        j, gap = i, 0
        k = i
        while k < n and gap <= merge:
            if rows[k][5]:
                j, gap = k, 0
            else:
                gap += 1
            k += 1
        seg = rows[i:j + 1]
        events.append({'start': i, 'end': j, 't0': rows[i][0], 'dur_ms': (j - i + 1) * trace['dt'] * 1e3,
                       'J_normal': sum(s[2] for s in seg), 'J_friction': sum(s[3] for s in seg),
                       'J_plate': sum(s[4] for s in seg),
                       'dr_contact_mm': (rows[j][1] - rows[max(i - 1, 0)][1]) * 1e3,
                       'kinds': '+'.join(sorted({kk for s in seg for kk in s[6].split('+') if kk})),
                       'vsep_end': rows[j][9], 'depth_mm': max(s[10] for s in seg) * 1e3})
        i = j + 1
    for e, nxt in zip(events, events[1:] + [None], strict=True):
        stop = nxt['start'] if nxt else n
        e['dr_after_mm'] = (rows[stop - 1][1] - rows[e['end']][1]) * 1e3
        e['J_plate_after'] = sum(s[4] for s in rows[e['end'] + 1:stop])
        speeds = [max(s[7], s[8]) for s in rows[e['end'] + 1:stop]] or [0.0]
        e['vmax_after'] = max(speeds)
        e['coast_ms'] = trace['dt'] * 1e3 * next((q for q, s in enumerate(rows[e['end'] + 1:stop])
                                                  if max(s[7], s[8]) < 1e-3), len(speeds))
    return events


def exp_collide(args: argparse.Namespace) -> None:
    settings = model_settings(args.model, args.set)
    trace = collide(settings, args.theta, args.phi, (0.0, args.phase2), args.periods, args.r)
    ev = collisions(trace)
    print(f'model {args.model} {args.set or ""}: theta {args.theta} phi {args.phi} p2 {args.phase2}; '
          f'{len(ev)} collisions; r {trace["rows"][0][1] / BL:.3f} -> {trace["rows"][-1][1] / BL:.3f} BL '
          f'{trace["trouble"]}')
    cols = ['t0', 'dur_ms', 'kinds', 'J_normal', 'J_friction', 'J_plate', 'dr_contact_mm', 'vsep_end',
            'dr_after_mm', 'J_plate_after', 'vmax_after', 'coast_ms', 'depth_mm']
    print(' | '.join(cols))
    for e in ev[:args.show]:
        print(' | '.join(f'{e[c]:.4g}' if isinstance(e[c], float) else str(e[c]) for c in cols))


# ------------------------------------------------------------------ mechanism table

#: P4-style starts for the mechanism table: theta in quadrants 2 and 3 and parallel normals (the paper's
#: repulsive region), plus quadrant 1 / 4 antiparallel (its attractive region), r = 1.3 BL, phases 0 / 0.25.
MECH_STARTS = [(th, ph) for th in (120, 150, 210, 240) for ph in (0, 180)] + \
    [(th, ph) for th in (30, 60, 300, 330) for ph in (0, 180)]

VARIANTS: dict[str, dict[str, Any]] = {
    'default': dict(OLD_DEFAULT),
    'rigid motor': {**OLD_DEFAULT, 'position_gain': 1.0, 'servo_torque': 10.0},
    'chrono speed': {**OLD_DEFAULT, 'gait_speed': CHRONO_SPEED},
    'restitution 0.85 (robots, rvt 0.01)': {**OLD_DEFAULT, 'restitution': 0.85, 'x_plate_restitution': 0.0,
                                            'x_rvt': 0.01},
    'arm-arm friction 0.3': {**OLD_DEFAULT, 'friction_arm_arm': None},
    'body 24.8 g': {**OLD_DEFAULT, 'arm_mass': 0.005},
    'split impulse': {**OLD_DEFAULT, 'x_split_impulse': 1, 'x_split_threshold': -0.0001},
    'contact ERP 0.2': {**OLD_DEFAULT, 'contact_erp': 0.2},
    'dt 1/960': {**OLD_DEFAULT, 'time_step': 1 / 960},
    'authors': MODELS['authors'],
    'restitution 0.85 (robots, Bullet rvt 0.2)': {**OLD_DEFAULT, 'restitution': 0.85, 'restitution_body_plate': 0.0},
    'candidate': {**MODELS['authors'], 'servo_bandwidth': 72.0},
    'authors + arm-arm friction 1.5': {**MODELS['authors'], 'friction_arm_arm': 1.5},
}
VARIANTS['proposed'] = MODELS['proposed']
for _inv in (480, 960, 1920):   # the shipped defaults against the time step
    VARIANTS[f'shipped dt 1/{_inv}'] = {'time_step': 1.0 / _inv}
VARIANTS['proposed soft'] = MODELS['proposed soft']
for _torque in (0.05, 0.18, 10.0):   # the servo's torque limit at the default: shipped, a micro servo, rigid
    VARIANTS[f'shipped torque {_torque}'] = {'servo_torque': _torque}
for _it in (5, 10, 20, 50):     # solver iterations at the candidate step, robots kept flat
    VARIANTS[f'flat dt 1/480 it {_it}'] = {**MODELS['candidate'], 'tilt_inertia_scale': 100.0,
                                           'time_step': 1.0 / 480, 'solver_iterations': _it}
for _inv in (480, 960, 1920):   # the candidate's binding outcome against the time step
    VARIANTS[f'candidate dt 1/{_inv}'] = {**MODELS['candidate'], 'time_step': 1.0 / _inv}
    VARIANTS[f'default dt 1/{_inv}'] = {**OLD_DEFAULT, 'time_step': 1.0 / _inv}


def summarise_trace(trace: dict[str, Any], period: float) -> dict[str, Any]:
    """Per-trace figures: collisions, separating impulses, dr in contact vs coasting, final r, contact late."""
    ev = collisions(trace)
    rows = trace['rows']
    n_per = round(period / trace['dt'])
    last = rows[-10 * n_per:]
    return {'collisions': len(ev), 'r0': rows[0][1] / BL, 'r_end': rows[-1][1] / BL,
            'J_normal': sum(e['J_normal'] for e in ev), 'J_friction': sum(e['J_friction'] for e in ev),
            'J_plate': sum(s[4] for s in rows),
            'dr_contact_BL': sum(e['dr_contact_mm'] for e in ev) * 1e-3 / BL,
            'dr_coast_BL': sum(e['dr_after_mm'] for e in ev) * 1e-3 / BL,
            'vsep_max': max((e['vsep_end'] for e in ev), default=0.0),
            'coast_ms_med': float(np.median([e['coast_ms'] for e in ev])) if ev else 0.0,
            'touch_last10': any(s[5] for s in last), 'depth_max_mm': max((s[10] for s in rows), default=0) * 1e3,
            'trouble': trace['trouble']}


def exp_mechanism(args: argparse.Namespace) -> None:
    names = args.variants or list(VARIANTS)
    for name in names:
        settings = dict(VARIANTS[name])
        for phase2 in args.phase2:
            for theta, phi in MECH_STARTS:
                t0 = time.perf_counter()
                try:
                    trace = collide(settings, theta, phi, (phase2, phase2), args.periods)   # paper: same phase p
                except SceneError:
                    continue
                row = {'variant': name, 'theta': theta, 'phi': phi, 'phase': phase2, 'periods': args.periods,
                       **summarise_trace(trace, trace['period']), 'wall_s': time.perf_counter() - t0}
                append_csv('mechanism', row)
                print(' '.join(f'{k}={v:.3g}' if isinstance(v, float) else f'{k}={v}' for k, v in row.items()),
                      flush=True)


# ------------------------------------------------------------------ drift, pair, basin, dense


def drift_run(settings: dict[str, Any], heading_deg: float, periods: int = 20, skip: int = 2,
              alpha: float = 90.0) -> dict[str, Any]:
    """One robot alone: net drift per cycle (um) over ``periods`` after ``skip`` transient periods."""
    config, _, _ = make_config(settings)
    gait = gait_for(settings, alpha)
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, math.radians(heading_deg), a, a, gait),), name='single')
    world = make_world(settings, scene)
    per = world.ticks_for(gait.period)
    world.gaits.start(0.0)  # type: ignore[union-attr]
    xy, tilts = [], []
    t0 = time.perf_counter()
    trouble = ''
    try:
        for q in range(periods + skip + 1):
            if q >= skip:
                xy.append(world.physics.poses()[0, :2].copy())
            if q < periods + skip:
                for _ in range(per):   # tick by tick: the body's tilt at every control tick
                    world.run(1)
                    if q >= skip:
                        tilts.append(float(world.physics.state().tilt[0]))
    except SimTrouble as exc:
        trouble = str(exc)[:80]
    wall = time.perf_counter() - t0
    world.close()
    xy_a = np.array(xy)
    steps = np.linalg.norm(np.diff(xy_a, axis=0), axis=1)
    tilt_deg = np.degrees(np.array(tilts)) if tilts else np.array([math.nan])
    return {'heading': heading_deg, 'alpha': alpha, 'periods': periods,
            'net_um': float(np.linalg.norm(xy_a[-1] - xy_a[0]) / (len(xy_a) - 1) * 1e6),
            'step_um': float(steps.mean() * 1e6), 'step_se_um': float(steps.std(ddof=1) / math.sqrt(len(steps)) * 1e6),
            'dir_deg': float(math.degrees(math.atan2(*(xy_a[-1] - xy_a[0])[::-1]))),
            'tilt_max_deg': float(tilt_deg.max()), 'tilt_rms_deg': float(np.sqrt(np.mean(tilt_deg ** 2))),
            'wall_per_sim_s': wall / ((periods + skip) * gait.period), 'trouble': trouble}


def pair_run(settings: dict[str, Any], theta: float, phi: float, phases: tuple[float, float],
             periods: int = 100, r: float = 1.3) -> dict[str, Any]:
    """A pair from pair coordinates: per-period contact, r, COM; bound-run figures (contact-based)."""
    config, _, _ = make_config(settings)
    gait = gait_for(settings)
    scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases)
    world = make_world(settings, scene)
    per = world.ticks_for(gait.period)
    world.gaits.start(0.0)  # type: ignore[union-attr]
    touched, rs, phis, com = [], [], [], []
    t0 = time.perf_counter()
    trouble = ''
    try:
        for _ in range(periods):
            poses = world.physics.poses()
            pc_r, _, pc_phi = one_pair(poses[0], poses[1])
            com.append(poses[:, :2].mean(axis=0))
            t_any = False
            for _ in range(per):
                world.tick()
                if not t_any and world.physics.robot_contacts()[0, 1]:
                    t_any = True
            touched.append(t_any)
            rs.append(pc_r / BL)
            phis.append(math.degrees(pc_phi))
        poses = world.physics.poses()
        com.append(poses[:, :2].mean(axis=0))
    except SimTrouble as exc:
        trouble = str(exc)[:80]
    wall = time.perf_counter() - t0
    world.close()
    tt = np.array(touched, dtype=bool)
    n = len(tt)
    # longest run of touching periods (gaps of one period allowed: a missed sample is not an unbinding)
    best, best_start, cur, start, miss = 0, 0, 0, 0, 0
    for q in range(n):
        if tt[q]:
            if cur == 0:
                start = q
            cur, miss = q - start + 1, 0
        else:
            miss += 1
            if miss > 1:
                cur = 0
        if cur > best:
            best, best_start = cur, start
    com_a = np.array(com)
    late = com_a[n // 2:]
    rs_a = np.array(rs)
    half = rs_a[n // 2:] if n else rs_a
    phis_a = np.radians(np.array(phis[n // 2:]))
    return {'theta0': theta, 'phi0': phi, 'p1': phases[0], 'p2': phases[1], 'periods': periods, 'ran': n,
            'touch': int(tt.sum()), 'bound_run': best, 'bound_to_end': bool(n and best_start + best >= n - 1),
            'touch_last10': bool(tt[-10:].any()) if n else False,
            'r_end': rs_a[-1] if n else math.nan, 'r_mean_late': float(half.mean()) if n else math.nan,
            'phi_late': float(math.degrees(math.atan2(np.sin(phis_a).mean(), np.cos(phis_a).mean())) % 360)
            if n else math.nan,
            'travel_W': float(np.linalg.norm(com_a[-1] - com_a[0]) / BL),
            'late_travel_W': float(np.linalg.norm(late[-1] - late[0]) / BL) if len(late) > 1 else 0.0,
            'wall_per_sim_s': wall / max(1e-9, n * gait.period), 'trouble': trouble}


def dense_run(settings: dict[str, Any], seed: int, periods: int, n: int = 7, jitter: float = 0.0,
              sample_every: int = 6) -> dict[str, Any]:
    """A dense scene run through the batch loop's metrics: trouble, max depth, gliders (contacts + 1.6 BL)."""
    from smarticle_tracking.gliders import GliderClass, GliderConfig, analyse_gliders
    config, _, _ = make_config(settings)
    gait = gait_for(settings)
    scene = dense_scene(config.robot, gait, n=n, seed=seed, phase_jitter=jitter)
    world = make_world(settings, scene)
    per = world.ticks_for(gait.period)
    ticks = per * periods
    times, poses, contacts = [], [], []
    deepest = 0.0
    world.gaits.start(0.0)  # type: ignore[union-attr]
    t0 = time.perf_counter()
    trouble = ''
    iu = np.triu_indices(n, 1)
    try:
        for i in range(ticks):
            world.tick()
            if i % sample_every == 0:
                times.append(world.time)
                poses.append(world.physics.poses().copy())
                contacts.append(world.physics.robot_contacts()[iu])
                deepest = max(deepest, world.physics.max_penetration()[1])
    except SimTrouble as exc:
        trouble = str(exc)[:100]
    wall = time.perf_counter() - t0
    world.close()
    row: dict[str, Any] = {'seed': seed, 'n': n, 'jitter': jitter, 'periods': periods,
                           'sim_s': times[-1] if times else 0.0, 'wall_s': wall,
                           'x_real_time': (times[-1] if times else 0.0) / wall, 'deepest_mm': deepest * 1e3,
                           'trouble': trouble}
    if n == 7 and len(times) > per:
        cfg = GliderConfig(period=gait.period, r_bind=R_BIND_BL * BL, min_periods=30, body_length=BL, width=BL)
        pos = np.array(poses)
        an = analyse_gliders(np.array(times), pos, cfg, contacts=np.array(contacts))
        gl = an.gliders
        # isolated: bound >= 100 periods and, in >= 90 % of the frames of its bound run, no third robot's
        # centre within 2 W of either member's centre (the "no third robot near")
        iso = 0
        best_dist = 0.0
        t_arr = np.array(times)
        for g in gl:
            if g.lifetime_periods < 100:
                continue
            i, j = g.i, g.j
            others = [k for k in range(n) if k not in (i, j)]
            sel = (t_arr >= g.start_time) & (t_arr < g.end_time)
            a = pos[sel][:, others, None, :2]
            b = pos[sel][:, None, [i, j], :2]
            near = (np.linalg.norm(a - b, axis=3) < 2 * BL).any(axis=(1, 2))
            if sel.any() and near.mean() <= 0.1:
                iso += 1
            best_dist = max(best_dist, g.distance / BL)
        row.update(gliders_30=len(gl), gliders_100=sum(g.lifetime_periods >= 100 for g in gl), isolated_100=iso,
                   best_dist_W=best_dist,
                   c1_lives=' '.join(str(g.lifetime_periods) for g in gl if g.glider_class is GliderClass.C1),
                   c2_lives=' '.join(str(g.lifetime_periods) for g in gl if g.glider_class is GliderClass.C2))
    return row


def seeds_arg(text: str) -> list[int]:
    if '-' in text:
        a, b = text.split('-')
        return list(range(int(a), int(b) + 1))
    return [int(x) for x in text.split(',')]


def exp_drift(args: argparse.Namespace) -> None:
    for dtinv in args.dt:
        settings = model_settings(args.model, (args.set or []) + [f'time_step=1/{dtinv}'])
        for h in args.headings:
            row = {'model': args.model, 'set': ';'.join(args.set or []), 'dt_inv': dtinv,
                   **drift_run(settings, h, args.periods, alpha=args.alpha)}
            append_csv(args.name or 'drift', row)
            print(row, flush=True)


def exp_pair(args: argparse.Namespace) -> None:
    for dtinv in args.dt:
        settings = model_settings(args.model, (args.set or []) + [f'time_step=1/{dtinv}'])
        for theta, phi in args.starts:
            for p2 in args.phase2:
                try:
                    row = {'model': args.model, 'set': ';'.join(args.set or []), 'dt_inv': dtinv,
                           **pair_run(settings, theta, phi, (0.0, p2), args.periods)}
                except SceneError:
                    continue
                append_csv(args.name or 'pair', row)
                print(row, flush=True)


def exp_basin(args: argparse.Namespace) -> None:
    settings = model_settings(args.model, (args.set or []) + ([f'time_step=1/{args.dt}'] if args.dt else []))
    for p in args.phase:
        for theta in np.arange(0, 360, args.step):
            for phi in np.arange(0, 360, args.step):
                try:
                    row = {'model': args.model, 'set': ';'.join(args.set or []),
                           'dt_inv': round(1.0 / make_config(settings)[0].physics.time_step),
                           'phase': p, **pair_run(settings, float(theta), float(phi), (p, p), args.periods)}
                except SceneError:
                    continue
                append_csv(args.name or 'basin', row)
                print(row, flush=True)


def exp_dense(args: argparse.Namespace) -> None:
    settings = model_settings(args.model, args.set)
    for seed in seeds_arg(args.seeds):
        row = {'model': args.model, 'set': ';'.join(args.set or []), **dense_run(settings, seed, args.periods, args.n,
                                                                           args.jitter)}
        append_csv(args.name or 'dense', row)
        print(row, flush=True)


# ------------------------------------------------------------------ figures


def _plt() -> Any:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    return plt


def fig_trace(theta: float = 330.0, phi: float = 180.0, periods: float = 3.0) -> Path:
    """r(t) and cumulative separating impulses of one pair start under three models."""
    plt = _plt()
    fig, axes = plt.subplots(2, 3, figsize=(13, 6), sharex=True)
    for col, name in enumerate(('default', 'authors', 'candidate')):
        tr = collide(MODELS[name], theta, phi, (0.0, 0.0), periods)
        rows = np.array([(s[0], s[1], s[2], s[3], s[4]) for s in tr['rows']])
        ax = axes[0, col]
        ax.plot(rows[:, 0], rows[:, 1] / BL, 'k-')
        touch = np.array([s[5] for s in tr['rows']])
        ax.fill_between(rows[:, 0], rows[:, 1].min() / BL, rows[:, 1].max() / BL, where=touch, color='orange',
                        alpha=0.3, label='robot-robot contact')
        ax.set_title(f'{name}: theta {theta:g}, phi {phi:g}, phases 0/0')
        ax.set_ylabel('r (BL)')
        ax.legend(fontsize=7)
        ax = axes[1, col]
        for k, lab in ((2, 'robot-robot normal'), (3, 'robot-robot friction'), (4, 'body-plate friction')):
            ax.plot(rows[:, 0], np.cumsum(rows[:, k]) * 1e3, label=lab)
        ax.set_ylabel('cumulative separating impulse (mN s)')
        ax.set_xlabel('t (s)')
        ax.legend(fontsize=7)
    fig.tight_layout()
    path = OUT / 'collision_trace.png'
    fig.savefig(path, dpi=110)
    return path


def fig_drift() -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    groups: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for name in ('drift', 'drift_bw'):
        for r in read_csv(name):
            groups.setdefault((r['model'], r['set'], r['heading']), []).append((float(r['dt_inv']), float(r['net_um'])))
    cmap = plt.get_cmap('tab20')
    for idx, ((model, st, head), pts) in enumerate(sorted(groups.items())):
        pts.sort()
        x, y = zip(*pts, strict=True)
        ax.plot([1 / v for v in x], y, 'os^vD<>'[idx % 7] + '-', color=cmap(idx % 20),
                label=f'{model} {st} heading {float(head):g}')
    ax.axhline(75, color='k', ls='--', lw=0.8, label='paper 75 um')
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('time step (s)')
    ax.set_ylabel('drift per cycle (um)')
    ax.legend(fontsize=6)
    fig.tight_layout()
    path = OUT / 'drift_vs_dt.png'
    fig.savefig(path, dpi=110)
    return path


def fig_mechanism() -> Path:
    plt = _plt()
    rows = read_csv('mechanism')
    names = list(dict.fromkeys(r['variant'] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    frac, lo, hi, jn, jf, jp = [], [], [], [], [], []
    for v in names:
        rs = [r for r in rows if r['variant'] == v]
        k = sum(r['touch_last10'] == 'True' for r in rs)
        a, b = wilson(k, len(rs))
        frac.append(k / len(rs))
        lo.append(k / len(rs) - a)
        hi.append(b - k / len(rs))
        jn.append(np.mean([float(r['J_normal']) for r in rs]) * 1e3)
        jf.append(np.mean([float(r['J_friction']) for r in rs]) * 1e3)
        jp.append(np.mean([float(r['J_plate']) for r in rs]) * 1e3)
    y = np.arange(len(names))
    axes[0].barh(y, frac, xerr=[lo, hi], color='tab:blue')
    axes[0].set_yticks(y, names, fontsize=7)
    axes[0].set_xlabel('fraction of starts still touching in the last 10 of 20 periods (95 % Wilson)')
    axes[1].barh(y - 0.25, jn, 0.25, label='robot-robot normal')
    axes[1].barh(y, jf, 0.25, label='robot-robot friction')
    axes[1].barh(y + 0.25, jp, 0.25, label='body-plate friction')
    axes[1].set_yticks(y, names, fontsize=7)
    axes[1].set_xlabel('separating impulse per start, 20 periods (mN s; + = apart)')
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    path = OUT / 'mechanism.png'
    fig.savefig(path, dpi=110)
    return path


def fig_knee() -> Path:
    """Run time against error: drift (candidate, 90 deg) and the binding fraction of the 22-start grid."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for model, st, head, ax_i in (('candidate', '', '90.0', 0), ('candidate', '', '0.0', 0),
                                  ('default', 'servo_bandwidth=72', '90.0', 0), ('default', '', '90.0', 0),
                                  ('rigid', '', '90.0', 0)):
        pts = sorted((int(r['dt_inv']), float(r['net_um']), float(r['wall_per_sim_s'])) for r in read_csv('drift')
                     if r['model'] == model and r['set'] == st and r['heading'] == head)
        if len(pts) < 3:
            continue
        lim = richardson([(n, v) for n, v, _ in pts])
        err = [abs(v - lim) / abs(lim) * 100 for _, v, _ in pts]
        ax = axes[ax_i]
        ax.plot([w for *_, w in pts], err, 'o-', label=f'{model} {st} heading {float(head):g}')
        for (n, _, w), e in zip(pts, err, strict=True):
            ax.annotate(f'1/{n}', (w, e), fontsize=6)
    axes[0].axhline(10, color='k', ls='--', lw=0.8)
    axes[0].set_xscale('log')
    axes[0].set_yscale('log')
    axes[0].set_xlabel('wall s per simulated s (one robot, shared machine)')
    axes[0].set_ylabel('|drift - Richardson limit| (%)')
    axes[0].legend(fontsize=6)
    rows = read_csv('mechanism')
    for base, names in (('candidate', ['candidate', 'candidate dt 1/480', 'candidate dt 1/960', 'candidate dt 1/1920']),
                        ('default', ['default', 'default dt 1/480', 'dt 1/960', 'default dt 1/1920'])):
        xs, ys, lo, hi = [], [], [], []
        for name in names:
            rs = [r for r in rows if r['variant'] == name]
            if not rs:
                continue
            k = sum(r['touch_last10'] == 'True' for r in rs)
            a, b = wilson(k, len(rs))
            xs.append(np.mean([float(r['wall_s']) for r in rs]) / (float(rs[0]['periods']) * GAIT_PERIOD))
            ys.append(k / len(rs))
            lo.append(k / len(rs) - a)
            hi.append(b - k / len(rs))
        axes[1].errorbar(xs, ys, yerr=[lo, hi], fmt='o-', capsize=3, label=base)
        for x, y, name in zip(xs, ys, names, strict=False):
            axes[1].annotate(name.split()[-1] if 'dt' in name else '1/240', (x, y), fontsize=6)
    axes[1].set_xscale('log')
    axes[1].set_xlabel('wall s per simulated s (pair)')
    axes[1].set_ylabel('fraction of 22 starts touching late (95 % Wilson)')
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    path = OUT / 'knee.png'
    fig.savefig(path, dpi=110)
    return path


def basin_summary(name: str = 'basin') -> list[str]:
    """Quadrant / normal-orientation summary of a basin scan (bound = contact in the last 10 periods)."""
    rows = read_csv(name)
    out = []
    for model_set in dict.fromkeys((r['model'], r['set']) for r in rows):
        for phase in sorted({r['phase'] for r in rows}):
            rs = [r for r in rows if (r['model'], r['set']) == model_set and r['phase'] == phase]
            if not rs:
                continue

            def frac(sel: list[dict[str, str]], key: str = 'touch_last10') -> str:
                k = sum(r[key] == 'True' for r in sel)
                a, b = wilson(k, len(sel))
                return f'{k}/{len(sel)} ({a:.2f}-{b:.2f})'
            q14 = [r for r in rs if float(r['theta0']) < 90 or float(r['theta0']) >= 270]
            q23 = [r for r in rs if 90 <= float(r['theta0']) < 270]
            anti = [r for r in rs if abs(float(r['phi0']) - 180) <= 45]
            par = [r for r in rs if min(float(r['phi0']), 360 - float(r['phi0'])) <= 45]
            q14a = [r for r in q14 if r in anti]
            q23a = [r for r in q23 if r in anti]
            full = sum(r['bound_to_end'] == 'True' and int(r['bound_run']) >= 65 for r in rs)
            r2 = sum(float(r['r_end']) < 2.0 for r in rs)
            out.append(f"| {model_set[0]} {model_set[1]} | {phase} | {len(rs)} | {frac(rs)} | {full} | {r2} | "
                       f"{frac(q14)} | "
                       f"{frac(q23)} | {frac(anti)} | {frac(par)} | {frac(q14a)} | {frac(q23a)} |")
    return out


def fig_basin(name: str = 'basin') -> Path:
    plt = _plt()
    rows = read_csv(name)
    phases = sorted({r['phase'] for r in rows})
    fig, axes = plt.subplots(1, max(1, len(phases)), figsize=(5.5 * max(1, len(phases)), 5))
    axes = np.atleast_1d(axes)
    for ax, phase in zip(axes, phases, strict=False):
        rs = [r for r in rows if r['phase'] == phase]
        th = [float(r['theta0']) for r in rs]
        ph = [float(r['phi0']) for r in rs]
        col = ['tab:pink' if r['touch_last10'] == 'True' else 'tab:blue' for r in rs]
        ax.scatter(th, ph, c=col, s=120, marker='s')
        ax.set_xlabel('theta (deg)')
        ax.set_ylabel('phi (deg)')
        ax.set_xticks(range(0, 361, 90))
        ax.set_yticks(range(0, 361, 90))
        ax.set_title(f'{rs[0]["model"]} {rs[0]["set"]}, p = {phase}: pink bound (contact in last 10 of '
                     f'{rs[0]["periods"]} periods), blue repelled, blank inadmissible', fontsize=7)
    fig.tight_layout()
    path = OUT / f'{name}.png'
    fig.savefig(path, dpi=110)
    return path


def exp_figures(args: argparse.Namespace) -> None:
    for f in args.which:
        print({'trace': fig_trace, 'drift': fig_drift, 'mechanism': fig_mechanism, 'knee': fig_knee, 'basin': fig_basin,
               'basin_default': lambda: fig_basin('basin_default')}[f]())


# ------------------------------------------------------------------ tables for docs/physics_study.md


def richardson(points: list[tuple[float, float]]) -> float:
    """First-order Richardson limit from the two finest (dt_inv, value) points (dt halving)."""
    pts = sorted(points)
    if len(pts) < 2:
        return math.nan
    (n1, f1), (n2, f2) = pts[-2], pts[-1]
    ratio = n2 / n1
    return f2 + (f2 - f1) / (ratio - 1.0)


def exp_tables(args: argparse.Namespace) -> None:
    groups: dict[tuple[str, str, str], list[tuple[float, float, float]]] = {}
    for name in ('drift', 'drift_bw', 'drift_cone'):
        for r in read_csv(name):
            groups.setdefault((r['model'], r['set'], r['heading']), []).append(
                (float(r['dt_inv']), float(r['net_um']), float(r['wall_per_sim_s'])))
    print('| model | setting | heading (deg) | drift per cycle (um) at dt = 1/240, 1/480, 1/960, 1/1920, 1/3840 s '
          '| Richardson limit | coarsest dt within 10 % |')
    print('| --- | --- | ---: | --- | ---: | --- |')
    for (model, st, head), pts in sorted(groups.items()):
        by = {int(n): v for n, v, _ in pts}
        lim = richardson([(n, v) for n, v, _ in pts])
        coarse = next((n for n in sorted(by) if all(abs(by[m] - lim) <= 0.1 * abs(lim) for m in by if m >= n)), None)
        cells = ', '.join(f'{by[n]:.1f}' if n in by else '-' for n in (240, 480, 960, 1920, 3840))
        print(f'| {model} | {st or "-"} | {float(head):g} | {cells} | {lim:.1f} | '
              f'{"1/" + str(coarse) if coarse else "none"} |')
    rows = read_csv('pair')
    if rows:
        print('\n| dt | start (theta, phi, p2) | touching periods / 100 | longest touching run | r late (BL) | '
              'phi late | travel (W) | wall s per sim s |')
        print('| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |')
        for r in rows:
            print(f"| 1/{r['dt_inv']} | {float(r['theta0']):g}, {float(r['phi0']):g}, {float(r['p2']):g} | "
                  f"{r['touch']} | "
                  f"{r['bound_run']} | {float(r['r_mean_late']):.3f} | {float(r['phi_late']):.0f} | "
                  f"{float(r['travel_W']):.2f} | {float(r['wall_per_sim_s']):.3f} |")
    rows = read_csv('mechanism')
    if rows:
        print('\n| variant | starts | touching in last 10 of 20 periods (95 % Wilson) | r_end mean +- se (BL) | '
              'r_end >= 1.6 BL | J normal | J friction (robot-robot) | J plate | dr in contact / after (BL) | '
              'max v_sep (m/s) | max depth (mm) |')
        print('| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | --- | ---: | ---: |')
        for v in dict.fromkeys(r['variant'] for r in rows):
            rs = [r for r in rows if r['variant'] == v]
            k = sum(r['touch_last10'] == 'True' for r in rs)
            lo, hi = wilson(k, len(rs))
            re = np.array([float(r['r_end']) for r in rs])
            m = lambda key, rs=rs: np.mean([float(r[key]) for r in rs]) * 1e3   # noqa: E731
            print(f"| {v} | {len(rs)} | {k} ({lo:.2f}-{hi:.2f}) | "
                  f"{re.mean():.2f} +- {re.std(ddof=1) / math.sqrt(len(re)):.2f} | "
                  f"{int((re >= R_BIND_BL).sum())} | {m('J_normal'):.0f} | {m('J_friction'):.0f} | "
                  f"{m('J_plate'):.0f} | "
                  f"{m('dr_contact_BL') / 1e3:.2f} / {m('dr_coast_BL') / 1e3:.2f} | "
                  f"{max(float(r['vsep_max']) for r in rs):.2f} | {max(float(r['depth_max_mm']) for r in rs):.1f} |")
    lines = basin_summary() + basin_summary('basin_default')
    if lines:
        print('\n| model | phase | admissible | bound (contact in last 10) | '
              'bound >= 65 of 75 periods to the end | r_end < 2 BL | '
              'quadrants 1+4 | quadrants 2+3 | antiparallel (phi 135-225) | parallel (phi <= 45 or >= 315) | '
              'Q1+4 antiparallel | Q2+3 antiparallel |')
        print('| --- | --- | ---: | --- | ---: | ---: | --- | --- | --- | --- | --- | --- |')
        print('\n'.join(lines))
    for name in ('dense7', 'dense50'):
        rows = read_csv(name)
        if not rows:
            continue
        print(f'\n{name}:')
        for st, jit in sorted({(r['model'] + ' ' + r['set'], r['jitter']) for r in rows}):
            rs = [r for r in rows if r['jitter'] == jit and r['model'] + ' ' + r['set'] == st]
            k = sum(bool(r['trouble']) for r in rs)
            lo, hi = wilson(k, len(rs))
            line = (f"{st}, jitter {jit}: {len(rs)} trials, trouble stops {k} (95 % Wilson {lo:.2f}-{hi:.2f}), "
                    f"deepest overlap max {max(float(r['deepest_mm']) for r in rs):.2f} mm, "
                    f"x real time {np.mean([float(r['x_real_time']) for r in rs]):.1f}")
            if 'isolated_100' in rs[0] and rs[0].get('isolated_100', '') != '':
                iso = sum(int(r['isolated_100'] or 0) > 0 for r in rs)
                g100 = sum(int(r['gliders_100'] or 0) > 0 for r in rs)
                a, b = wilson(iso, len(rs))
                c1 = [int(x) for r in rs for x in r['c1_lives'].split()]
                c2 = [int(x) for r in rs for x in r['c2_lives'].split()]
                line += (f"; trials with a pair bound >= 100 periods {g100}; "
                         f"with an isolated one {iso} ({a:.2f}-{b:.2f}); "
                         f"C1 gliders {len(c1)} median life {np.median(c1) if c1 else float('nan'):.0f}; "
                         f"C2 {len(c2)} median {np.median(c2) if c2 else float('nan'):.0f}; best travel "
                         f"{max(float(r['best_dist_W'] or 0) for r in rs):.2f} W")
            print(line)
            for r in rs:
                if r['trouble']:
                    print('   seed', r['seed'], r['trouble'])


def exp_impact(args: argparse.Namespace) -> None:
    """The restitution Bullet gives a head-on impact of two robot bodies, against the meeting point within a
    step (``smarticle_sim.impact``), for each ERP:restitution pair, step and speed: table, CSV and PNG."""
    from smarticle_sim.impact import impact_sweep, summary

    base, _, _ = make_config(model_settings('shipped', args.set))
    rows: list[dict[str, Any]] = []
    curves: dict[str, list[float]] = {}
    for pair in args.pairs:
        erp, _, e = pair.partition(':')
        for dtinv in args.dt:
            config, _, _ = make_config(model_settings('shipped', (args.set or []) + [
                f'contact_erp={erp}', f'restitution={e}', f'time_step=1/{dtinv}']))
            for speed in args.speeds:
                impacts = impact_sweep(config.physics, config.robot, speed, args.phases)
                stats = summary(impacts)
                overlap_mm = 1e3 * stats.pop('overlap_max')
                rows.append({'contact_erp': float(erp), 'restitution': float(e), 'dt_inv': dtinv, 'speed': speed,
                             **{k: round(v, 4) for k, v in stats.items()}, 'overlap_mm': round(overlap_mm, 3)})
                if dtinv == args.dt[0] and speed == args.speeds[0]:
                    curves[f'ERP {erp}, restitution {e}'] = [i.restitution for i in impacts]
    print(f'head-on impact of two robot bodies ({base.robot.total_mass * 1e3:.1f} g each), {args.phases} meeting '
          f'points evenly spread over one step; effective restitution = separation / approach speed')
    print('| contact ERP | restitution set | step | speed (m/s) | effective: mean | sd | min | max | overlap (mm) |')
    print('| ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |')
    for r in rows:
        print(f"| {r['contact_erp']:g} | {r['restitution']:g} | 1/{r['dt_inv']} s | {r['speed']:g} | {r['mean']:.3f} | "
              f"{r['sd']:.3f} | {r['min']:.3f} | {r['max']:.3f} | {r['overlap_mm']:.2f} |")
    OUT.mkdir(parents=True, exist_ok=True)
    with (OUT / 'impact.csv').open('w', newline='') as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    phase = np.arange(args.phases) / args.phases
    for label, values in curves.items():
        ax.plot(phase, values, marker='o', ms=3, label=label)
    ax.axhline(0.85, color='k', lw=0.8, ls='--', label="the authors' 0.85")
    ax.set_xlabel('where in the step the bodies meet (fraction of a step)')
    ax.set_ylabel('effective restitution')
    ax.set_title(f'head-on impact at {args.speeds[0]:g} m/s, step 1/{args.dt[0]} s')
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / 'impact.png', dpi=120)
    print(OUT / 'impact.csv', OUT / 'impact.png')


def main() -> None:
    """Entry point of ``smarticle-physics-study``: run one experiment of the study."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='experiment', required=True)
    p = sub.add_parser('collide')
    p.add_argument('--model', default='default', choices=list(MODELS))
    p.add_argument('--set', action='append')
    p.add_argument('--theta', type=float, default=150.0)
    p.add_argument('--phi', type=float, default=180.0)
    p.add_argument('--phase2', type=float, default=0.0)
    p.add_argument('--r', type=float, default=1.3)
    p.add_argument('--periods', type=float, default=5.0)
    p.add_argument('--show', type=int, default=30)
    p = sub.add_parser('mechanism')
    p.add_argument('--variants', nargs='*')
    p.add_argument('--phase2', type=float, nargs='*', default=[0.0])
    p.add_argument('--periods', type=float, default=20.0)
    for name in ('drift', 'pair', 'basin', 'dense'):
        p = sub.add_parser(name)
        p.add_argument('--model', default='default', choices=list(MODELS))
        p.add_argument('--set', action='append')
        p.add_argument('--name', default=None, help='CSV name (default: the experiment)')
        p.add_argument('--periods', type=int, default={'drift': 20, 'pair': 100, 'basin': 75, 'dense': 300}[name])
    sub.choices['drift'].add_argument('--dt', type=int, nargs='*', default=[240])
    sub.choices['drift'].add_argument('--headings', type=float, nargs='*', default=[90.0])
    sub.choices['drift'].add_argument('--alpha', type=float, default=90.0, help='alpha_max (deg)')
    sub.choices['pair'].add_argument('--dt', type=int, nargs='*', default=[240])
    sub.choices['pair'].add_argument('--starts', type=lambda t: tuple(float(x) for x in t.split(',')), nargs='*',
                                     default=[(330.0, 180.0)])
    sub.choices['pair'].add_argument('--phase2', type=float, nargs='*', default=[0.05])
    sub.choices['basin'].add_argument('--dt', type=int, default=0)
    sub.choices['basin'].add_argument('--step', type=float, default=30.0)
    sub.choices['basin'].add_argument('--phase', type=float, nargs='*', default=[0.0, 0.25])
    sub.choices['dense'].add_argument('--seeds', default='0-9')
    sub.choices['dense'].add_argument('--n', type=int, default=7)
    sub.choices['dense'].add_argument('--jitter', type=float, default=0.0)
    p = sub.add_parser('impact')
    p.add_argument('--set', action='append', help='PhysicsConfig field on top of the shipped model')
    p.add_argument('--pairs', nargs='*', default=['0.6:0.85', '0.2:0.76', '0.1:0.8', '0.6:0'],
                   help='contact ERP:restitution pairs')
    p.add_argument('--dt', type=int, nargs='*', default=[960, 480, 1920])
    p.add_argument('--speeds', type=float, nargs='*', default=[0.3, 0.1, 0.6])
    p.add_argument('--phases', type=int, default=16, help='meeting points per step')
    sub.add_parser('tables')
    p = sub.add_parser('figures')
    p.add_argument('which', nargs='*', default=['trace', 'drift', 'mechanism'])
    args = parser.parse_args()
    {'tables': exp_tables, 'figures': exp_figures, 'collide': exp_collide, 'mechanism': exp_mechanism,
     'drift': exp_drift, 'pair': exp_pair, 'impact': exp_impact,
     'basin': exp_basin, 'dense': exp_dense}[args.experiment](args)


if __name__ == '__main__':
    main()
