"""What the live view shows: robots, arms, trails and gliders as plain scene entities (no ROS, no Foxglove).

``SceneBuilder`` takes what the stack publishes (poses of ``/smarticles/poses`` as an (N, 3) array with
NaN rows for unseen robots, arm angles of ``/smarticle_<k>/joint_states``, bound pairs of
``/smarticles/gliders``) and returns ``Entity`` values in the ``arena`` frame: per robot its body and
two arms as cubes and its id as a label (``robot_<k>``), its trail as a line strip (``trail_<k>``), and
per bound pair a bond coloured by class with the class and age as a label (``glider_<i>_<j>``). The
``smarticle-view`` node (``view_node.py``) converts them to Foxglove ``SceneUpdate`` messages. Colours
are the glider monitor's (``smarticle_tracking.markers``), so RViz markers and the live view agree.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from smarticle_common import topics
from smarticle_tracking.gliders import GliderClass
from smarticle_tracking.markers import BOUND_COLOUR, CLASS_COLOURS, ROBOT_COLOUR, RobotDims

Rgba = tuple[float, float, float, float]
Point = tuple[float, float, float]

#: Colours of the arms (darker than the body), the trails and the labels.
ARM_COLOUR: Rgba = (0.55, 0.55, 0.6, 1.0)
TRAIL_COLOUR: Rgba = (0.3, 0.8, 0.4, 0.8)
LABEL_COLOUR: Rgba = (1.0, 1.0, 1.0, 1.0)
#: Height of the drawn body and arm cubes (m); the robot is planar, this is only for the 3D view.
BODY_HEIGHT = 0.01
TRAIL_THICKNESS = 0.002     # m
BOND_THICKNESS = 0.004      # m
LABEL_SIZE = 0.012          # m


@dataclass(frozen=True)
class Cube:
    """A box: centre (m), yaw about z (rad), size along its own x, y, z (m), colour."""

    centre: Point
    yaw: float
    size: Point
    rgba: Rgba


@dataclass(frozen=True)
class Line:
    """A line strip through ``points`` (m)."""

    points: tuple[Point, ...]
    rgba: Rgba
    thickness: float


@dataclass(frozen=True)
class Label:
    """A text facing the viewer at ``position`` (m)."""

    position: Point
    text: str
    size: float
    rgba: Rgba


@dataclass(frozen=True)
class Entity:
    """One scene entity in the arena frame: an id and its primitives."""

    id: str
    cubes: tuple[Cube, ...] = ()
    lines: tuple[Line, ...] = ()
    labels: tuple[Label, ...] = ()
    frame: str = topics.ARENA_FRAME


@dataclass(frozen=True)
class GliderReport:
    """One pair bound now of ``/smarticles/gliders``: robots, class, age and the monitor's label."""

    i: int
    j: int
    glider_class: GliderClass
    age: float            # s
    age_periods: int
    label: str = ''       # 'bound' before K periods, then e.g. 'C1 bound pair', 'C1 glider'


@dataclass(frozen=True)
class SceneUpdate:
    """Entities to draw (replacing those with the same id) and ids to delete."""

    entities: tuple[Entity, ...]
    deletions: tuple[str, ...]


def _pair_colour(pair: GliderReport) -> Rgba:
    """The class colour of a bound pair or glider; grey while the monitor still calls it only 'bound'."""
    return BOUND_COLOUR if pair.label == 'bound' else CLASS_COLOURS[pair.glider_class]


def glider_reports(statuses: Iterable[Mapping[str, str]]) -> list[GliderReport]:
    """Parse the key/values of ``/smarticles/gliders`` statuses (ValueError names a malformed one)."""
    out = []
    for values in statuses:
        try:
            out.append(GliderReport(int(values['i']), int(values['j']), GliderClass(values['class']),
                                    float(values['age']), int(values.get('age_periods', '0')),
                                    values.get('label', values['class'])))
        except (KeyError, ValueError) as err:
            raise ValueError(f'glider report {dict(values)} is malformed: {err}') from None
    return out


def robot_cubes(pose: ArrayLike, arm_angles: ArrayLike | None, dims: RobotDims, colour: Rgba) -> tuple[Cube, ...]:
    """Body and (when the angles are known) both arms of one robot, as cubes.

    The body's long side is along the joint axis, perpendicular to the heading (the body normal); arm 1
    is at the body's -x end, arm 2 at +x; angle zero is an arm in line with the body and a positive angle
    turns its tip toward the normal (docs/gait.md), as in the glider monitor's outlines.
    """
    x, y, heading = (float(v) for v in np.asarray(pose, dtype=float))
    yaw = heading - math.pi / 2.0
    ex = (math.cos(yaw), math.sin(yaw))
    z = BODY_HEIGHT / 2.0
    cubes = [Cube((x, y, z), yaw, (dims.body_width, dims.body_depth, BODY_HEIGHT), colour)]
    if arm_angles is not None:
        alphas = np.asarray(arm_angles, dtype=float)
        if alphas.shape == (2,) and np.all(np.isfinite(alphas)):
            for sign, angle in ((-1.0, yaw + math.pi - alphas[0]), (1.0, yaw + alphas[1])):
                jx, jy = x + sign * ex[0] * dims.body_width / 2.0, y + sign * ex[1] * dims.body_width / 2.0
                cx = jx + math.cos(angle) * dims.arm_length / 2.0
                cy = jy + math.sin(angle) * dims.arm_length / 2.0
                cubes.append(Cube((cx, cy, z), float(angle), (dims.arm_length, dims.arm_thickness, BODY_HEIGHT),
                                  ARM_COLOUR))
    return tuple(cubes)


