"""Figures of the glider analysis (matplotlib, Agg canvas: no display, no global backend change)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Arc, Polygon

from .gliders import GliderAnalysis
from smarticle_common.pairs import BODY_LENGTH
from smarticle_common.facts import SMALL



def _save(fig: Figure, path: str | Path, dpi: int) -> Path:
    """Render ``fig`` on an Agg canvas into a PNG at ``path``."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(out, dpi=dpi)
    return out


def plot_glider_analysis(analysis: GliderAnalysis, path: str | Path, max_gliders: int = 6,
                         dpi: int = 120) -> Path:
    """Write a PNG of r(t) (BL), phi(t) (deg) and the paths of each bound pair's robots and centre of mass,
    each labelled by its class and kind ('C1 glider', 'C1 bound pair')."""
    cfg = analysis.config
    gliders = analysis.gliders[:max_gliders]
    fig = Figure(figsize=(12, 4.2), layout='constrained')
    ax_r, ax_phi, ax_xy = fig.subplots(1, 3)
    t = analysis.times
    coords = analysis.coords
    if not gliders:   # nothing bound long enough: show every pair faintly so the figure still informs
        for p in range(coords.pairs.shape[0]):
            ax_r.plot(t, coords.r[:, p] / cfg.body_length, lw=0.5, color='0.6')
            ax_phi.plot(t, np.degrees(coords.phi[:, p]), '.', ms=0.5, color='0.6')
        ax_xy.text(0.5, 0.5, f'no bound pair (K = {cfg.min_periods} periods), no glider', ha='center',
                   transform=ax_xy.transAxes)
    colours = [f'C{k}' for k in range(10)]
    for k, g in enumerate(gliders):
        c = colours[k % len(colours)]
        label = f'({g.i},{g.j}) {g.label}, {g.lifetime_periods} T, {g.distance / cfg.width:.2f} W'
        ax_r.plot(t, coords.r[:, g.pair_index] / cfg.body_length, lw=0.7, color=c, label=label)
        ax_r.axvspan(g.start_time, g.end_time, color=c, alpha=0.08)
        ax_phi.plot(t, np.degrees(coords.phi[:, g.pair_index]), '.', ms=1.0, color=c)
        inside = (t >= g.start_time) & (t < g.end_time)
        for robot, style in ((g.i, '-'), (g.j, '--')):
            xy = analysis.poses[inside, robot, :2] / cfg.width
            ax_xy.plot(xy[:, 0], xy[:, 1], style, lw=0.6, color=c, alpha=0.6)
        com = g.com_path / cfg.width
        ax_xy.plot(com[:, 0], com[:, 1], 'o-', ms=1.5, lw=1.2, color=c, label=label)
    ax_r.axhline(cfg.r_bind / cfg.body_length, color='k', lw=0.8, ls=':', label='r_bind')
    ax_r.set(xlabel='t [s]', ylabel='r [BL]', title='centre distance r(t)')
    ax_phi.set(xlabel='t [s]', ylabel='phi [deg]', title='relative heading phi(t)', ylim=(0, 360),
               yticks=[0, 90, 180, 270, 360])
    ax_xy.set(xlabel='x [W]', ylabel='y [W]', title='paths (robots thin, centre of mass bold)')
    ax_xy.set_aspect('equal', adjustable='datalim')
    if gliders:
        ax_r.legend(fontsize=7, loc='upper right')
    return _save(fig, path, dpi)


