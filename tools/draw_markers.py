"""Draw the glider monitor's markers for a simulated scene into a PNG (the picture in docs/tracking.md).

Runs a pair scene (C1-like start, r = 1.3 BL) and five parked-free robots of a dense scene through
GliderMonitor and renders ``scene_markers`` of the last frame with ``render_png``, as RViz or Foxglove
would draw /smarticles/markers.

    .venv/bin/python smarticle_tracking/scripts/draw_markers.py docs/figures/tracking_markers.png
"""

from __future__ import annotations

import sys

import numpy as np
from smarticle_common.gait import GaitConfig
from smarticle_sim.scenes import dense_scene
from smarticle_sim.config_builder import build_config
from smarticle_sim.runner import Runner
from smarticle_tracking.glider_monitor import GliderMonitor
from smarticle_tracking.gliders import GliderConfig
from smarticle_tracking.markers import render_png, scene_markers


def main(path: str) -> None:
    """Simulate 8 periods of the dense 7-robot scene and draw the last frame's markers."""
    config = build_config('small')
    gait = GaitConfig.from_degrees(90.0)
    monitor = GliderMonitor(GliderConfig(min_periods=3))
    bound: tuple = ()  # type: ignore[type-arg]
    with Runner.with_gaits(config, dense_scene(config.robot, gait, 7, seed=1)) as run:
        world = run.physics
        run.gaits.start(0.0)
        for _ in range(8 * 32):
            run.run(world.ticks_for(0.05))
            bound = monitor.update(world.time, world.poses())
        poses, arms = world.poses().copy(), world.arm_angles().copy()
    shapes = scene_markers(poses, bound, arms)
    render_png(shapes, path, title=f'/smarticles/markers at t = 12.8 s: {len(bound)} bound pair(s), '
               '7 robots (dense scene, seed 1)')
    print(path, [(b.i, b.j, b.glider_class.value, b.age_periods) for b in bound])
    np.set_printoptions(precision=3)


if __name__ == '__main__':
    main(sys.argv[1] if len(sys.argv) > 1 else 'docs/figures/tracking_markers.png')
