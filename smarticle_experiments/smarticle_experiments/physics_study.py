"""The physics study's measurements as trial kinds: collisions of a pair, a lone robot's drift, a pair's binding,
dense stability, head-on impacts (docs/physics_study.md).

Each measurement runs one world step by step with the instruments the study needs (contact impulses per
step, tilt per tick, contact per period) and returns a compact row; ``trials.py`` registers them as the
kinds ``study_collision``, ``study_drift``, ``study_pair``, ``study_dense`` and ``study_impact``, which
``smarticle-experiments physics-study`` runs on the engine into the store. A trial's ``settings`` is a flat
mapping of PhysicsConfig / RobotSpec fields on top of the shipped defaults, ``Diagnostics`` fields (the knobs
measured and not taken, raw Bullet knobs included: ``split_impulse``, ``split_threshold``, ``cfm``,
``cone_friction``, ``friction_erp``, ``plate_restitution``, ``link_contact_stiffness`` /
``link_contact_damping``, ``mass_model``, ``yaw_inertia_scale``, ``plate_friction_slip``, ``arm_ends``;
smarticle_sim.diagnostics) and ``gait_speed`` (the gait's servo speed, rad/s).
The named models of the study (its old default, 'authors', 'candidate', ...) are history: archive/README.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np
from smarticle_common.facts import BODY_LENGTH, R_BIND_BL
from smarticle_common.gait import GaitConfig
from smarticle_common.pairs import one_pair

from smarticle_sim.errors import SceneError, SimTrouble
from smarticle_sim.physics import Physics
from smarticle_sim.runner import Runner
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene, pair_scene
from smarticle_sim.settings import SimConfig

from .configs import DIAGNOSTIC_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS, make_config
from .quantities import theta_quadrants
from .errors import SpecError
from .results import (StudyCollisionResult, StudyDenseResult, StudyDriftResult, StudyImpactResult,
                      StudyInadmissibleResult, StudyPairResult, TrialResult)

#: Body length (m) of the robot the study measures (the small preset's): lengths in the rows are in BL.
BL = BODY_LENGTH


def split_settings(settings: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any], float | None]:
    """A study's flat settings as (PhysicsConfig fields, RobotSpec fields, Diagnostics fields, gait speed or None).

    A ``time_step`` is snapped to 1 / a whole number of Hz and, without a ``control_tick``, the tick becomes
    1/60 s when that is a whole number of steps, else one step. SpecError names an unknown setting.
    """
    physics = {k: v for k, v in settings.items() if k in PHYSICS_FIELDS}
    robot = {k: v for k, v in settings.items() if k in ROBOT_FIELDS}
    diagnostics = {k: v for k, v in settings.items() if k in DIAGNOSTIC_FIELDS}
    unknown = sorted(set(settings) - PHYSICS_FIELDS - ROBOT_FIELDS - DIAGNOSTIC_FIELDS - {'gait_speed'})
    if unknown:
        raise SpecError(f'unknown setting(s) {unknown}: not a PhysicsConfig / RobotSpec / Diagnostics field or '
                        'gait_speed')
    if 'time_step' in physics:
        dt = physics['time_step'] = 1.0 / round(1.0 / float(physics['time_step']))
        if 'control_tick' not in physics:   # a tick must be a whole number of steps: 1/60 s or one step
            physics['control_tick'] = 1.0 / 60.0 if round(1.0 / dt) % 60 == 0 else dt
    speed = settings.get('gait_speed')
    return physics, robot, diagnostics, None if speed is None else float(speed)


def study_config(settings: Mapping[str, Any]) -> tuple[SimConfig, float]:
    """(SimConfig, gait servo speed) of a settings mapping (``configs.make_config`` of the small preset); a gait
    speed above the servo's raises the servo's top speed to it."""
    physics, robot, diagnostics, speed = split_settings(settings)
    config = make_config('small', physics, robot, diagnostics=diagnostics)
    if speed is not None and speed > config.robot.servo_speed:
        config = make_config('small', physics, {**robot, 'servo_speed': speed}, diagnostics=diagnostics)
    return config, speed if speed is not None else config.robot.servo_speed


def make_world(settings: dict[str, Any], scene: Scene) -> Runner:
    """The runner (Bullet physics + gait controller) of ``scene`` with the settings and diagnostics applied."""
    return Runner.with_gaits(study_config(settings)[0], scene)


def bullet_world(run: Runner) -> Physics:
    """The Bullet world of ``run`` (the study's instruments read Bullet's contact points)."""
    assert isinstance(run.physics, Physics)
    return run.physics


def gait_for(settings: dict[str, Any], alpha_deg: float = 90.0, phase: float = 0.0) -> GaitConfig:
    """The square gait of a model."""
    _, speed = study_config(settings)
    return GaitConfig.from_degrees(alpha_deg, servo_speed=speed, phase=phase)


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
    config, _ = study_config(settings)
    gait = gait_for(settings, alpha)
    scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases)
    world = make_world(settings, scene)
    bullet = bullet_world(world)
    c = bullet.client
    b1, b2 = bullet.body_ids
    plate = bullet.plate_id
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


# ------------------------------------------------------------------ mechanism table

#: P4-style starts for the mechanism table: theta in quadrants 2 and 3 and parallel normals (the paper's
#: repulsive region), plus quadrant 1 / 4 antiparallel (its attractive region), r = 1.3 BL, phases 0 / 0.25.
MECH_STARTS = [(th, ph) for th in (120, 150, 210, 240) for ph in (0, 180)] + \
    [(th, ph) for th in (30, 60, 300, 330) for ph in (0, 180)]

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


# ------------------------------------------------------------------ drift, pair, basin, dense


def drift_run(settings: dict[str, Any], heading_deg: float, periods: int = 20, skip: int = 2,
              alpha: float = 90.0) -> dict[str, Any]:
    """One robot alone: net drift per cycle (um) over ``periods`` after ``skip`` transient periods."""
    config, _ = study_config(settings)
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
    config, _ = study_config(settings)
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
    config, _ = study_config(settings)
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


def richardson(points: list[tuple[float, float]]) -> float:
    """First-order Richardson limit from the two finest (dt_inv, value) points (dt halving)."""
    pts = sorted(points)
    if len(pts) < 2:
        return math.nan
    (n1, f1), (n2, f2) = pts[-2], pts[-1]
    ratio = n2 / n1
    return f2 + (f2 - f1) / (ratio - 1.0)


# ------------------------------------------------------------------ the trial kinds


def _settings(p: Mapping[str, Any]) -> dict[str, Any]:
    """A trial's settings mapping (copied)."""
    return dict(p.get('settings') or {})


