"""The demo's figures: robot paths, a pair's r(t) with the halts marked, and the animation of the run.

Pure (no rclpy); matplotlib on its Agg backend, the animation written as a GIF by matplotlib's
``PillowWriter`` (``smarticle_tracking.gif.BlitGifWriter``: the moving artists are blitted onto a saved
background and each frame mapped onto one fixed palette). Each robot is drawn as its three links, the
footprint rectangles of ``smarticle_sim.geometry.robot_rects`` from its pose and its two arm angles.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from smarticle_common.facts import GAIT_PERIOD, R_BIND_BL, RobotSpec
from smarticle_common.pairs import pair_coordinates
from smarticle_tracking.gliders import MIN_PERIODS

#: Colours: a robot not in a glider, a halted robot's outline, the glider classes (as the live view's).
ROBOT_FILL = '#b8b8c0'
ROBOT_EDGE = '#404048'
HALT_COLOUR = '#d62728'
CLASS_FILL = {'C1': '#2a8cff', 'C2': '#ff8c00', 'unclassified': '#bf4de6'}
#: The animation's scale bar (m): one physical length in every part, whichever robot W stands for.
SCALE_BAR = 0.05



def robot_outlines(spec: RobotSpec, pose: Sequence[float], arms: Sequence[float]) -> list[np.ndarray]:
    """Corners (4, 2) of a robot's body, arm 1 and arm 2 (m) at ``pose`` (x, y, heading) and ``arms``
    (alpha1, alpha2, rad; NaN: drawn straight)."""
    from smarticle_sim.geometry import rect_corners, robot_rects

    a1, a2 = (0.0 if not math.isfinite(a) else float(a) for a in arms)
    return [rect_corners(r) for r in robot_rects(spec, float(pose[0]), float(pose[1]), float(pose[2]), a1, a2)]


@dataclass(frozen=True)
class GliderSpan:
    """A bound pair to highlight: its robots, class, the sim times it was bound, its travel (W) and what the run
    so far is after each of its periods (``smarticle_tracking.gliders.running_labels``: 'bound', then e.g.
    'C1 bound pair', 'C1 glider'); without labels, 'bound' and then '<class> bound pair' from its K-th period."""

    i: int
    j: int
    glider_class: str
    start: float     # s after the gait start
    end: float       # s after the gait start
    travel_w: float
    labels: Sequence[str] = ()

    def label_at(self, t: float) -> str | None:
        """The words for the pair at ``t`` (s): those of its completed bound periods; None before the first
        one ends or outside the run. A label appears only once its definition is met."""
        done = math.floor((t - self.start) / GAIT_PERIOD + 1e-9)
        if not self.start <= t < self.end or done < 1:
            return None
        if self.labels:
            return self.labels[min(done, len(self.labels)) - 1]
        return f'{self.glider_class} bound pair' if done >= MIN_PERIODS else 'bound'


@dataclass(frozen=True)
class AnimatedPart:
    """One part of the run as the animation shows it."""

    label: str                        # title line of the part
    spec: RobotSpec
    times: np.ndarray                 # (T,) s after the gait start
    poses: np.ndarray                 # (T, N, 3)
    arms: np.ndarray                  # (T, N, 2) rad, NaN where unknown
    gliders: Sequence[GliderSpan] = ()
    halts: Sequence[tuple[float, int, str]] = ()   # (s after the gait start, robot, face)
    phases: Sequence[float] = ()      # each robot's gait phase (periods): a halted robot holds until its next period

    def held(self, t: float) -> set[int]:
        """The robots holding their arms at ``t`` (s after the start): halted, their next gait period not begun."""
        robots = set()
        for s, k, _ in self.halts:
            phase = self.phases[k] if k < len(self.phases) else 0.0
            resume = (math.floor(s / GAIT_PERIOD + phase + 1e-9) + 1.0 - phase) * GAIT_PERIOD
            if s <= t < resume:
                robots.add(k)
        return robots


def frame_indices(times: np.ndarray, step: float) -> np.ndarray:
    """Indices of the samples nearest to every ``step`` seconds of ``times`` (no repeats)."""
    if len(times) == 0:
        return np.empty(0, dtype=int)
    wanted = np.arange(times[0], times[-1] + 1e-9, step)
    idx = np.clip(np.searchsorted(times, wanted), 0, len(times) - 1)
    return np.unique(idx)


def view_box(part: AnimatedPart) -> tuple[np.ndarray, float]:
    """Centre (x, y) and half side (m) of the square that holds every robot of ``part`` with its arms."""
    xy = part.poses[:, :, :2].reshape(-1, 2)
    lo = np.nanmin(xy, axis=0) - part.spec.reach
    hi = np.nanmax(xy, axis=0) + part.spec.reach
    return (lo + hi) / 2.0, max(float(np.max(hi - lo)) / 2.0, 2.0 * part.spec.body_width)


def scale_label(spec: RobotSpec) -> str:
    """The scale bar's label: its length in cm and the W of ``spec`` (its body width) in cm."""
    return f'{SCALE_BAR * 100:.0f} cm   (W = {spec.body_width * 100:.1f} cm)'


