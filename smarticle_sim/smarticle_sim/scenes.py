"""Scene builders: where the robots start, their arm angles and gaits; every random choice is seeded."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from smarticle_common.facts import RobotSpec
from smarticle_common.gait import GaitConfig, open_loop_angles
from smarticle_common.pairs import place_pair

from .errors import SceneError
from .geometry import Rect, rect_corners, robot_rects, robots_overlap

#: Smallest gap (m) kept between robots by the builders.
DEFAULT_GAP = 0.001


#: Names of ``RobotState.values`` (CSV columns of a saved state).
STATE_FIELDS: tuple[str, ...] = ('z', 'qx', 'qy', 'qz', 'qw', 'vx', 'vy', 'vz', 'wx', 'wy', 'wz',
                                 'dalpha1', 'dalpha2')


@dataclass(frozen=True)
class RobotState:
    """The rest of a robot's dynamic state, for a start taken from a running trial (``Physics.placements``).

    With it the robot starts with this body height and orientation (a tilted body stays tilted) and these
    velocities instead of at rest, flat on the plate.
    """

    z: float                                       # body centre height (m)
    orientation: tuple[float, float, float, float]  # body quaternion (x, y, z, w); its yaw is the heading's
    velocity: tuple[float, float, float]           # body centre velocity (m/s)
    angular_velocity: tuple[float, float, float]   # body angular velocity (rad/s)
    arm_velocities: tuple[float, float]            # d alpha1 / dt, d alpha2 / dt (rad/s)

    def values(self) -> tuple[float, ...]:
        """All 13 numbers, in the order of ``STATE_FIELDS``."""
        return (self.z, *self.orientation, *self.velocity, *self.angular_velocity, *self.arm_velocities)

    @classmethod
    def from_values(cls, values: Sequence[float]) -> RobotState:
        """The inverse of ``values``."""
        v = [float(x) for x in values]
        if len(v) != len(STATE_FIELDS) or not all(math.isfinite(x) for x in v):
            raise SceneError(f'a robot state has {len(STATE_FIELDS)} finite numbers (z, quaternion, velocity, '
                             f'angular velocity, arm velocities), got {v}')
        return cls(v[0], (v[1], v[2], v[3], v[4]), (v[5], v[6], v[7]), (v[8], v[9], v[10]), (v[11], v[12]))


@dataclass(frozen=True)
class RobotPlacement:
    """Initial pose (x, y in m, heading of the body normal in rad), arm angles and optional gait core."""

    x: float
    y: float
    heading: float
    alpha1: float = 0.0
    alpha2: float = 0.0
    gait: GaitConfig | None = None   # None: the robot follows external joint commands
    state: RobotState | None = None  # None: at rest, flat on the plate
    #: True: the body is held in place (it neither moves nor tips; contacts act on it but cannot move it),
    #: its arms still turn. Bullet gives a held body no mass, a fixed base (``Physics``).
    held: bool = False

    def rects(self, spec: RobotSpec) -> tuple[Rect, Rect, Rect]:
        """Footprint rectangles (body, arm 1, arm 2) of this placement."""
        return robot_rects(spec, self.x, self.y, self.heading, self.alpha1, self.alpha2)


@dataclass(frozen=True)
class Scene:
    """The initial state of a world: robot placements plus a name and the seed that built it."""

    robots: tuple[RobotPlacement, ...]
    name: str = 'custom'
    seed: int | None = None
    #: Footprints may overlap by this much (m): a start taken from a running trial holds its contacts as
    #: deep as the solver left them (``state_scene``). 0 for every scene built from scratch.
    overlap_tolerance: float = 0.0

    def validate(self, spec: RobotSpec, plate_size: float, gap: float = 0.0) -> None:
        """Raise SceneError if a value is not finite, a robot hangs off the plate or two robots overlap
        (by more than ``overlap_tolerance``)."""
        gap -= self.overlap_tolerance
        if not self.robots:
            raise SceneError(f'scene {self.name!r} has no robots')
        half = plate_size / 2.0
        footprints = []
        for k, robot in enumerate(self.robots):
            values = (robot.x, robot.y, robot.heading, robot.alpha1, robot.alpha2)
            if not all(math.isfinite(v) for v in values):
                raise SceneError(f'scene {self.name!r}: robot {k} has a non-finite pose or arm angle '
                                 f'{values}')
            rects = robot.rects(spec)
            corners = np.concatenate([rect_corners(r) for r in rects])
            if np.abs(corners).max() > half:
                raise SceneError(f'scene {self.name!r}: robot {k} at ({robot.x:.3f}, {robot.y:.3f}) m '
                                 f'reaches off the {plate_size} m plate')
            footprints.append(rects)
        centres = np.array([(robot.x, robot.y) for robot in self.robots])
        apart = 2.0 * spec.reach + gap + 0.01   # centres farther apart than this cannot overlap (1 cm margin)
        for i in range(len(footprints)):
            near = np.flatnonzero(np.hypot(*(centres[i + 1:] - centres[i]).T) <= apart) + i + 1
            for j in near:
                if robots_overlap(footprints[i], footprints[j], gap):
                    a, b = self.robots[i], self.robots[j]
                    raise SceneError(f'scene {self.name!r}: robots {i} at ({a.x:.4f}, {a.y:.4f}) and {j} at '
                                     f'({b.x:.4f}, {b.y:.4f}) overlap; move them apart')


def start_angles(gait: GaitConfig) -> tuple[float, float]:
    """Arm angles of a gait at its start (its phase), from the shared gait core."""
    return open_loop_angles(gait, gait.phase)


def _placement(x: float, y: float, heading: float, gait: GaitConfig, held: bool = False) -> RobotPlacement:
    """A placement whose arms start where ``gait`` starts (``held``: its body held in place)."""
    a1, a2 = start_angles(gait)
    return RobotPlacement(float(x), float(y), float(heading), a1, a2, gait, held=held)


def hex_points(n: int) -> np.ndarray:
    """The first ``n`` points of a unit hexagonal lattice, nearest the origin first, as (n, 2)."""
    if n < 1:
        raise SceneError(f'number of robots must be >= 1, got {n}')
    rings = 1
    while 1 + 3 * rings * (rings + 1) < n:
        rings += 1
    pts = []
    for i in range(-rings, rings + 1):
        for j in range(-rings, rings + 1):
            pts.append((i + 0.5 * j, j * math.sqrt(3.0) / 2.0))
    arr = np.array(pts)
    order = np.lexsort((np.arctan2(arr[:, 1], arr[:, 0]), np.round(np.hypot(arr[:, 0], arr[:, 1]), 9)))
    return arr[order[:n]]


def dense_scene(spec: RobotSpec, gait: GaitConfig, n: int = 7, seed: int = 0,
                gap: float = DEFAULT_GAP, jitter: float = 0.1, phase_jitter: float = 0.0) -> Scene:
    """N robots densely packed (paper Fig. 1(c)): in phase, random headings, lattice shrunk to touch.

    The robots sit on a hexagonal lattice (jittered by ``jitter`` of the spacing) with seeded random
    headings; the spacing is the smallest, in 0.5 mm steps, at which no two footprints come closer
    than ``gap``. ``phase_jitter`` (periods, default 0: exactly in phase) adds a seeded uniform offset in
    [-phase_jitter, +phase_jitter] to each robot's gait phase, the sim's stand-in for the experiments'
    phase drift (``docs/sim_calibration.md``: equal phases make bound pairs symmetric and stationary);
    the first draws are unchanged, so a seed gives the same poses with or without it.
    """
    if not (math.isfinite(phase_jitter) and 0.0 <= phase_jitter <= 0.5):
        raise SceneError(f'dense_scene: phase_jitter must be in [0, 0.5] periods, got {phase_jitter!r}')
    rng = np.random.default_rng(seed)
    base = hex_points(n)
    offsets = rng.uniform(-jitter, jitter, size=(n, 2))
    headings = rng.uniform(-math.pi, math.pi, size=n)
    gaits = [gait] * n
    if phase_jitter > 0.0:
        gaits = [GaitConfig(gait.alpha_max, gait.period, gait.servo_speed, (gait.phase + float(d)) % 1.0)
                 for d in rng.uniform(-phase_jitter, phase_jitter, size=n)]
    spacing = spec.body_depth
    limit = 4.0 * spec.reach
    while spacing <= limit:
        pts = (base + offsets) * spacing
        scene = Scene(tuple(_placement(p[0], p[1], h, g) for p, h, g in zip(pts, headings, gaits, strict=True)),
                      name='dense', seed=seed)
        try:
            scene.validate(spec, math.inf, gap)
            return scene
        except SceneError:
            spacing += 0.0005
    raise SceneError(f'could not pack {n} robots within a lattice spacing of {limit:.3f} m')


def pair_scene(spec: RobotSpec, gait: GaitConfig, r: float, theta: float, phi: float,
               phases: tuple[float, float] = (0.0, 0.0), heading1: float = math.pi / 2.0,
               centre: tuple[float, float] = (0.0, 0.0), seed: int | None = None,
               alpha_max2: float | None = None, hold_first: bool = False) -> Scene:
    """Two robots at pair coordinates (r in BL, theta, phi in rad) with gait phases ``phases``.

    Robot 1 sits at ``centre`` with normal ``heading1``; robot 2's centre is r BL away in the direction
    theta counter-clockwise from robot 1's body x axis (theta = pi/2: straight ahead along its normal),
    and its normal is robot 1's turned by phi. Nothing here is random; ``seed`` is the trial's seed the
    scene carries, from which the noise with a cause draws (``NoiseConfig.trial_seed``).
    ``alpha_max2`` (rad) gives robot 2 its own amplitude (default: the gait's), two robots whose servos
    turn their arms unequally far. ``hold_first`` holds robot 1's body in place (``RobotPlacement.held``: it
    neither moves nor tips, its arms still follow its gait), the paper's P4 read literally ("fix one robot").
    Raises SceneError if the two overlap in their starting shapes.
    """
    if not (math.isfinite(r) and r > 0.0):
        raise SceneError(f'pair separation r must be > 0 body lengths, got {r!r}')
    pose1 = (centre[0], centre[1], heading1)
    pose2 = place_pair(pose1, r * spec.body_length, theta, phi)
    g1 = GaitConfig(gait.alpha_max, gait.period, gait.servo_speed, phases[0])
    g2 = GaitConfig(gait.alpha_max if alpha_max2 is None else alpha_max2, gait.period, gait.servo_speed, phases[1])
    scene = Scene((_placement(*pose1, g1, held=hold_first), _placement(*pose2, g2)), name='pair', seed=seed)
    scene.validate(spec, math.inf)
    return scene


def state_scene(placements: Sequence[RobotPlacement], gaits: Sequence[GaitConfig | None], name: str = 'state',
                seed: int | None = None, centre: tuple[float, float] = (0.0, 0.0),
                overlap_tolerance: float = 0.002) -> Scene:
    """Robots that start where a running trial left them (``Physics.placements``), moved together so their
    mean centre is at ``centre``, with these gaits (a period boundary of the old trial: each gait starts at its
    phase). Footprints may overlap by ``overlap_tolerance`` (m, default 2 mm): the contacts of the old trial.
    Raises SceneError if a placement has no ``state`` or the robots overlap by more.
    """
    if not (math.isfinite(overlap_tolerance) and 0.0 <= overlap_tolerance <= 0.01):
        raise SceneError(f'state_scene: overlap_tolerance must be in [0, 0.01] m, got {overlap_tolerance!r}')
    if len(placements) != len(gaits):
        raise SceneError(f'state_scene: {len(placements)} placements but {len(gaits)} gaits')
    if not placements:
        raise SceneError('state_scene: no robots')
    for k, p in enumerate(placements):
        if p.state is None:
            raise SceneError(f'state_scene: placement {k} has no state (take it from Physics.placements)')
    mean = np.mean([(p.x, p.y) for p in placements], axis=0)
    dx, dy = centre[0] - float(mean[0]), centre[1] - float(mean[1])
    robots = tuple(RobotPlacement(p.x + dx, p.y + dy, p.heading, p.alpha1, p.alpha2, g, p.state, p.held)
                   for p, g in zip(placements, gaits, strict=True))
    return Scene(robots, name=name, seed=seed, overlap_tolerance=overlap_tolerance)


def random_scene(spec: RobotSpec, gait: GaitConfig, n: int, seed: int = 0, region: float = 0.3,
                 random_phases: bool = False, gap: float = DEFAULT_GAP, max_tries: int = 10000) -> Scene:
    """N robots at seeded random non-overlapping poses in a square of side ``region`` (m) at the centre."""
    rng = np.random.default_rng(seed)
    placed: list[RobotPlacement] = []
    footprints: list[tuple[Rect, Rect, Rect]] = []
    half = region / 2.0
    tries = 0
    while len(placed) < n:
        tries += 1
        if tries > max_tries:
            raise SceneError(f'could not place {n} robots without overlap in a {region} m square '
                             f'after {max_tries} tries; enlarge the region')
        x, y = rng.uniform(-half, half, size=2)
        heading = rng.uniform(-math.pi, math.pi)
        phase = float(rng.uniform(0.0, 1.0)) if random_phases else gait.phase
        g = GaitConfig(gait.alpha_max, gait.period, gait.servo_speed, phase)
        candidate = _placement(x, y, heading, g)
        rects = candidate.rects(spec)
        if any(robots_overlap(rects, other, gap) for other in footprints):
            continue
        placed.append(candidate)
        footprints.append(rects)
    return Scene(tuple(placed), name='random', seed=seed)


SCENE_KINDS: tuple[str, ...] = ('dense', 'pair', 'random')


def build_scene(kind: str, spec: RobotSpec, gait: GaitConfig, robots: int = 7, seed: int = 0,
                r: float = 1.3, theta: float = math.pi / 2.0, phi: float = math.pi,
                phases: tuple[float, float] = (0.0, 0.0), random_phases: bool = False,
                phase_jitter: float = 0.0) -> Scene:
    """Build a scene by kind name (``dense``, ``pair`` or ``random``); r in BL, angles in rad."""
    if kind == 'dense':
        return dense_scene(spec, gait, robots, seed=seed, phase_jitter=phase_jitter)
    if kind == 'random':
        return random_scene(spec, gait, robots, seed=seed, random_phases=random_phases)
    if kind == 'pair':
        return pair_scene(spec, gait, r, theta, phi, phases=phases)
    raise SceneError(f'scene kind {kind!r} is unknown; choose one of {", ".join(SCENE_KINDS)}')