def study_collision_trial(p: Mapping[str, Any], seed: int) -> StudyCollisionResult | StudyInadmissibleResult:
    """A pair from (``r_bl``, ``theta_deg``, ``phi_deg``), both robots at gait phase ``phase``, stepped with every
    contact impulse measured: collisions, separating impulses (N s), dr in contact and coasting (BL), contact in
    the last 10 periods (``summarise_trace``); an overlapping start is ``admissible: false``."""
    try:
        trace = collide(_settings(p), float(p['theta_deg']), float(p['phi_deg']), (float(p['phase']),) * 2,
                        float(p['periods']), float(p['r_bl']))
    except SceneError as exc:
        return StudyInadmissibleResult(admissible=False, why=str(exc), trouble='')
    return StudyCollisionResult(admissible=True, **summarise_trace(trace, trace['period']))


def study_drift_trial(p: Mapping[str, Any], seed: int) -> StudyDriftResult:
    """A lone robot at heading ``heading_deg``: net drift per cycle (um) after ``skip`` periods, its tilt."""
    return StudyDriftResult(**drift_run(_settings(p), float(p['heading_deg']), int(p['periods']), int(p['skip']),
                                        float(p['alpha_max_deg'])))


def study_pair_trial(p: Mapping[str, Any], seed: int) -> StudyPairResult | StudyInadmissibleResult:
    """A pair from pair coordinates at phases (``phase1``, ``phase2``): contact per period, the longest touching
    run, r and phi late, travel (``pair_run``); an overlapping start is ``admissible: false``."""
    try:
        row = pair_run(_settings(p), float(p['theta_deg']), float(p['phi_deg']),
                       (float(p['phase1']), float(p['phase2'])), int(p['periods']), float(p['r_bl']))
    except SceneError as exc:
        return StudyInadmissibleResult(admissible=False, why=str(exc), trouble='')
    return StudyPairResult(admissible=True, **row)


