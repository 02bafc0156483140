"""The same scene in Project Chrono, the paper authors' engine: the physics reference of the sim.

PyBullet is the simulation of this project; MuJoCo (``mujoco_engine``) cross-checks its contact model. This
module runs a ``Scene`` in Chrono itself, through the project's own driver (``tools/chrono_reference/``,
C++ against Chrono's core library), and returns the same ``Recording`` as ``batch.run_trial``, so the
glider analysis and the experiment reports read it unchanged. Chrono is not on the package registries:
``tools/chrono_reference/build_chrono.sh`` builds its core and the driver from a Chrono 10 source tree
into ``.chrono/`` at the repository root (docs/chrono_reference.md). Without that build every run raises
``ChronoUnavailable`` with one line saying how to get it.

The model is the authors' published pair code: each link a box with its mass and inertia (from
``RobotSpec``, ``PhysicsConfig.tilt_inertia_scale`` and ``Diagnostics.mass_model``, ``yaw_inertia_scale``, as in
Bullet), the arms ``arm_clearance`` above the plate, a robot's own links never colliding; Chrono's smooth
contact (SMC, Hertz, from Young's modulus, Poisson ratio, restitution and friction: ``ChronoSettings``) or
its non-smooth one (NSC); the arms on rigid speed motors whose speed is a function of time alone: the
square gait's open-loop stroke at the gait's servo speed (no angle feedback, no torque limit). The plate
is a box of the robots' material (the authors' floor) with ``PhysicsConfig.friction_body_plate``.

Not modelled: noise, FSR forces, feedback and halts, starts from a running trial (``RobotState``) with
their velocities; ``at_rest_scene`` starts such a scene at rest when its velocities are negligible (a held pair).
A run stops early, with ``meta['trouble']`` set, when the state is not finite, a body tips past
``PhysicsConfig.max_tilt`` or leaves the plate.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.gait import GaitConfig, GaitError, open_loop_angles
from smarticle_common.pairs import one_pair
from smarticle_common.poses import body_headings_and_tilts
from smarticle_common.runs import Recording
from smarticle_common.topics import FSR_FACES

from .batch import check_run_request, scene_period
from .errors import SceneError, SimError
from .config_builder import build_config
from .diagnostics import arm_masses, authors_inertias, body_inertia_scales, box_inertia
from .scenes import RobotPlacement, Scene, pair_scene
from .settings import SimConfig

#: Environment variable naming the driver executable (default: ``DEFAULT_DRIVER``).
DRIVER_ENV = 'SMARTICLE_CHRONO_DRIVER'
#: Where ``build_chrono.sh`` puts the driver by default: ``.chrono/driver/`` at the repository root.
DEFAULT_DRIVER = Path(__file__).resolve().parents[2] / '.chrono' / 'driver' / 'smarticle_chrono'
#: Scene format the driver reads.
SCENE_FORMAT = 1
#: Columns per robot in a recording row: x, y, z, qx, qy, qz, qw, alpha1, alpha2.
ROBOT_COLUMNS = 9
#: ``ChronoSettings.contact`` and ``collision_system`` values.
CONTACTS = ('smc', 'nsc')
COLLISION_SYSTEMS = ('multicore', 'bullet')
#: A start whose arm angles differ from the gait's start angles by more than this (rad) is refused: the
#: speed motors follow the open-loop gait from where it starts.
START_TOLERANCE = 1e-6


class ChronoUnavailable(SimError):
    """The Chrono driver is not built (or not where it was said to be); the message says how to build it."""


@dataclass(frozen=True)
class ChronoSettings:
    """The Chrono side of a reference run (SI units): the authors' contact material, step and collision."""

    time_step: float = 1e-4              # s, the authors' step
    contact: str = 'smc'                 # 'smc': smooth (Hertz) contact; 'nsc': non-smooth (complementarity)
    collision_system: str = 'multicore'  # 'multicore': Chrono's own collision detection; 'bullet': Chrono's Bullet
    youngs_modulus: float = 2.0e7        # Pa, the authors' material (SMC only)
    poisson_ratio: float = 0.3           # the authors' material (SMC only)
    restitution: float = 0.85            # the authors' value (0.85-0.9)
    #: Robot-robot friction; None: ``PhysicsConfig.friction_robot_robot``.
    friction: float | None = None
    #: Body-plate friction; None: ``PhysicsConfig.friction_body_plate``. Chrono takes the smaller of two
    #: materials' frictions, so the plate's material carries it.
    plate_friction: float | None = None
    #: The plate's restitution; None: ``restitution`` (the authors' floor is of the robots' material).
    plate_restitution: float | None = None
    collision_envelope: float = 0.002    # m, the distance at which Chrono starts tracking a contact pair
    #: Wall-clock limit of one run (s); None: none.
    timeout: float | None = None

    def __post_init__(self) -> None:
        for name in ('time_step', 'youngs_modulus', 'collision_envelope'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value)
                                                                                      and value > 0.0):
                raise SimError(f'ChronoSettings.{name} must be a positive number, got {value!r}')
        if self.contact not in CONTACTS:
            raise SimError(f'ChronoSettings.contact must be one of {", ".join(CONTACTS)}, got {self.contact!r}')
        if self.collision_system not in COLLISION_SYSTEMS:
            raise SimError(f'ChronoSettings.collision_system must be one of {", ".join(COLLISION_SYSTEMS)}, '
                           f'got {self.collision_system!r}')
        if not (isinstance(self.poisson_ratio, (int, float)) and 0.0 <= self.poisson_ratio < 0.5):
            raise SimError(f'ChronoSettings.poisson_ratio must be in [0, 0.5), got {self.poisson_ratio!r}')
        for name in ('restitution', 'plate_restitution'):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise SimError(f'ChronoSettings.{name} must be in [0, 1], got {value!r}')
        for name in ('friction', 'plate_friction'):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
                raise SimError(f'ChronoSettings.{name} must be a number >= 0, got {value!r}')
        if self.timeout is not None and not (isinstance(self.timeout, (int, float)) and self.timeout > 0.0):
            raise SimError(f'ChronoSettings.timeout must be None or a positive number of seconds, got {self.timeout!r}')