def write_animation(parts: Sequence[AnimatedPart], path: Path, step: float = 0.2, fps: int = 20,
                    size_px: int = 420) -> Path:
    """Write a GIF of ``parts`` one after the other: robots as three links, bound pairs with a bond between the
    two, in their class colour and labelled ('C1 bound pair', 'C1 glider') only once the run so far meets that,
    each robot's path once per period, a robot outlined in red while it holds after a halt, the time, the gait
    period and the halts so far. Every part is drawn at one scale, with a scale bar of ``SCALE_BAR`` metres
    labelled in centimetres and the part's W (its preset's body width)."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    dpi = 100
    fig = Figure(figsize=(size_px / dpi, size_px / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)   # a canvas that keeps its pixels: the moving artists are blitted onto a background
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.02, top=0.88)
    ax = fig.add_subplot(1, 1, 1)
    from smarticle_tracking.gif import BlitGifWriter, fixed_palette

    writer = BlitGifWriter(fps, fixed_palette([ROBOT_FILL, ROBOT_EDGE, HALT_COLOUR, *CLASS_FILL.values()]))
    path.parent.mkdir(parents=True, exist_ok=True)
    views = [view_box(part) for part in parts]
    half = max((h for _, h in views), default=0.0)   # one scale for every part: the bar keeps its length
    with writer.saving(fig, str(path), dpi):
        for part, (centre, _) in zip(parts, views, strict=True):
            ax.clear()
            ax.set_aspect('equal')
            ax.set_xticks([])
            ax.set_yticks([])
            xy = part.poses[:, :, :2]
            x0, y0 = centre[0] - half, centre[1] - half
            ax.set_xlim(x0, centre[0] + half)
            ax.set_ylim(y0, centre[1] + half)
            ax.plot([x0 + 0.05 * half, x0 + 0.05 * half + SCALE_BAR], [y0 + 0.06 * half] * 2, color='k', lw=2)
            ax.text(x0 + 0.05 * half, y0 + 0.09 * half, scale_label(part.spec), fontsize=7)
            fig.suptitle(textwrap.fill(part.label, 64), fontsize=8)
            n = part.poses.shape[1]
            links = [[Polygon(np.zeros((4, 2)), closed=True, fc=ROBOT_FILL, ec=ROBOT_EDGE, lw=0.6, animated=True,
                              antialiased=False)   # hard edges: a third smaller GIF
                      for _ in range(3)] for _ in range(n)]
            for robot in links:
                for patch in robot:
                    ax.add_patch(patch)
            trails = [ax.plot([], [], lw=0.7, color='0.6', animated=True)[0] for _ in range(n)]
            bond, = ax.plot([], [], lw=2.0, color='k', alpha=0.6, animated=True)
            info = ax.text(0.02, 0.98, '', transform=ax.transAxes, va='top', fontsize=7, family='monospace',
                           animated=True)
            names = [ax.text(0, 0, str(k), fontsize=7, ha='center', va='center', animated=True) for k in range(n)]
            moving = [*trails, bond, *(patch for robot in links for patch in robot), *names, info]
            canvas.draw()
            background = canvas.copy_from_bbox(fig.bbox)
            # trails: one point per gait period (the within-period wiggle drops out) and the current one
            strobe = np.unique(np.searchsorted(part.times, np.arange(0.0, part.times[-1] + 1e-9, GAIT_PERIOD)))
            for index in frame_indices(part.times, step):
                t = float(part.times[index])
                path_idx = [*strobe[strobe <= index], index]
                live = [(g, label) for g in part.gliders if (label := g.label_at(t)) is not None]
                colour = {}
                for g, label in live:   # the class colour once the pair is a bound pair (its label names the class)
                    if label != 'bound':
                        colour[g.i] = colour[g.j] = CLASS_FILL.get(label.split()[0], CLASS_FILL['unclassified'])
                halted = part.held(t)
                for k in range(n):
                    pose = part.poses[index, k]
                    seen = bool(np.all(np.isfinite(pose)))
                    outlines = robot_outlines(part.spec, pose, part.arms[index, k]) if seen else [np.zeros((4, 2))] * 3
                    for patch, corners in zip(links[k], outlines, strict=True):
                        patch.set_xy(corners)
                        patch.set_visible(seen)
                        patch.set_facecolor(colour.get(k, ROBOT_FILL))
                        patch.set_edgecolor(HALT_COLOUR if k in halted else ROBOT_EDGE)
                        patch.set_linewidth(2.0 if k in halted else 0.6)
                    trails[k].set_data(xy[path_idx, k, 0], xy[path_idx, k, 1])
                    names[k].set_position((pose[0], pose[1]) if seen else (np.nan, np.nan))
                if live:
                    g = live[0][0]
                    bond.set_data(part.poses[index, [g.i, g.j], 0], part.poses[index, [g.i, g.j], 1])
                else:
                    bond.set_data([], [])
                done = [(s, k) for s, k, _ in part.halts if s <= t]
                lines = [f't = {t:5.1f} s   period {t / GAIT_PERIOD:4.1f}']
                lines += [f'{g.i}-{g.j} {label}: bound {(t - g.start) / GAIT_PERIOD:4.1f} periods' for g, label in live]
                if part.halts or 'feedback' in part.label:
                    per = [sum(1 for _, r in done if r == k) for k in range(n)]
                    lines.append('halts: ' + ', '.join(f'{k}: {c}' for k, c in enumerate(per))
                                 + ('   holding: ' + ', '.join(str(k) for k in sorted(halted)) if halted else ''))
                info.set_text('\n'.join(lines))
                canvas.restore_region(background)
                for artist in moving:
                    ax.draw_artist(artist)
                writer.grab_frame()
    return path


def plot_trajectories(times: np.ndarray, poses: np.ndarray, width: float, path: Path, title: str) -> Path:
    """Draw every robot's body-centre path (in W) with start and end markers."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 6), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    xy = poses[:, :, :2] / width
    for k in range(xy.shape[1]):
        line, = ax.plot(xy[:, k, 0], xy[:, k, 1], lw=0.8, label=f'robot {k}')
        ax.plot(*xy[0, k], 'o', color=line.get_color(), ms=4)
        ax.plot(*xy[-1, k], 's', color=line.get_color(), ms=5)
        ax.annotate('', xy=xy[-1, k] + 0.4 * np.array([math.cos(poses[-1, k, 2]), math.sin(poses[-1, k, 2])]),
                    xytext=xy[-1, k], arrowprops={'arrowstyle': '->', 'color': line.get_color()})
    ax.set_aspect('equal')
    ax.set_xlabel('x (W)')
    ax.set_ylabel('y (W)')
    ax.set_title(f'{title}: {xy.shape[1]} robots, {times[-1]:.0f} s (o start, square end, arrow heading)',
                 fontsize=8)
    ax.legend(fontsize=7)
    fig.savefig(path)
    return path