def study_dense_trial(p: Mapping[str, Any], seed: int) -> StudyDenseResult:
    """``robots`` robots densely packed (seeded), phase offsets within +-``jitter``: trouble, deepest overlap and,
    for 7 robots, gliders of >= 30 and >= 100 periods, isolated ones, C1 / C2 lifetimes (``dense_run``)."""
    return StudyDenseResult(**dense_run(_settings(p), seed, int(p['periods']), int(p['robots']),
                                        float(p['jitter']), int(p['sample_every'])))


def study_impact_trial(p: Mapping[str, Any], seed: int) -> StudyImpactResult:
    """Head-on impacts of two robot bodies at ``speed_m_s``, meeting at ``phases`` points spread over one step:
    the effective restitution (separation / approach speed) mean, sd, min, max and the deepest overlap (mm)."""
    from smarticle_sim.impact import impact_sweep, summary

    config, _ = study_config(_settings(p))
    impacts = impact_sweep(config.physics, config.robot, float(p['speed_m_s']), int(p['phases']))
    figures = summary(impacts)
    overlap_mm = 1e3 * figures.pop('overlap_max')
    return StudyImpactResult(**{k: round(v, 4) for k, v in figures.items()}, overlap_mm=round(overlap_mm, 3),
                             restitution_by_phase=[round(i.restitution, 4) for i in impacts], trouble='')


# ------------------------------------------------------------------ tables of the stored rows

R = TypeVar('R', bound=TrialResult)


@dataclass(frozen=True)
class StudyRow(Generic[R]):
    """One stored physics-study trial: its parameters, seed, physics rate and typed result."""

    params: Mapping[str, Any]       # the trial's merged parameters (``label``, ``settings``, the kind's own)
    seed: int
    dt_inv: int                     # physics rate (1 / time step, Hz)
    result: R

    @property
    def label(self) -> str:
        """The setting's name in the tables."""
        return str(self.params['label'])


def _admitted(rows: list[StudyRow[Any]], cls: type[R]) -> list[StudyRow[R]]:
    """The rows whose start ran (a start whose robots overlapped is ``StudyInadmissibleResult``)."""
    return [r for r in rows if isinstance(r.result, cls)]


def dt_inv(settings: Mapping[str, Any]) -> int:
    """The physics rate (1 / time step, Hz) of a settings mapping."""
    return round(1.0 / study_config(settings)[0].physics.time_step)


def _wilson_text(k: int, n: int) -> str:
    """``k/n (low-high)`` with the 95 % Wilson interval (``stats.wilson``)."""
    from .stats import wilson

    est = wilson(k, n)
    return f'{k}/{n} ({est.low:.2f}-{est.high:.2f})' if n else '0/0'