#: ChronoSettings field names (the ``chrono`` mapping of a trial's parameters).
CHRONO_FIELDS: frozenset[str] = frozenset(f.name for f in fields(ChronoSettings))


def driver_path(path: str | Path | None = None) -> Path:
    """The driver executable: ``path``, else ``$SMARTICLE_CHRONO_DRIVER``, else ``DEFAULT_DRIVER``;
    ChronoUnavailable if it is not an executable file."""
    chosen = Path(path) if path is not None else Path(os.environ.get(DRIVER_ENV) or DEFAULT_DRIVER)
    if not (chosen.is_file() and os.access(chosen, os.X_OK)):
        raise ChronoUnavailable(f'Chrono is not built: no driver at {chosen}; build it with '
                                'tools/chrono_reference/build_chrono.sh <a Chrono 10 source tree or its tarball> '
                                f'(or set {DRIVER_ENV})')
    return chosen


def chrono_available(path: str | Path | None = None) -> bool:
    """True if the driver is built (``driver_path`` finds it)."""
    try:
        driver_path(path)
    except ChronoUnavailable:
        return False
    return True


def _link(size: tuple[float, float, float], mass: float, inertia: Iterable[float]) -> dict[str, Any]:
    """One link of the scene document: box edges (m), mass (kg), principal inertia (kg m^2)."""
    return {'size': list(size), 'mass': mass, 'inertia': [float(v) for v in inertia]}


