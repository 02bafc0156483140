"""What the glider monitor draws: robot outlines and glider bonds as plain shapes, and a PNG of them.

``scene_markers`` turns poses, optional arm angles and the bound pairs of ``GliderMonitor`` into
``MarkerShape`` values (line lists and texts in the arena frame). The node converts each shape to one
visualization_msgs/Marker (after a DELETEALL), so RViz and Foxglove draw exactly these; ``render_png``
draws the same shapes with matplotlib, "a picture of the markers as RViz or Foxglove would draw them".
No rclpy here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .gliders import GliderClass
from .glider_monitor import BoundPair
from smarticle_common.facts import SMALL

Point = tuple[float, float]
Rgba = tuple[float, float, float, float]

#: Colours of glider bonds (and of their robots' outlines) by class, and of unbound robots.
CLASS_COLOURS: dict[GliderClass, Rgba] = {
    GliderClass.C1: (0.15, 0.55, 1.0, 1.0),
    GliderClass.C2: (1.0, 0.55, 0.0, 1.0),
    GliderClass.UNCLASSIFIED: (0.75, 0.3, 0.9, 1.0),
}
#: A pair bound fewer than K periods: not yet a bound pair, so drawn without a class colour.
BOUND_COLOUR: Rgba = (0.6, 0.6, 0.6, 1.0)
ROBOT_COLOUR: Rgba = (0.85, 0.85, 0.85, 1.0)
TEXT_COLOUR: Rgba = (1.0, 1.0, 1.0, 1.0)
OUTLINE_WIDTH = 0.0015   # m
BOND_WIDTH = 0.004       # m
TEXT_HEIGHT = 0.012      # m


@dataclass(frozen=True)
class RobotDims:
    """Outline geometry of a robot (m): body w x D, arms l x t (defaults: the small smarticle)."""

    body_width: float = SMALL.body_width
    body_depth: float = SMALL.body_depth
    arm_length: float = SMALL.arm_length
    arm_thickness: float = SMALL.arm_thickness


class MarkerShape(NamedTuple):
    """One marker: ``kind`` 'line_list' (pairs of points), 'text' (at ``points[0]``) or 'delete_all'."""

    ns: str
    id: int
    kind: str
    points: tuple[Point, ...]
    rgba: Rgba
    width: float = 0.0          # line width or text height (m)
    text: str = ''


def _rect(centre: np.ndarray, axis: np.ndarray, half_len: float, half_wid: float) -> list[np.ndarray]:
    """Corners of a rectangle around ``centre`` with its long axis along unit vector ``axis``."""
    normal = np.array([-axis[1], axis[0]])
    return [centre + s * half_len * axis + t * half_wid * normal for s, t in ((1, 1), (-1, 1), (-1, -1), (1, -1))]


def _closed(corners: Sequence[np.ndarray]) -> list[Point]:
    """Segment endpoints (line list) of a closed polygon."""
    out: list[Point] = []
    for a, b in zip(corners, [*corners[1:], corners[0]], strict=True):
        out += [(float(a[0]), float(a[1])), (float(b[0]), float(b[1]))]
    return out


def robot_outline(pose: ArrayLike, arm_angles: ArrayLike | None, dims: RobotDims) -> tuple[Point, ...]:
    """Line-list points of a robot: body rectangle, a heading tick along the normal, arms if known."""
    x, y, heading = (float(v) for v in np.asarray(pose, dtype=float))
    yaw = heading - math.pi / 2.0
    ex = np.array([math.cos(yaw), math.sin(yaw)])
    ey = np.array([-ex[1], ex[0]])
    centre = np.array([x, y])
    points = _closed(_rect(centre, ex, dims.body_width / 2.0, dims.body_depth / 2.0))
    tip = centre + ey * dims.body_depth
    points += [(x, y), (float(tip[0]), float(tip[1]))]
    if arm_angles is not None:
        alphas = np.asarray(arm_angles, dtype=float)
        if alphas.shape == (2,) and np.all(np.isfinite(alphas)):
            for sign, angle in ((-1.0, yaw + math.pi - alphas[0]), (1.0, yaw + alphas[1])):
                u = np.array([math.cos(angle), math.sin(angle)])
                joint = centre + sign * ex * dims.body_width / 2.0
                mid = joint + u * dims.arm_length / 2.0
                points += _closed(_rect(mid, u, dims.arm_length / 2.0, dims.arm_thickness / 2.0))
    return tuple(points)


def pair_colour(pair: BoundPair) -> Rgba:
    """The class colour of a bound pair or glider; grey while the run is shorter than K periods."""
    return CLASS_COLOURS[pair.glider_class] if pair.is_bound_pair else BOUND_COLOUR


def scene_markers(poses: ArrayLike, bound: Sequence[BoundPair], arm_angles: ArrayLike | None = None,
                  dims: RobotDims | None = None, body_length: float | None = None) -> list[MarkerShape]:
    """Markers of one moment: DELETEALL, then robots (outline + id), then a bond + label per bound pair."""
    dims = dims or RobotDims()
    bl = body_length or dims.body_width
    arr = np.asarray(poses, dtype=float).reshape(-1, 3)
    arms = None if arm_angles is None else np.asarray(arm_angles, dtype=float).reshape(-1, 2)
    colour_of: dict[int, Rgba] = {}
    for pair in bound:
        colour_of[pair.i] = colour_of[pair.j] = pair_colour(pair)
    shapes = [MarkerShape('', 0, 'delete_all', (), (0.0, 0.0, 0.0, 0.0))]
    seen = np.all(np.isfinite(arr), axis=1)
    for k in map(int, np.flatnonzero(seen)):
        outline = robot_outline(arr[k], None if arms is None or k >= len(arms) else arms[k], dims)
        shapes.append(MarkerShape('robots', k, 'line_list', outline, colour_of.get(k, ROBOT_COLOUR),
                                  OUTLINE_WIDTH))
        label = (float(arr[k, 0]), float(arr[k, 1]))
        shapes.append(MarkerShape('robot_ids', k, 'text', (label,), TEXT_COLOUR, TEXT_HEIGHT * 0.8, str(k)))
    for n, pair in enumerate(bound):
        if not (seen[pair.i] and seen[pair.j]):
            continue
        a = (float(arr[pair.i, 0]), float(arr[pair.i, 1]))
        b = (float(arr[pair.j, 0]), float(arr[pair.j, 1]))
        colour = pair_colour(pair)
        shapes.append(MarkerShape('gliders', n, 'line_list', (a, b), colour, BOND_WIDTH))
        mid = ((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0 + 0.03)
        text = (f'{pair.label} {pair.i}-{pair.j}  r={pair.r / bl:.2f} BL  '
                f'phi={math.degrees(pair.phi):.0f} deg  {pair.age_periods} T')
        shapes.append(MarkerShape('glider_labels', n, 'text', (mid,), colour, TEXT_HEIGHT, text))
    return shapes


def render_png(shapes: Sequence[MarkerShape], path: str | Path, title: str = '',
               extent: tuple[float, float, float, float] | None = None, dpi: int = 130) -> Path:
    """Draw marker shapes as RViz/Foxglove would (top view of the arena frame) into a PNG; return its path."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 6.0), dpi=dpi, facecolor='#303030')
    ax = fig.add_subplot(1, 1, 1, facecolor='#303030')
    xs: list[float] = []
    ys: list[float] = []
    for shape in shapes:
        if shape.kind == 'line_list':
            segs = [shape.points[i:i + 2] for i in range(0, len(shape.points) - 1, 2)]
            lw = max(0.6, shape.width * 1000.0 * 0.6)      # ~points per mm at this scale
            ax.add_collection(LineCollection(segs, colors=[shape.rgba], linewidths=lw))
            xs += [p[0] for p in shape.points]
            ys += [p[1] for p in shape.points]
        elif shape.kind == 'text':
            (x, y), = shape.points
            ax.text(x, y, shape.text, color=shape.rgba, fontsize=max(5.0, shape.width * 700.0),
                    ha='center', va='center')
    if extent is None and xs:
        pad = 0.04
        extent = (min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad)
    if extent is not None:
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
    ax.set_aspect('equal')
    ax.grid(True, color='#505050', linewidth=0.5)
    ax.tick_params(colors='#c0c0c0', labelsize=7)
    ax.set_xlabel('arena x (m)', color='#c0c0c0')
    ax.set_ylabel('arena y (m)', color='#c0c0c0')
    if title:
        ax.set_title(title, color='#e0e0e0', fontsize=9)
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(target, facecolor=fig.get_facecolor())
    return target
