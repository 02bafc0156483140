"""The registry of trial kinds (``KINDS``): pure functions of (params, seed) that run one trial and return a
compact result. Every study of the package is a kind here, run by the one engine into the one store.

The other smarticle packages (sim, tracking, feedback) are imported by this module, ``configs`` and the
study modules its kinds call (``p6``, ``c2_harvest``, ``physics_study``), never by the engine, store,
statistics or report.

A trial function takes the merged parameter mapping of one trial (``KINDS[kind].defaults`` overridden by
the spec) and its seed, and returns a typed result (``results.TrialResult``) or a JSON-ready dict; it
never reads or writes shared state. Lengths in
the results are in body lengths (``_bl``) or in W (``_w``, W = BL for the smarticle), angles in degrees
(``_deg``), speeds as stated. ``trouble`` is the SimTrouble message that ended the trial early ('' if
none): such a trial still returns what it measured, and the report counts and lists it.

Gliders follow the glider analysis's rules (``smarticle_tracking.gliders``, docs/gliders.md): bound = r
under ``r_bind_bl`` (1.6 BL) in any frame of a period, from the poses; **isolated** = in at least 90 % of
its bound periods no third robot's centre comes within ``isolation_w`` W (default 2 W) of either robot's
centre. P1 counts trials with an isolated glider of at least ``positive_periods`` periods.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from smarticle_sim.batch import Recording, run_trial
from smarticle_sim.chrono_reference import (PAIR_CHRONO_DEFAULTS, SINGLE_CHRONO_DEFAULTS, ChronoSettings,
                                            ChronoUnavailable, driver_path, pair_chrono_trial,
                                            single_chrono_trial, trailing_true)
from smarticle_sim.errors import SceneError, SimError
from smarticle_sim.runner import ContactPeriods
from smarticle_sim.mujoco_engine import MujocoSettings, run_mujoco
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene, pair_scene
from smarticle_sim.settings import NoiseConfig, SimConfig
from smarticle_tracking.gliders import Glider, GliderConfig, analyse_gliders
from smarticle_tracking.msd import fit_msd_exponent, msd

from . import physics_study
from .configs import (config_of, make_config, make_gait,
                      noise_mapping)
from .errors import SpecError
from .results import (AccuracyResult, C2HarvestResult, DenseResult, InadmissiblePairResult, P6Result, PairResult,
                      SingleResult, TrialResult)

#: A trial kind's function: (merged parameters, seed) -> a typed result (or a JSON-ready dict).
TrialFunction = Callable[[Mapping[str, Any], int], 'TrialResult | dict[str, Any]']

#: The trial kinds stepped by MuJoCo (``smarticle_sim.mujoco_engine``) instead of Bullet.
MUJOCO_KINDS: frozenset[str] = frozenset({'pair_mujoco', 'single_mujoco'})
#: The trial kinds run by the Chrono reference driver (``smarticle_sim.chrono_reference``), where it is built.
CHRONO_KINDS: frozenset[str] = frozenset({'pair_chrono', 'single_chrono'})


# ------------------------------------------------------------------ glider measurements


def _rounded(values: np.ndarray, digits: int) -> list[Any]:
    """A nested list of rounded floats, NaN as None (JSON has no NaN)."""
    arr = np.round(np.asarray(values, dtype=float), digits)
    return [_rounded(row, digits) if np.ndim(row) else (None if not math.isfinite(row) else float(row))
            for row in arr]


def _finite(value: float) -> float | None:
    """A float, or None for NaN / inf."""
    return float(value) if math.isfinite(value) else None


def glider_record(g: Glider, period: float, bl: float) -> dict[str, Any]:
    """One glider as a JSON-ready dict (lengths in BL = W, angles in degrees)."""
    return {
        'i': g.i, 'j': g.j, 'class': g.glider_class.value, 'start_period': g.start_period,
        'lifetime_periods': g.lifetime_periods, 'ongoing': g.ongoing,
        'r_bl': _finite(g.r_mean / bl), 'theta_deg': _finite(math.degrees(g.theta_mean) % 360.0),
        'phi_deg': _finite(math.degrees(g.phi_mean) % 360.0), 'distance_w': _finite(g.distance / bl),
        'path_w': _finite(g.path_length / bl), 'v_com_w_per_period': _finite(g.v_com * period / bl),
        'beta': _finite(g.beta), 'isolated': g.isolated, 'isolation': round(g.isolation, 4),
        'com_path_w': _rounded(g.com_path / bl, 4),
    }


def analyse_recording(config: SimConfig, rec: Recording, period: float, p: Mapping[str, Any]) -> dict[str, Any]:
    """Gliders of a recording (the glider analysis's one bound rule, on poses) plus per-trial figures."""
    bl = config.robot.body_length
    gcfg = GliderConfig(period=period, r_bind=float(p['r_bind_bl']) * bl, min_periods=int(p['min_periods']),
                        isolation_distance=float(p['isolation_w']) * bl,
                        body_length=bl, width=bl)
    analysis = analyse_gliders(rec.time, rec.poses, gcfg)
    gliders = [glider_record(g, period, bl) for g in analysis.gliders]
    per = max(1, round(period / (config.physics.control_tick * rec.meta['sample_every'])))
    positive = int(p['positive_periods'])
    longest = max(gliders, key=lambda g: g['lifetime_periods'], default=None)
    return {
        'periods_run': (len(rec.time) - 1) / per if len(rec.time) else 0.0,
        'trouble': rec.trouble,
        'peak_tilt_deg': _finite(float(rec.meta.get('peak_tilt_deg', math.nan))),
        'peak_overlap_mm': _finite(float(rec.meta.get('peak_overlap_mm', math.nan))),
        'n_gliders': len(gliders),
        'positive': any(g['lifetime_periods'] >= positive for g in gliders),
        'positive_isolated': any(g['lifetime_periods'] >= positive and g['isolated'] for g in gliders),
        'longest_periods': longest['lifetime_periods'] if longest else 0,
        'longest_class': longest['class'] if longest else '',
        'longest_distance_w': longest['distance_w'] if longest else None,
        'gliders': gliders,
        'trajectory_bl': _rounded(rec.poses[::per, :, :2] / bl, 3) if p.get('trajectory', True) else [],
        'trajectory_dt': period,
    }


# ------------------------------------------------------------------ trial kinds


def dense_trial(p: Mapping[str, Any], seed: int) -> DenseResult:
    """P1/P2/P3: N robots densely packed, in phase (or jittered), for ``periods`` periods; its gliders."""
    config = config_of(p)
    gait = make_gait(config, p['alpha_max_deg'], p['servo_speed'])
    scene = dense_scene(config.robot, gait, n=int(p['robots']), seed=seed, phase_jitter=float(p['phase_jitter']))
    watch = ContactPeriods(gait.period) if p.get('contacts') else None
    rec = run_trial(config, scene, float(p['periods']), sample_every=int(p['sample_every']), record_contacts=False,
                    controllers=None if watch is None else (lambda physics, gaits: [watch]))
    result = analyse_recording(config, rec, gait.period, p)
    if watch is not None:
        add_contact_fractions(result['gliders'], watch.periods)
    return DenseResult(**result)


def add_contact_fractions(gliders: Sequence[dict[str, Any]], periods: Mapping[tuple[int, int], set[int]]) -> None:
    """Give each glider record ``contact_fraction``: the share of its bound periods in which its two robots
    touched at some physics step (a pair bound by r alone can sit still side by side without touching)."""
    for g in gliders:
        touched = periods.get((min(g['i'], g['j']), max(g['i'], g['j'])), set())
        span = range(g['start_period'], g['start_period'] + g['lifetime_periods'])
        g['contact_fraction'] = round(sum(q in touched for q in span) / max(len(span), 1), 4)


def pair_start(p: Mapping[str, Any], seed: int) -> tuple[float, float, float]:
    """The pair start (r BL, theta deg, phi deg): the spec's plus seeded uniform jitter ``start_jitter``."""
    jitter = np.asarray(p['start_jitter'], dtype=float)
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, size=3) if np.any(jitter) else np.zeros(3)
    return (float(p['r_bl'] + jitter[0] * u[0]), float(p['theta_deg'] + jitter[1] * u[1]),
            float(p['phi_deg'] + jitter[2] * u[2]))