def _robot_links(config: SimConfig) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The body and the two arms of ``config``'s robot, with Bullet's masses and inertias."""
    spec, ph, diag = config.robot, config.physics, config.diagnostics
    body_size = (spec.body_width, spec.body_depth, spec.body_height)
    arm_size = (spec.arm_length, spec.arm_thickness, spec.arm_height)
    masses = arm_masses(spec, diag.mass_model)
    if diag.mass_model == 'authors':
        body_inertia, *arm_inertias = authors_inertias(spec)
    else:
        body_inertia = box_inertia(spec.body_mass, *body_size)
        arm_inertias = [box_inertia(m, *arm_size) for m in masses]
    scales = body_inertia_scales(ph.tilt_inertia_scale, diag)
    body = _link(body_size, spec.body_mass, (i * k for i, k in zip(body_inertia, scales, strict=True)))
    arms = [_link(arm_size, m, inertia) for m, inertia in zip(masses, arm_inertias, strict=True)]
    return body, arms


def scene_document(config: SimConfig, scene: Scene, duration: float, record_interval: float,
                   settings: ChronoSettings, fixed: Iterable[int] = ()) -> dict[str, Any]:
    """The JSON scene the driver reads: ``scene``'s robots for ``duration`` s, a sample every ``record_interval``
    s; robots in ``fixed`` (and those ``RobotPlacement.held``) have their body held in place (their arms still
    move). SceneError / SimError on a
    scene the driver cannot run."""
    spec, ph = config.robot, config.physics
    scene.validate(spec, ph.plate_size)
    held = set(fixed) | {k for k, robot in enumerate(scene.robots) if robot.held}
    if not held <= set(range(len(scene.robots))):
        raise SceneError(f'fixed robots {sorted(held)} are not all in the scene of {len(scene.robots)} robots')
    steps = record_interval / settings.time_step
    if abs(steps - round(steps)) > 1e-6 * steps or round(steps) < 1:
        raise SimError(f'the sample interval {record_interval:g} s is not a whole number of Chrono steps '
                       f'({settings.time_step:g} s)')
    body, arms = _robot_links(config)
    robots = []
    for k, robot in enumerate(scene.robots):
        if robot.state is not None:
            raise SceneError(f'robot {k} starts from a running trial (RobotState): the Chrono reference starts '
                             'robots at rest')
        gait = None
        if robot.gait is not None:
            a1, a2 = open_loop_angles(robot.gait, robot.gait.phase)
            if max(abs(a1 - robot.alpha1), abs(a2 - robot.alpha2)) > START_TOLERANCE:
                raise SceneError(f'robot {k} starts with arms at ({robot.alpha1:.4f}, {robot.alpha2:.4f}) rad, not '
                                 f'where its gait starts ({a1:.4f}, {a2:.4f}): the Chrono motors follow the '
                                 'open-loop gait from its start')
            gait = {'alpha_max': robot.gait.alpha_max, 'period': robot.gait.period,
                    'servo_speed': robot.gait.servo_speed, 'phase': robot.gait.phase}
        robots.append({'x': robot.x, 'y': robot.y, 'heading': robot.heading, 'alpha1': robot.alpha1,
                       'alpha2': robot.alpha2, 'body': body, 'arms': arms,
                       'arm_z': spec.arm_clearance + spec.arm_height / 2.0 - spec.body_height / 2.0,
                       'gait': gait, 'fixed': k in held})
    robot_material = {'youngs_modulus': settings.youngs_modulus, 'poisson_ratio': settings.poisson_ratio,
                      'friction': ph.friction_robot_robot if settings.friction is None else settings.friction,
                      'restitution': settings.restitution}
    plate_friction = ph.friction_body_plate if settings.plate_friction is None else settings.plate_friction
    plate_restitution = settings.restitution if settings.plate_restitution is None else settings.plate_restitution
    plate_material = {**robot_material, 'friction': plate_friction, 'restitution': plate_restitution}
    return {'format': SCENE_FORMAT, 'contact': settings.contact, 'collision_system': settings.collision_system,
            'step': settings.time_step, 'duration': duration, 'record_interval': record_interval,
            'gravity': ph.gravity, 'collision_envelope': settings.collision_envelope, 'plate_size': ph.plate_size,
            'plate_thickness': ph.plate_thickness, 'max_tilt': ph.max_tilt,
            'robot_material': robot_material, 'plate_material': plate_material, 'robots': robots}


def read_recording(path: str | Path, n_robots: int, body_length: float,
                   meta: Mapping[str, Any] | None = None) -> Recording:
    """The driver's binary recording at ``path`` (rows of float64, module docstring of the driver) as a
    ``Recording``; a partly written last row is dropped. SimError if the file is not such a recording."""
    width = 1 + ROBOT_COLUMNS * n_robots + n_robots * n_robots
    raw = np.fromfile(path, dtype='<f8')
    rows = raw.size // width
    if rows < 1:
        raise SimError(f'{path}: no complete sample of {n_robots} robots ({raw.size} numbers)')
    data = raw[:rows * width].reshape(rows, width)
    per_robot = data[:, 1:1 + ROBOT_COLUMNS * n_robots].reshape(rows, n_robots, ROBOT_COLUMNS)
    quats = per_robot[:, :, 3:7].reshape(-1, 4)
    heading, _ = body_headings_and_tilts(quats)
    poses = np.empty((rows, n_robots, 3))
    poses[:, :, :2] = per_robot[:, :, :2]
    poses[:, :, 2] = heading.reshape(rows, n_robots)
    contacts = data[:, 1 + ROBOT_COLUMNS * n_robots:].reshape(rows, n_robots, n_robots) > 0.5
    return Recording(data[:, 0].copy(), poses, per_robot[:, :, 7:9].copy(),
                     np.zeros((rows, n_robots, len(FSR_FACES))), contacts, float(body_length), dict(meta or {}))


#: A start taken from a running trial may have arms this far (rad) from where their gaits start and still be
#: started at rest there by ``at_rest_scene``: a servo settled on its corner, to the solver's rounding.
AT_REST_ARM_TOLERANCE = 1e-3


def at_rest_scene(scene: Scene, arm_tolerance: float = AT_REST_ARM_TOLERANCE) -> tuple[Scene, float]:
    """``scene`` with every robot at rest, flat on the plate: each robot's pose (x, y, heading) and gait kept, its
    running state (``RobotState``: height, tilt, velocities) dropped and its arms put where its gait starts. For
    a start taken from a running trial at a period boundary whose velocities are negligible (a held pair), so
    that the Chrono driver, which starts robots at rest, can run it. Returns the scene and the largest arm
    correction (rad). SceneError if a robot has no gait or an arm is more than ``arm_tolerance`` rad from
    its gait's start."""
    robots = []
    largest = 0.0
    for k, robot in enumerate(scene.robots):
        if robot.gait is None:
            raise SceneError(f'robot {k} has no gait: an at-rest start puts the arms where the gait starts')
        a1, a2 = open_loop_angles(robot.gait, robot.gait.phase)
        off = max(abs(a1 - robot.alpha1), abs(a2 - robot.alpha2))
        if not off <= arm_tolerance:
            raise SceneError(f'robot {k}: arms at ({robot.alpha1:.4f}, {robot.alpha2:.4f}) rad are {off:.2g} rad '
                             f'from where its gait starts ({a1:.4f}, {a2:.4f}), more than {arm_tolerance:g}')
        largest = max(largest, off)
        robots.append(RobotPlacement(robot.x, robot.y, robot.heading, a1, a2, robot.gait))
    return replace(scene, robots=tuple(robots)), largest