def drift_table(rows: list[StudyRow[StudyDriftResult]]) -> list[str]:
    """Drift per cycle against the time step per (label, heading), its Richardson limit and the coarsest step
    within 10 % of it."""
    groups: dict[tuple[str, float], dict[int, float]] = {}
    for r in rows:
        groups.setdefault((r.label, float(r.params['heading_deg'])), {})[r.dt_inv] = float(r.result.net_um)
    out = ['| setting | heading (deg) | drift per cycle (um) at dt = 1/240, 1/480, 1/960, 1/1920, 1/3840 s | '
           'Richardson limit | coarsest dt within 10 % |', '| --- | ---: | --- | ---: | --- |']
    for (label, heading), by in sorted(groups.items()):
        lim = richardson(list(by.items()))
        coarse = next((n for n in sorted(by) if all(abs(by[m] - lim) <= 0.1 * abs(lim) for m in by if m >= n)), None)
        cells = ', '.join(f'{by[n]:.1f}' if n in by else '-' for n in (240, 480, 960, 1920, 3840))
        out.append(f'| {label} | {heading:g} | {cells} | {lim:.1f} | {"1/" + str(coarse) if coarse else "none"} |')
    return out


def pair_table(rows: list[StudyRow[Any]]) -> list[str]:
    """One line per pair run: step, start, touching periods, longest touching run, r and phi late, travel."""
    out = ['| setting | dt | start (theta, phi, p2) | touching periods | longest touching run | r late (BL) | '
           'phi late | travel (W) |', '| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |']
    for r in _admitted(rows, StudyPairResult):
        p, res = r.params, r.result
        out.append(f"| {r.label} | 1/{r.dt_inv} | {p['theta_deg']:g}, {p['phi_deg']:g}, {p['phase2']:g} | "
                   f"{res.touch} / {res.ran} | {res.bound_run} | {res.r_mean_late:.3f} | {res.phi_late:.0f} | "
                   f"{res.travel_W:.2f} |")
    return out


def mechanism_table(rows: list[StudyRow[Any]]) -> list[str]:
    """Per setting: starts touching in the last 10 periods (Wilson), r at the end, the separating impulses."""
    out = ['| setting | starts | touching in the last 10 periods (95 % Wilson) | r_end mean +- se (BL) | '
           'r_end >= 1.6 BL | J normal | J friction (robot-robot) | J plate (mN s) | dr in contact / after (BL) | '
           'max v_sep (m/s) | max depth (mm) |',
           '| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | --- | ---: | ---: |']
    ran = _admitted(rows, StudyCollisionResult)
    for label in dict.fromkeys(r.label for r in rows):
        rs = [r.result for r in ran if r.label == label]
        if not rs:
            continue
        re = np.array([float(r.r_end) for r in rs])
        se = re.std(ddof=1) / math.sqrt(len(re)) if len(re) > 1 else math.nan

        def m(values: list[float]) -> float:
            return float(np.mean([float(v) for v in values]))
        out.append(f"| {label} | {len(rs)} | {_wilson_text(sum(bool(r.touch_last10) for r in rs), len(rs))} | "
                   f"{re.mean():.2f} +- {se:.2f} | {int((re >= R_BIND_BL).sum())} | "
                   f"{m([r.J_normal for r in rs]) * 1e3:.0f} | {m([r.J_friction for r in rs]) * 1e3:.0f} | "
                   f"{m([r.J_plate for r in rs]) * 1e3:.0f} | {m([r.dr_contact_BL for r in rs]):.2f} / "
                   f"{m([r.dr_coast_BL for r in rs]):.2f} | {max(float(r.vsep_max) for r in rs):.2f} | "
                   f"{max(float(r.depth_max_mm) for r in rs):.1f} |")
    return out