def dims_of(preset: str) -> RobotDims:
    """The outline of a robot preset (``smarticle_common.facts.PRESETS``); ValueError naming the known ones."""
    from smarticle_common.facts import PRESETS

    spec = PRESETS.get(preset)
    if spec is None:
        raise ValueError(f'robot preset must be one of {", ".join(sorted(PRESETS))}, got {preset!r}')
    return RobotDims(spec.body_width, spec.body_depth, spec.arm_length, spec.arm_thickness)


@dataclass
class SceneBuilder:
    """Keeps the latest poses, arm angles and gliders, and the trails; ``update()`` gives the scene."""

    dims: RobotDims = field(default_factory=RobotDims)
    trail_length: int = 200          # points kept per trail
    trail_spacing: float = 0.002     # m: a new trail point once the robot moved this far
    poses: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    arms: dict[int, np.ndarray] = field(default_factory=dict)
    gliders: list[GliderReport] = field(default_factory=list)
    trails: dict[int, deque[tuple[float, float]]] = field(default_factory=dict)
    _drawn: set[str] = field(default_factory=set)

    def set_poses(self, poses: ArrayLike) -> None:
        """Take one frame of poses (N, 3), NaN rows unseen; extend the trails of the seen robots."""
        arr = np.asarray(poses, dtype=float).reshape(-1, 3)
        self.poses = arr
        for k in map(int, np.flatnonzero(np.all(np.isfinite(arr), axis=1))):
            trail = self.trails.setdefault(k, deque(maxlen=self.trail_length))
            point = (float(arr[k, 0]), float(arr[k, 1]))
            if not trail or math.hypot(point[0] - trail[-1][0], point[1] - trail[-1][1]) >= self.trail_spacing:
                trail.append(point)

    def set_arms(self, robot: int, angles: ArrayLike) -> None:
        """Take robot ``robot``'s arm angles (arm1, arm2 in rad)."""
        self.arms[robot] = np.asarray(angles, dtype=float).reshape(2)

    def set_gliders(self, reports: Iterable[GliderReport]) -> None:
        """Take the bound pairs of the latest glider report."""
        self.gliders = list(reports)

    def entities(self) -> list[Entity]:
        """Every entity of the current scene."""
        colour_of: dict[int, Rgba] = {}
        for pair in self.gliders:
            colour_of[pair.i] = colour_of[pair.j] = _pair_colour(pair)
        seen = np.all(np.isfinite(self.poses), axis=1) if len(self.poses) else np.zeros(0, dtype=bool)
        out = []
        for k in map(int, np.flatnonzero(seen)):
            x, y = float(self.poses[k, 0]), float(self.poses[k, 1])
            label = Label((x, y, BODY_HEIGHT + 0.005), str(k), LABEL_SIZE, LABEL_COLOUR)
            out.append(Entity(f'robot_{k}', robot_cubes(self.poses[k], self.arms.get(k), self.dims,
                                                         colour_of.get(k, ROBOT_COLOUR)), labels=(label,)))
        for k, trail in sorted(self.trails.items()):
            if len(trail) >= 2:
                out.append(Entity(f'trail_{k}', lines=(Line(tuple((px, py, 0.0) for px, py in trail),
                                                            TRAIL_COLOUR, TRAIL_THICKNESS),)))
        for pair in self.gliders:
            if pair.i < len(seen) and pair.j < len(seen) and seen[pair.i] and seen[pair.j]:
                a, b = self.poses[pair.i, :2], self.poses[pair.j, :2]
                colour = _pair_colour(pair)
                mid = ((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, BODY_HEIGHT + 0.015)
                text = f'{pair.label or pair.glider_class.value} {pair.age:.1f} s ({pair.age_periods} periods)'
                out.append(Entity(f'glider_{pair.i}_{pair.j}',
                                  lines=(Line(((float(a[0]), float(a[1]), BODY_HEIGHT),
                                               (float(b[0]), float(b[1]), BODY_HEIGHT)), colour, BOND_THICKNESS),),
                                  labels=(Label((float(mid[0]), float(mid[1]), mid[2]), text, LABEL_SIZE, colour),)))
        return out

    def update(self) -> SceneUpdate:
        """The current scene, and the ids drawn before that are gone now (an unseen robot, a broken pair)."""
        entities = self.entities()
        ids = {e.id for e in entities}
        gone = tuple(sorted(self._drawn - ids))
        self._drawn = ids
        return SceneUpdate(tuple(entities), gone)