def run_chrono(config: SimConfig, scene: Scene, periods: float, sample_every: int,
               settings: ChronoSettings | None = None, fixed: Iterable[int] = (),
               driver: str | Path | None = None, keep: str | Path | None = None) -> Recording:
    """Run ``scene`` for ``periods`` gait periods in Chrono from a synchronised start at t = 0.

    Samples every ``sample_every`` control ticks (``PhysicsConfig.control_tick``), like ``run_trial``;
    ``contacts[s]`` is True for two robots that overlapped at any Chrono step since the sample before.
    ``fixed``: robots whose body is held in place. ``keep``: a folder that keeps the scene and the raw
    recording (default: a temporary one). ChronoUnavailable if the driver is not built.
    """
    settings = settings or ChronoSettings()
    sample_every = check_run_request(periods, sample_every)
    exe = driver_path(driver)
    period = scene_period(scene)
    record_interval = sample_every * config.physics.control_tick
    document = scene_document(config, scene, periods * period, record_interval, settings, fixed)
    meta: dict[str, Any] = {
        'engine': 'chrono', 'chrono': asdict(settings), 'robot': asdict(config.robot),
        'physics': asdict(config.physics), 'scene': scene.name, 'seed': scene.seed, 'periods': periods,
        'period': period, 'start_time': 0.0, 'sample_every': sample_every, 'sample_rate': 1.0 / record_interval,
        'fsr_recorded': False, 'contacts_recorded': True, 'fsr_faces': list(FSR_FACES), 'fixed': sorted(set(fixed)),
        'initial': [{'x': r.x, 'y': r.y, 'heading': r.heading, 'alpha1': r.alpha1, 'alpha2': r.alpha2,
                     'phase': r.gait.phase if r.gait else None,
                     'alpha_max': r.gait.alpha_max if r.gait else None} for r in scene.robots]}
    with tempfile.TemporaryDirectory(prefix='smarticle-chrono-') as scratch:
        folder = Path(keep) if keep is not None else Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        scene_file, recording_file = folder / 'scene.json', folder / 'recording.bin'
        scene_file.write_text(json.dumps(document, indent=1))
        try:
            done = subprocess.run([str(exe), str(scene_file), str(recording_file)], capture_output=True,
                                  text=True, timeout=settings.timeout, check=False)
        except subprocess.TimeoutExpired:
            raise SimError(f'the Chrono run took longer than ChronoSettings.timeout ({settings.timeout:g} s)') from None
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or ['(no message)'])[-1]
            raise SimError(f'the Chrono driver failed (exit code {done.returncode}): {last}')
        try:
            summary = json.loads(done.stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            raise SimError(f'the Chrono driver wrote no summary line: {done.stdout[-200:]!r}') from None
        meta.update(trouble=str(summary['trouble']), chrono_version=str(summary['chrono_version']),
                    peak_tilt_deg=math.degrees(float(summary['peak_tilt_rad'])),
                    peak_overlap_mm=float(summary['peak_overlap_m']) * 1000.0,
                    wall_time_s=float(summary['wall_time_s']), steps=int(summary['steps']))
        return read_recording(recording_file, len(scene.robots), config.robot.body_length, meta)


# ------------------------------------------------------------------ the experiment kind

#: Parameters of ``pair_chrono_trial`` and their defaults (the project's pair kind's names and units).
PAIR_CHRONO_DEFAULTS: dict[str, Any] = {
    'preset': 'small', 'physics': {}, 'robot': {}, 'diagnostics': {}, 'chrono': {},
    'alpha_max_deg': 90.0, 'servo_speed': None, 'r_bl': 1.3, 'theta_deg': 330.0, 'phi_deg': 180.0,
    'phase2': 0.0, 'periods': 40.0, 'sample_every': 3, 'hold_first': False,
    'r_bind_bl': 1.6, 'bound_tail': 10,
}


def _config(p: Mapping[str, Any]) -> SimConfig:
    """SimConfig of a trial's ``preset``, ``physics``, ``robot`` and ``diagnostics`` (``build_config`` for the
    Chrono engine; ConfigError, a SimError, on bad fields)."""
    return build_config(str(p['preset']), p.get('physics'), p.get('robot'),
                        diagnostics=p.get('diagnostics'), engine='chrono')


def _checked(params: Mapping[str, Any], defaults: Mapping[str, Any], kind: str) -> dict[str, Any]:
    """``defaults`` overridden by ``params``; SimError on a parameter the kind does not know."""
    unknown = sorted(set(params) - set(defaults))
    if unknown:
        raise SimError(f'{kind}: unknown parameter {unknown[0]!r}; known: {", ".join(sorted(defaults))}')
    return {**defaults, **params}


def _settings(p: Mapping[str, Any]) -> ChronoSettings:
    """ChronoSettings of a trial's ``chrono`` mapping."""
    unknown = sorted(set(p['chrono']) - CHRONO_FIELDS)
    if unknown:
        raise SimError(f'chrono.{unknown[0]} is not a ChronoSettings field; known: {", ".join(sorted(CHRONO_FIELDS))}')
    return ChronoSettings(**dict(p['chrono']))


def _gait(p: Mapping[str, Any], config: SimConfig) -> GaitConfig:
    """The square gait of a trial's ``alpha_max_deg`` and ``servo_speed`` (default: the robot's)."""
    try:
        return GaitConfig.from_degrees(float(p['alpha_max_deg']),
                                       servo_speed=p['servo_speed'] or config.robot.servo_speed)
    except GaitError as exc:
        raise SimError(f'gait: {exc}') from None


def pair_chrono_trial(params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """Two robots from pair coordinates run in Chrono: where the pair ends, how far it travelled.

    ``params`` overrides ``PAIR_CHRONO_DEFAULTS`` (r in BL, angles in degrees; ``chrono`` sets
    ``ChronoSettings`` fields; ``hold_first`` holds robot 1's body in place). ``seed`` is the trial's seed
    the scene carries (nothing here is random). Returns a JSON-ready dict: the start; ``admissible`` (False:
    the robots overlap at the start, ``why``); ``trouble``; ``periods_run``; ``r_end_bl``,
    ``phi_end_deg``; ``travel_w`` (net displacement of the pair's centre, W = BL) and ``travel_w_per_100``;
    ``bound_tail_periods`` (last periods in a row with r < ``r_bind_bl`` or contact in the period),
    ``colliding_tail_periods`` (contact in each), ``bound_at_end`` (tail >= ``bound_tail``); the peaks and
    the wall time. ChronoUnavailable when Chrono is not built.
    """
    p = _checked(params, PAIR_CHRONO_DEFAULTS, 'pair_chrono_trial')
    config, settings = _config(p), _settings(p)
    driver_path()    # before any work: one clear line when Chrono is absent
    gait = _gait(p, config)
    r, theta, phi = float(p['r_bl']), float(p['theta_deg']), float(p['phi_deg'])
    start = {'r0_bl': r, 'theta0_deg': theta, 'phi0_deg': phi, 'phase2': float(p['phase2'])}
    try:
        scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi),
                           (0.0, float(p['phase2'])), seed=seed)
    except SceneError as exc:
        return {**start, 'admissible': False, 'why': str(exc), 'trouble': ''}
    sample_every = int(p['sample_every'])
    rec = run_chrono(config, scene, float(p['periods']), sample_every, settings,
                     fixed=(0,) if p['hold_first'] else ())
    return {**start, 'admissible': True, **pair_figures(rec, gait.period, config.physics.control_tick * sample_every,
                                                        float(p['r_bind_bl']), int(p['bound_tail']))}