def pair_trial(p: Mapping[str, Any], seed: int) -> PairResult | InadmissiblePairResult:
    """P4/P5: two robots from pair coordinates; binding at the end, travel, and the pair's gliders.
    ``hold_first``: robot 1's body held in place, its arms still following the gait (P4 read literally)."""
    return _pair(p, seed, mujoco=False)


def pair_mujoco_trial(p: Mapping[str, Any], seed: int) -> PairResult | InadmissiblePairResult:
    """The pair kind's trial stepped by MuJoCo instead of Bullet (``smarticle_sim.mujoco_engine``): the same
    robots, start and gait; soft contacts with an isotropic friction cone. ``mujoco`` sets ``MujocoSettings``
    fields. A period counts as colliding if the robots touched at any servo update (1/960 s) in it."""
    return _pair(p, seed, mujoco=True)


def _pair(p: Mapping[str, Any], seed: int, mujoco: bool) -> PairResult | InadmissiblePairResult:
    """The pair kind in either engine."""
    if mujoco and p['hold_first']:
        raise SpecError('hold_first: the MuJoCo pair kind has no held robot; use the pair kind (Bullet) or '
                        'pair_chrono')
    config = config_of(p)
    gait = make_gait(config, p['alpha_max_deg'], p['servo_speed'])
    r, theta, phi = pair_start(p, seed)
    start = {'r0_bl': r, 'theta0_deg': theta, 'phi0_deg': phi}
    try:
        scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi),
                           (0.0, float(p['phase2'])), seed=seed,
                           alpha_max2=gait.alpha_max + math.radians(float(p['alpha2_delta_deg'])),
                           hold_first=bool(p['hold_first']))
    except SceneError as exc:
        return InadmissiblePairResult(**start, admissible=False, why=str(exc), trouble='', gliders=[])
    per = max(1, round(gait.period / (config.physics.control_tick * int(p['sample_every']))))
    if mujoco:
        rec = run_mujoco(config, scene, float(p['periods']), int(p['sample_every']),
                         MujocoSettings(**dict(p.get('mujoco') or {})))
        touched = {q for q in range((len(rec.time) - 1) // per)
                   if rec.contacts[q * per + 1:(q + 1) * per + 1, 0, 1].any()}
    else:
        watch = ContactPeriods(gait.period)   # contact at every physics step: a kick lasts one to a few steps
        rec = run_trial(config, scene, float(p['periods']), sample_every=int(p['sample_every']), record_contacts=True,
                        controllers=lambda physics, gaits: [watch])
        touched = watch.periods.get((0, 1), set())
    out = analyse_recording(config, rec, gait.period, p)
    bl = config.robot.body_length
    touching = rec.contacts[:, 0, 1]
    r_all = np.hypot(*(rec.poses[:, 1, :2] - rec.poses[:, 0, :2]).T) / bl
    bound = [bool(touching[q * per:(q + 1) * per].any() or (r_all[q * per:(q + 1) * per] < p['r_bind_bl']).any())
             for q in range(len(touching) // per)]
    colliding = [q in touched for q in range(len(bound))]
    tail, colliding_tail = trailing_true(bound), trailing_true(colliding)
    com = rec.poses[::per, :, :2].mean(axis=1) / bl
    phi_end = (rec.poses[-1, 1, 2] - rec.poses[-1, 0, 2]) % (2.0 * math.pi)
    out.update(start, admissible=True, bound_tail_periods=tail,
               bound_at_end=tail >= int(p['bound_tail']),
               colliding_tail_periods=colliding_tail,
               colliding_at_end=colliding_tail >= int(p['bound_tail']),
               out_of_reach_at_end=bool(r_all[-1] * bl > 2.0 * config.robot.reach),
               late_w=float(np.linalg.norm(com[-1] - com[len(com) // 2])) if len(com) else 0.0,
               r_end_bl=float(r_all[-1]), phi_end_deg=math.degrees(phi_end))
    return PairResult(**out)


def single_trial(p: Mapping[str, Any], seed: int) -> SingleResult:
    """P7: one robot alone (heading drawn from the seed); drift per cycle in micrometres."""
    return _single(p, seed, mujoco=False)


def single_mujoco_trial(p: Mapping[str, Any], seed: int) -> SingleResult:
    """The single kind's trial stepped by MuJoCo (``mujoco`` sets ``MujocoSettings`` fields)."""
    return _single(p, seed, mujoco=True)


def _single(p: Mapping[str, Any], seed: int, mujoco: bool) -> SingleResult:
    """The single kind in either engine."""
    config = config_of(p)
    gait = make_gait(config, p['alpha_max_deg'], p['servo_speed'])
    heading = float(np.random.default_rng(seed).uniform(-math.pi, math.pi))
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, heading, a, a, gait),), name='single', seed=seed)
    if mujoco:
        rec = run_mujoco(config, scene, float(p['periods']), int(p['sample_every']),
                         MujocoSettings(**dict(p.get('mujoco') or {})))
    else:
        rec = run_trial(config, scene, float(p['periods']), sample_every=int(p['sample_every']))
    per = max(1, round(gait.period / (config.physics.control_tick * int(p['sample_every']))))
    xy = rec.poses[::per, 0, :2]
    cycles = max(len(xy) - 1, 1)
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    return SingleResult(heading_deg=math.degrees(heading), trouble=rec.trouble, cycles=len(xy) - 1,
                        drift_um_per_cycle=float(np.linalg.norm(xy[-1] - xy[0]) / cycles * 1e6),
                        step_um_per_cycle=float(steps.mean() * 1e6) if steps.size else None)


def p6_trial(p: Mapping[str, Any], seed: int) -> P6Result:
    """P6: a C2 pair of the feedback robot, open loop or with impact-halt feedback (the feedback package's trial).

    ``physics`` / ``robot`` replace fields of the feedback preset's PhysicsConfig / RobotSpec (a spec's
    ``physics:`` / ``robot:`` or grid keys ``physics.X`` / ``robot.X``); ``windows`` (feedback parameters,
    ``p6.window_values``) replaces the shipped impact windows; ``details`` adds the bound run's travel and
    the periods with contact (a step hook: the trajectory is the same).
    """
    from smarticle_experiments.p6 import Condition, run_pair_trial, start_base, windows_config

    noise = replace(NoiseConfig.none(), **noise_mapping(p.get('noise'))) if p.get('noise') else None
    details = bool(p.get('details'))
    trial = run_pair_trial(Condition(float(p['alpha_max_deg']), bool(p['feedback'])), seed, float(p['periods']),
                           feedback=windows_config(p['windows']) if p.get('windows') else None,
                           base=start_base(str(p['start'])), noise=noise, count_contacts=details,
                           robot_changes=dict(p.get('robot') or {}), physics_changes=dict(p.get('physics') or {}))
    return P6Result(lifetime_periods=int(trial.lifetime_periods), censored=bool(trial.censored),
                    halts=len(trial.halts), trouble=trial.trouble, r0_bl=trial.start[0], theta0_deg=trial.start[1],
                    phi0_deg=trial.start[2], final_r_bl=_finite(float(trial.r[-1])) if len(trial.r) else None,
                    travel_w=trial.travel_w if details else None,
                    contact_periods=[int(q) for q in trial.contact_periods] if details else None)


def c2_harvest_trial(p: Mapping[str, Any], seed: int) -> C2HarvestResult:
    """A dense open-loop trial of the feedback robot (in phase, as the paper's collectives start): every C2
    glider of at least ``min_periods`` sampled at its period boundaries after ``settle`` periods, with the
    pair's full state (``c2_harvest.harvest_trial``)."""
    from smarticle_experiments.c2_harvest import harvest_recording, sample_record

    samples, trouble = harvest_recording(seed, float(p['periods']), str(p['preset']), float(p['alpha_max_deg']),
                            int(p['robots']), int(p['min_periods']), int(p['settle']), int(p['sample_every']))
    return C2HarvestResult(samples=[sample_record(s) for s in samples],
                           gliders=len({(s.seed, min(s.i, s.j), max(s.i, s.j)) for s in samples}), trouble=trouble)


def accuracy_trial(p: Mapping[str, Any], seed: int) -> AccuracyResult:
    """Run time against error: one (physics rate, solver iterations) setting on a pair and a lone robot.

    Returns the pair's body-centre positions after 1 and 10 periods (BL), its mean separation r (BL),
    the lone robot's drift per cycle (um) and the wall time per simulated second of the pair run; the
    errors against the sweep's finest setting are computed by the report.
    """
    import time

    physics = {**dict(p.get('physics') or {}), 'time_step': 1.0 / float(p['rate_hz']),
               'control_tick': float(p['control_tick']), 'solver_iterations': int(p['solver_iterations'])}
    config = make_config(str(p['preset']), physics, dict(p.get('robot') or {}), dict(p.get('noise') or {}))
    gait = make_gait(config, p['alpha_max_deg'], p['servo_speed'])
    scene = pair_scene(config.robot, gait, float(p['r_bl']), math.radians(p['theta_deg']), math.radians(p['phi_deg']),
                       (0.0, float(p['phase2'])), seed=seed)
    every = max(1, round(0.05 / config.physics.control_tick))
    start = time.perf_counter()
    rec = run_trial(config, scene, float(p['periods']), sample_every=every)
    wall = time.perf_counter() - start
    bl = config.robot.body_length
    out: dict[str, Any] = {'trouble': rec.trouble, 'wall_per_sim_s': wall / max(float(rec.time[-1]), 1e-12)}
    for mark in (1, 10):
        k = int(np.argmin(np.abs(rec.time - mark * gait.period)))
        out[f'xy{mark}_bl'] = _rounded(rec.poses[k, :, :2] / bl, 7) if abs(rec.time[k] - mark * gait.period) < 0.06 \
            else None
    out['r_mean_bl'] = float(np.mean(np.hypot(*(rec.poses[:, 1, :2] - rec.poses[:, 0, :2]).T))) / bl
    single = single_trial({**p, 'physics': physics, 'periods': p['single_periods'], 'sample_every': 1}, seed)
    out['drift_um_per_cycle'] = single.drift_um_per_cycle
    if single.trouble:
        out['trouble'] = '; '.join(t for t in (out['trouble'], single.trouble) if t)
    return AccuracyResult(**out)


# ------------------------------------------------------------------ registry


@dataclass(frozen=True)
class TrialKind:
    """A trial kind: its function, its parameters with defaults, and the report sections it supports."""

    function: TrialFunction
    defaults: Mapping[str, Any]
    description: str


_COMMON: dict[str, Any] = {'preset': 'small', 'physics': {}, 'robot': {}, 'periods': 300.0,
                           'alpha_max_deg': 90.0, 'servo_speed': None}
_GLIDERS: dict[str, Any] = {'min_periods': 30, 'r_bind_bl': 1.6, 'isolation_w': 2.0, 'positive_periods': 100,
                            'trajectory': True}

#: The pair kinds' parameters (Bullet's and MuJoCo's take the same).
_PAIR: dict[str, Any] = {**_COMMON, **_GLIDERS, 'periods': 75.0, 'r_bl': 1.3, 'theta_deg': 0.0, 'phi_deg': 180.0,
                         'phase2': 0.0, 'start_jitter': [0.0, 0.0, 0.0], 'sample_every': 2, 'min_periods': 10,
                         'bound_tail': 5, 'alpha2_delta_deg': 0.0, 'hold_first': False}

#: The physics study's kinds: flat ``settings`` (physics_study.split_settings) and a ``label`` for its tables.
_STUDY: dict[str, Any] = {'settings': {}, 'label': 'shipped'}

KINDS: dict[str, TrialKind] = {
    'dense': TrialKind(dense_trial, {**_COMMON, **_GLIDERS, 'robots': 7, 'phase_jitter': 0.0, 'sample_every': 4,
                                     'contacts': False},
                       'N robots densely packed (P1, P2, P3)'),
    'pair': TrialKind(pair_trial, _PAIR, 'two robots from pair coordinates (P4 basin scan, P5 alpha_max sweep)'),
    'pair_mujoco': TrialKind(pair_mujoco_trial, {**_PAIR, 'mujoco': {}},
                             'the pair kind stepped by MuJoCo (cross-engine check; smarticle_sim.mujoco_engine)'),
    'single': TrialKind(single_trial, {**_COMMON, 'periods': 20.0, 'sample_every': 1},
                        'one robot alone, drift per cycle (P7)'),
    'single_mujoco': TrialKind(single_mujoco_trial, {**_COMMON, 'periods': 20.0, 'sample_every': 1, 'mujoco': {}},
                               'the single kind stepped by MuJoCo (cross-engine check)'),
    'pair_chrono': TrialKind(pair_chrono_trial, PAIR_CHRONO_DEFAULTS,
                             'two robots from pair coordinates in Chrono, the authors\' engine (cross-engine '
                             'check; smarticle_sim.chrono_reference, needs the Chrono build)'),
    'single_chrono': TrialKind(single_chrono_trial, SINGLE_CHRONO_DEFAULTS,
                               'one robot alone in Chrono, drift per cycle (cross-engine check; needs the Chrono '
                               'build)'),
    'p6': TrialKind(p6_trial, {'periods': 100.0, 'alpha_max_deg': 90.0, 'feedback': False, 'start': 'harvested',
                               'physics': {}, 'robot': {}, 'windows': {}, 'details': False},
                    'C2 pair of the feedback robot, open loop or feedback (P6; smarticle_experiments.p6)'),
    'c2_harvest': TrialKind(c2_harvest_trial, {'periods': 150.0, 'preset': 'feedback', 'alpha_max_deg': 90.0,
                                               'robots': 7, 'min_periods': 30, 'settle': 5, 'sample_every': 4},
                            'dense open-loop feedback robots: where their C2 gliders sit (smarticle_experiments.'
                            'c2_harvest)'),
    'study_collision': TrialKind(physics_study.study_collision_trial,
                                 {**_STUDY, 'r_bl': 1.3, 'theta_deg': 150.0, 'phi_deg': 180.0, 'phase': 0.0,
                                  'periods': 20.0},
                                 'physics study: a pair with every contact impulse measured (collision mechanism)'),
    'study_drift': TrialKind(physics_study.study_drift_trial,
                             {**_STUDY, 'heading_deg': 90.0, 'alpha_max_deg': 90.0, 'periods': 20.0, 'skip': 2},
                             'physics study: a lone robot\'s drift per cycle and tilt, tick by tick'),
    'study_pair': TrialKind(physics_study.study_pair_trial,
                            {**_STUDY, 'r_bl': 1.3, 'theta_deg': 330.0, 'phi_deg': 180.0, 'phase1': 0.0,
                             'phase2': 0.05, 'periods': 100.0},
                            'physics study: a pair\'s contact per period, touching run, r and travel'),
    'study_dense': TrialKind(physics_study.study_dense_trial,
                             {**_STUDY, 'robots': 7, 'jitter': 0.0, 'periods': 300.0, 'sample_every': 6},
                             'physics study: dense stability (trouble, overlap) and gliders'),
    'study_impact': TrialKind(physics_study.study_impact_trial, {**_STUDY, 'speed_m_s': 0.3, 'phases': 16},
                              'physics study: effective restitution of head-on impacts'),
    'accuracy': TrialKind(accuracy_trial, {**_COMMON, 'periods': 20.0, 'single_periods': 10.0, 'rate_hz': 240.0,
                                           'control_tick': 1.0 / 60.0, 'solver_iterations': 50, 'r_bl': 1.4,
                                           'theta_deg': 60.0, 'phi_deg': 180.0, 'phase2': 0.5},
                          'run time against error of one physics setting (pair + lone robot)'),
}


def resolve_kind(kind: str) -> TrialKind | None:
    """The built-in kind named ``kind``, or None for a user's ``module:function`` kind."""
    if kind in KINDS:
        return KINDS[kind]
    if ':' in kind:
        return None
    raise SpecError(f'kind {kind!r} is unknown; choose one of {", ".join(KINDS)} or give module:function')


def engine_missing(kind: str) -> str | None:
    """Why trials of ``kind`` cannot run on this machine (one line), or None if they can: the Chrono kinds
    need the Chrono driver (tools/chrono_reference/build_chrono.sh)."""
    if kind not in CHRONO_KINDS:
        return None
    try:
        driver_path()
    except ChronoUnavailable as exc:
        return str(exc)
    return None


def trial_function(kind: str) -> TrialFunction:
    """The function that runs a trial of ``kind`` (a built-in name or an importable ``module:function``)."""
    known = resolve_kind(kind)
    if known is not None:
        return known.function
    import importlib

    module, _, name = kind.partition(':')
    try:
        func = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise SpecError(f'kind {kind!r}: cannot import {name} from {module} ({exc})') from None
    if not callable(func):
        raise SpecError(f'kind {kind!r}: {name} is not callable')
    return func


def run_kind(kind: str, params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """Run one trial of ``kind`` and return its result in the stored form (a typed result's ``as_dict``)."""
    result = trial_function(kind)(params, seed)
    return result.as_dict() if isinstance(result, TrialResult) else dict(result)


def validate_params(kind: str, params: Mapping[str, Any]) -> None:
    """Raise SpecError (ValueError) if the merged params of a built-in kind make no valid config or gait."""
    if kind not in KINDS:
        return
    try:
        if kind == 'p6':
            from smarticle_experiments.p6 import START_NAMES

            if params['start'] not in START_NAMES:
                raise SpecError(f'params.start must be one of {", ".join(START_NAMES)}, got {params["start"]!r}')
            replace(NoiseConfig.none(), **noise_mapping(params.get('noise')))
            config = make_config('feedback', dict(params.get('physics') or {}), dict(params.get('robot') or {}))
            make_gait(config, params['alpha_max_deg'])
            if params.get('windows'):
                from smarticle_experiments.p6 import windows_config

                windows_config(params['windows'])
            return
        if kind.startswith('study_'):
            physics_study.study_config(dict(params.get('settings') or {}))
            return
        if kind == 'c2_harvest':
            make_gait(make_config(str(params['preset']), {}, {}), params['alpha_max_deg'])
            return
        config = config_of(params)
        if kind == 'pair_mujoco' and params.get('hold_first'):
            raise SpecError('hold_first: the MuJoCo pair kind has no held robot; use the pair kind (Bullet) or '
                            'pair_chrono')
        if kind in MUJOCO_KINDS:
            try:
                MujocoSettings(**dict(params.get('mujoco') or {}))
            except SimError as exc:
                raise SpecError(str(exc)) from None
        if kind in CHRONO_KINDS:
            try:
                ChronoSettings(**dict(params.get('chrono') or {}))
            except SimError as exc:
                raise SpecError(str(exc)) from None
        if kind == 'accuracy':
            make_config(str(params['preset']), {**dict(params.get('physics') or {}),
                                                'time_step': 1.0 / float(params['rate_hz']),
                                                'control_tick': float(params['control_tick']),
                                                'solver_iterations': int(params['solver_iterations'])}, {})
        make_gait(config, params['alpha_max_deg'], params['servo_speed'])
    except SpecError:
        raise
    except (ValueError, TypeError, KeyError) as exc:
        raise SpecError(str(exc).split('\n')[0]) from None


def ensemble_msd(paths: Sequence[Sequence[Sequence[float | None]]], max_lag: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The tracking package's ensemble MSD (``<x^2> - <x>^2``) of per-period paths (W): (lags, msd W^2)."""
    arrays = [np.array([[math.nan if v is None else v for v in row] for row in path], dtype=float)
              for path in paths if len(path) >= 2]
    if not arrays:
        return np.empty(0), np.empty(0)
    result = msd(arrays, max_lag=max_lag, subtract_mean=True)
    return result.lags.astype(float), result.msd


def msd_beta(lags: np.ndarray, values: np.ndarray) -> float:
    """The tracking package's power-law fit of an MSD curve (lags in periods); NaN if it cannot be fitted."""
    from smarticle_tracking.errors import MsdFitError
    from smarticle_tracking.msd import MsdResult

    if lags.size < 2:
        return math.nan
    result = MsdResult(lags.astype(np.intp), values, np.ones(lags.size, dtype=np.intp))
    try:
        return fit_msd_exponent(result).beta
    except MsdFitError:
        return math.nan


def code_versions() -> dict[str, str]:
    """Versions of the libraries a trial's numbers depend on (pybullet, numpy) in this process."""
    from importlib import metadata

    out = {'numpy': np.__version__}
    try:
        out['pybullet'] = metadata.version('pybullet')
    except metadata.PackageNotFoundError:
        out['pybullet'] = 'unknown'
    return out