def _robot_outline(x: float, y: float, heading: float, alpha: tuple[float, float],
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Body rectangle corners and the two arm polylines of a robot, in arena coordinates."""
    normal = np.array([math.cos(heading), math.sin(heading)])
    axis = np.array([math.sin(heading), -math.cos(heading)])     # body x = normal turned by -90 deg
    centre = np.array([x, y])
    hw, hd = SMALL.body_width / 2, SMALL.body_depth / 2
    body = np.array([centre + sx * hw * axis + sy * hd * normal
                     for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    joint1, joint2 = centre - hw * axis, centre + hw * axis
    tip1 = joint1 + SMALL.arm_length * (-math.cos(alpha[0]) * axis + math.sin(alpha[0]) * normal)
    tip2 = joint2 + SMALL.arm_length * (math.cos(alpha[1]) * axis + math.sin(alpha[1]) * normal)
    arms = np.array([[tip1, joint1], [joint2, tip2]])
    return body, arms


def draw_pair_coordinates(path: str | Path, theta: float = math.radians(50.0),
                          phi: float = math.radians(165.0), r_bl: float = 2.4, dpi: int = 150) -> Path:
    """Write the Fig. 3(a) picture of the pair coordinates r, theta, phi (the docs' figure)."""
    r = r_bl * BODY_LENGTH
    heading_i = math.pi / 2                      # robot i: normal up, body axis to the right
    cj = np.array([r * math.cos(theta), r * math.sin(theta)])   # body frame of i = arena frame here
    heading_j = heading_i + phi
    fig = Figure(figsize=(6.4, 5.6), layout='constrained')
    ax = fig.subplots()
    for (cx, cy, h, name, colour) in ((0.0, 0.0, heading_i, 'i', '0.35'),
                                      (cj[0], cj[1], heading_j, 'j', 'tab:blue')):
        body, arms = _robot_outline(cx, cy, h, (math.radians(50), math.radians(50)))
        ax.add_patch(Polygon(body, closed=True, fc=colour, ec='k', alpha=0.85))
        for arm in arms:
            ax.plot(arm[:, 0], arm[:, 1], color=colour, lw=4, solid_capstyle='round')
        ax.annotate('', xy=(cx + 0.045 * math.cos(h), cy + 0.045 * math.sin(h)), xytext=(cx, cy),
                    arrowprops={'arrowstyle': '-|>', 'color': 'crimson', 'lw': 1.8})
        ax.text(cx + 0.052 * math.cos(h), cy + 0.052 * math.sin(h), f'n_{name}', color='crimson',
                ha='center', va='center')
        ax.plot(cx, cy, 'ko', ms=4)
        ax.text(cx + 0.006, cy - 0.022, name, fontsize=12, weight='bold')
    # body axis of i (x_i, joint 1 -> joint 2) and the r vector
    ax.annotate('', xy=(0.11, 0), xytext=(0, 0), arrowprops={'arrowstyle': '->', 'ls': '--', 'color': 'k'})
    ax.text(0.112, -0.006, 'x_i (body axis,\njoint 1 -> joint 2)', fontsize=8, va='top')
    ax.plot([0, cj[0]], [0, cj[1]], 'k-', lw=1.2)
    ax.text(cj[0] / 2 - 0.012, cj[1] / 2 + 0.004, 'r', fontsize=13, style='italic')
    ax.add_patch(Arc((0, 0), 0.06, 0.06, theta1=0.0, theta2=math.degrees(theta), color='darkgreen', lw=1.5))
    ax.text(0.036 * math.cos(theta / 2), 0.036 * math.sin(theta / 2), 'theta', color='darkgreen', fontsize=11)
    # phi: from a copy of n_i carried to j's centre, counter-clockwise to n_j
    ax.plot([cj[0], cj[0]], [cj[1], cj[1] + 0.045], color='crimson', ls=':', lw=1.2)
    ax.add_patch(Arc(tuple(cj), 0.05, 0.05, theta1=math.degrees(heading_i), theta2=math.degrees(heading_j),
                     color='purple', lw=1.5))
    mid = heading_i + phi / 2
    ax.text(cj[0] + 0.05 * math.cos(mid), cj[1] + 0.05 * math.sin(mid), 'phi', color='purple', fontsize=11)
    ax.set_title('Pair coordinates (paper Fig. 3(a)); theta from body axis x_i, CCW;\n'
                 'phi = heading_j - heading_i (normals n), both in [0, 360) deg', fontsize=9)
    ax.set_aspect('equal')
    ax.set_xlim(-0.09, 0.2)
    ax.set_ylim(-0.05, 0.19)
    ax.set_xlabel('arena x [m]')
    ax.set_ylabel('arena y [m]')
    return _save(fig, path, dpi)