#: Parameters of ``single_chrono_trial`` and their defaults (the project's single kind's names and units).
SINGLE_CHRONO_DEFAULTS: dict[str, Any] = {
    'preset': 'small', 'physics': {}, 'robot': {}, 'diagnostics': {}, 'chrono': {},
    'alpha_max_deg': 90.0, 'servo_speed': None, 'periods': 20.0, 'sample_every': 3,
}


def single_chrono_trial(params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """One robot alone in Chrono (P7), its heading drawn from ``seed`` as the project's single kind does: the
    drift per cycle in micrometres (net, and the mean per-cycle step). ChronoUnavailable without the build."""
    p = _checked(params, SINGLE_CHRONO_DEFAULTS, 'single_chrono_trial')
    config, settings = _config(p), _settings(p)
    driver_path()
    gait = _gait(p, config)
    heading = float(np.random.default_rng(seed).uniform(-math.pi, math.pi))
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, heading, a, a, gait),), name='single', seed=seed)
    sample_every = int(p['sample_every'])
    rec = run_chrono(config, scene, float(p['periods']), sample_every, settings)
    per = max(1, round(gait.period / (config.physics.control_tick * sample_every)))
    xy = rec.poses[::per, 0, :2]
    cycles = max(len(xy) - 1, 1)
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    return {'heading_deg': math.degrees(heading), 'trouble': rec.trouble, 'cycles': len(xy) - 1,
            'drift_um_per_cycle': float(np.linalg.norm(xy[-1] - xy[0]) / cycles * 1e6),
            'step_um_per_cycle': float(steps.mean() * 1e6) if steps.size else None,
            'wall_time_s': _number(rec.meta.get('wall_time_s'))}


