"""Draw the gait convention of docs/gait.md: the body frame, the angle signs and the square gait.

Usage: python tools/draw_gait.py [--out docs/figures/gait_convention.png]
"""

from __future__ import annotations

import argparse
import math

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt
import numpy as np

from smarticle_common.gait import GaitConfig, SquareGait

BODY_W, ARM_L = 5.4, 5.0


def robot_outline(alpha1: float, alpha2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return body and arm polylines (cm, body frame) for arm angles alpha1, alpha2."""
    j1, j2 = np.array([-BODY_W / 2, 0.0]), np.array([BODY_W / 2, 0.0])
    tip1 = j1 + ARM_L * np.array([-math.cos(alpha1), math.sin(alpha1)])
    tip2 = j2 + ARM_L * np.array([math.cos(alpha2), math.sin(alpha2)])
    return np.array([j1, j2]), np.array([j1, tip1]), np.array([j2, tip2])


def main() -> None:
    """Write the figure."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--out', default='docs/figures/gait_convention.png')
    args = parser.parse_args()
    config = GaitConfig.from_degrees(90.0)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    ax = axes[0]
    body, arm1, arm2 = robot_outline(math.radians(40), math.radians(40))
    ax.plot(*body.T, 'k-', lw=6, label='body (w = 5.4 cm)')
    ax.plot(*arm1.T, 'tab:blue', lw=3, label='arm 1 (alpha1 = +40 deg)')
    ax.plot(*arm2.T, 'tab:orange', lw=3, label='arm 2 (alpha2 = +40 deg)')
    for arm, sign in ((arm1, -1), (arm2, 1)):
        ax.plot([arm[0, 0], arm[0, 0] + sign * ARM_L], [0, 0], 'k:', lw=1)
    ax.annotate('', xy=(0, 4), xytext=(0, 0), arrowprops={'arrowstyle': '->', 'lw': 2, 'color': 'green'})
    ax.text(0.2, 3.6, 'body normal y = heading', color='green')
    ax.annotate('', xy=(3, 0), xytext=(0, 0), arrowprops={'arrowstyle': '->', 'lw': 1.5})
    ax.text(2.6, -0.7, 'x')
    ax.text(-BODY_W / 2 - 3.5, -1.2, 'alpha1 = 0 (straight)')
    ax.text(-BODY_W / 2, 0.4, 'joint 1', ha='right')
    ax.text(BODY_W / 2, 0.4, 'joint 2')
    ax.set_aspect('equal')
    ax.set_xlim(-9, 9)
    ax.set_ylim(-6, 7)
    ax.legend(loc='lower center', fontsize=8)
    ax.set_title('body frame: alpha > 0 turns the arm tip toward the normal')
    ax = axes[1]
    gait = SquareGait(config)
    gait.start(0.0)
    times = np.arange(0.0, config.period, 0.002)
    path = np.degrees([gait.command(float(t)).positions for t in times])
    ax.plot(path[:, 0], path[:, 1], color='gray', lw=1)
    a = 90
    corners = [(a, a), (-a, a), (-a, -a), (a, -a)]
    for i, (c, d) in enumerate(zip(corners, corners[1:] + corners[:1], strict=False)):
        ax.annotate('', xy=d, xytext=c, arrowprops={'arrowstyle': '->', 'color': 'red', 'lw': 2})
        ax.text(c[0] * 1.12, c[1] * 1.12, f'c{i}', ha='center', va='center', fontsize=12)
        mid = ((c[0] + d[0]) / 2, (c[1] + d[1]) / 2)
        ax.text(mid[0] * 0.75, mid[1] * 0.75, f'q{i}: arm {1 + i % 2}', ha='center', fontsize=9)
    ax.plot(a, a, 'ko', ms=8)
    ax.text(a - 5, a - 15, 'start (phase 0)', ha='right', fontsize=9)
    ax.set_xlabel('alpha1 (deg)')
    ax.set_ylabel('alpha2 (deg)')
    ax.set_xlim(-120, 120)
    ax.set_ylim(-120, 120)
    ax.set_aspect('equal')
    ax.grid(alpha=0.3)
    ax.set_title('square gait, alpha_max = 90 deg: c0 -> c1 -> c2 -> c3')
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)


if __name__ == '__main__':
    main()