def plot_halts(times: np.ndarray, poses: np.ndarray, halts: Sequence[tuple[float, int, str]], body_length: float,
               path: Path, title: str, pair: tuple[int, int] = (0, 1)) -> Path:
    """r (BL) and phi (deg) of ``pair`` over time (gait periods), every halt a vertical line in its robot's
    colour with its face, and the bind distance ``R_BIND_BL``."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    coords = pair_coordinates(poses[:, list(pair)])
    periods = times / GAIT_PERIOD
    fig = Figure(figsize=(7.5, 4.6), dpi=100)
    ax_r, ax_phi = fig.subplots(2, 1, sharex=True, gridspec_kw={'height_ratios': [2, 1]})
    ax_r.plot(periods, coords.r[:, 0] / body_length, color='k', lw=1.0, label=f'r of robots {pair[0]}-{pair[1]}')
    ax_r.axhline(R_BIND_BL, color='0.5', ls='--', lw=0.8, label=f'bound below {R_BIND_BL:g} BL')
    ax_phi.plot(periods, (np.degrees(coords.phi[:, 0]) + 180.0) % 360.0 - 180.0, color='k', lw=0.8)
    colours = ('#d62728', '#1f77b4', '#2ca02c', '#9467bd')
    for robot in sorted({k for _, k, _ in halts}):
        ts = [s / GAIT_PERIOD for s, k, _ in halts if k == robot]
        for ax in (ax_r, ax_phi):
            for i, s in enumerate(ts):
                ax.axvline(s, color=colours[robot % len(colours)], lw=0.9, alpha=0.8,
                           label=f'halt of robot {robot} ({len(ts)})' if ax is ax_r and i == 0 else None)
    ax_r.set_ylabel('r (BL)')
    ax_phi.set_ylabel('phi (deg)')
    ax_phi.set_ylim(-180.0, 180.0)
    ax_phi.set_xlabel('gait periods after the start')
    ax_r.set_title(title, fontsize=9)
    ax_r.legend(fontsize=7, loc='upper left')
    fig.tight_layout()
    fig.savefig(path)
    return path