def pair_figures(rec: Recording, period: float, sample_interval: float, r_bind_bl: float,
                 bound_tail: int) -> dict[str, Any]:
    """A two-robot recording's end state and travel (the figures of ``pair_chrono_trial``), from any engine."""
    bl = rec.body_length
    per = max(1, round(period / sample_interval))
    whole = (len(rec.time) - 1) // per
    r_all = np.hypot(*(rec.poses[:, 1, :2] - rec.poses[:, 0, :2]).T) / bl
    touching = rec.contacts[:, 0, 1]
    bound = [bool(touching[q * per + 1:(q + 1) * per + 1].any() or (r_all[q * per:(q + 1) * per + 1] < r_bind_bl).any())
             for q in range(whole)]
    colliding = [bool(touching[q * per + 1:(q + 1) * per + 1].any()) for q in range(whole)]
    com = rec.poses[:, :, :2].mean(axis=1) / bl
    travel = float(np.linalg.norm(com[whole * per] - com[0])) if whole else 0.0
    _, _, phi_end = one_pair(rec.poses[-1, 0], rec.poses[-1, 1])
    bound_tail_periods = trailing_true(bound)
    return {'trouble': rec.trouble, 'periods_run': whole, 'r_end_bl': float(r_all[-1]),
            'phi_end_deg': math.degrees(phi_end), 'travel_w': travel,
            'travel_w_per_100': 100.0 * travel / whole if whole else 0.0,
            'bound_tail_periods': bound_tail_periods, 'colliding_tail_periods': trailing_true(colliding),
            'bound_at_end': bound_tail_periods >= bound_tail,
            'peak_tilt_deg': _number(rec.meta.get('peak_tilt_deg')),
            'peak_overlap_mm': _number(rec.meta.get('peak_overlap_mm')),
            'wall_time_s': _number(rec.meta.get('wall_time_s'))}


def _number(value: Any) -> float | None:
    """A finite float, or None (JSON has no NaN)."""
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def trailing_true(flags: Sequence[bool]) -> int:
    """How many of the last entries of ``flags`` are true in a row (a pair's bound or colliding periods at the end)."""
    tail = 0
    for flag in reversed(flags):
        if not flag:
            break
        tail += 1
    return tail