def basin_table(rows: list[StudyRow[Any]]) -> list[str]:
    """Per setting and phase: bound (contact in the last 10 periods) overall, by quadrant and normal orientation."""
    out = ['| setting | phase | admissible | bound (contact in last 10) | r_end < 2 BL | quadrants 1+4 | '
           'quadrants 2+3 | antiparallel (phi 135-225) | parallel (phi <= 45 or >= 315) |',
           '| --- | --- | ---: | --- | ---: | --- | --- | --- | --- |']
    ran = _admitted(rows, StudyPairResult)
    for label, phase in dict.fromkeys((r.label, r.params['phase1']) for r in rows):
        rs = [r for r in ran if (r.label, r.params['phase1']) == (label, phase)]

        def frac(sel: list[StudyRow[StudyPairResult]]) -> str:
            return _wilson_text(sum(bool(r.result.touch_last10) for r in sel), len(sel))
        q14 = [r for r in rs if theta_quadrants(r.params['theta_deg']) == '1, 4']
        q23 = [r for r in rs if theta_quadrants(r.params['theta_deg']) == '2, 3']
        anti = [r for r in rs if abs(r.params['phi_deg'] - 180) <= 45]
        par = [r for r in rs if min(r.params['phi_deg'], 360 - r.params['phi_deg']) <= 45]
        out.append(f"| {label} | {phase:g} | {len(rs)} | {frac(rs)} | "
                   f"{sum(float(r.result.r_end) < 2.0 for r in rs)} | {frac(q14)} | {frac(q23)} | {frac(anti)} | "
                   f"{frac(par)} |")
    return out


def dense_lines(rows: list[StudyRow[StudyDenseResult]]) -> list[str]:
    """Per setting and jitter: trouble stops (Wilson), deepest overlap, speed and, for 7 robots, the gliders."""
    out = []
    for label, jitter in sorted({(r.label, float(r.result.jitter)) for r in rows}):
        rs = [r.result for r in rows if (r.label, float(r.result.jitter)) == (label, jitter)]
        line = (f"{label}, jitter {jitter:g}: {len(rs)} trials, trouble stops "
                f"{_wilson_text(sum(bool(r.trouble) for r in rs), len(rs))}, deepest overlap max "
                f"{max(float(r.deepest_mm) for r in rs):.2f} mm, x real time "
                f"{np.mean([float(r.x_real_time) for r in rs]):.1f}")
        if all(r.isolated_100 is not None for r in rs):
            c1 = [int(x) for r in rs for x in str(r.c1_lives).split()]
            c2 = [int(x) for r in rs for x in str(r.c2_lives).split()]
            line += (f"; trials with a pair bound >= 100 periods {sum(int(r.gliders_100 or 0) > 0 for r in rs)}; "
                     f"with an isolated one {_wilson_text(sum(int(r.isolated_100 or 0) > 0 for r in rs), len(rs))}; "
                     f"C1 gliders {len(c1)} median life {np.median(c1) if c1 else math.nan:.0f}; "
                     f"C2 {len(c2)} median {np.median(c2) if c2 else math.nan:.0f}; best travel "
                     f"{max(float(r.best_dist_W or 0.0) for r in rs):.2f} W")
        out.append(line)
        out += [f"   seed {r.seed}: {r.trouble}" for r in rs if r.trouble]
    return out


def impact_table(rows: list[StudyRow[StudyImpactResult]]) -> list[str]:
    """Effective restitution of head-on impacts per contact ERP, restitution set, step and speed."""
    out = ['| setting | contact ERP | restitution set | step | speed (m/s) | effective: mean | sd | min | max | '
           'overlap (mm) |', '| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |']
    for r in rows:
        config = study_config(r.params['settings'])[0]
        res = r.result
        out.append(f"| {r.label} | {config.physics.contact_erp:g} | {config.physics.restitution:g} | "
                   f"1/{r.dt_inv} s | {r.params['speed_m_s']:g} | {res.mean:.3f} | {res.sd:.3f} | {res.min:.3f} | "
                   f"{res.max:.3f} | {res.overlap_mm:.2f} |")
    return out


#: The table of each study kind's stored rows.
TABLES = {'study_drift': drift_table, 'study_pair': pair_table, 'study_collision': mechanism_table,
          'study_dense': dense_lines, 'study_impact': impact_table}
