"""Sim camera: rendering cost of the two paths, and what rendering only while subscribed saves.

1. Per resolution, milliseconds per frame of ``OverheadCamera.render`` with the ``opencv`` path (draw
   the known geometry) and the ``pybullet`` path (``getCameraImage``, TINY renderer, on Physics.client),
   7 robots, one thread; plus the tracker's detection rate and median error on each path's frames.
2. The sim bridge core over one sim second (20 publish periods, 7 robots, lock-step commands from the gait
   cores): advancing only (nobody subscribes to the camera: nothing is rendered) against advancing plus a
   1920x1080 frame every period converted to message bytes (someone subscribes, camera_rate 20 Hz).

Writes ``out/benchmarks/camera.csv``.

    .venv/bin/python tests/benchmarks/bench_camera.py --quick
"""

from __future__ import annotations

import argparse
import array
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_line, markdown_table, out_path, write_csv
from smarticle_common import topics
from smarticle_common.gait import GaitConfig, SquareGait
from smarticle_sim.bridge import BridgeSettings, SimBridgeCore
from smarticle_sim.camera import CameraConfig, OverheadCamera
from smarticle_bringup.sim_camera import sim_calibration
from smarticle_tracking.tracker import TagTracker, TrackerConfig

RESOLUTIONS = ((640, 480), (1280, 720), (1920, 1080))


def render_costs(repeats: int) -> list[dict[str, Any]]:
    """ms per frame and tracking quality of both rendering paths at each resolution."""
    import cv2

    cv2.setNumThreads(1)
    core = SimBridgeCore(BridgeSettings.defaults())
    rows = []
    try:
        core.advance()
        state = core.physics.state()
        for w, h in RESOLUTIONS:
            tracker = TagTracker(TrackerConfig(), sim_calibration(w, h))
            for backend in ('opencv', 'pybullet'):
                camera = OverheadCamera(CameraConfig(width=w, height=h, backend=backend))
                frame = camera.render(state.poses, state.arm_angles, physics=core.physics)
                times = []
                for _ in range(repeats):
                    start = time.perf_counter()
                    camera.render(state.poses, state.arm_angles, physics=core.physics)
                    times.append(time.perf_counter() - start)
                result = tracker.track(frame)
                err = np.hypot(*(result.poses[result.seen, :2] - state.poses[result.seen, :2]).T) * 1000.0
                rows.append({'width': w, 'height': h, 'backend': backend,
                             'render_ms': float(np.median(times)) * 1000.0,
                             'detected': float(result.seen.mean()),
                             'pos_median_mm': float(np.median(err)) if err.size else math.nan})
    finally:
        core.close()
    return rows


def subscription_savings(seconds: float) -> list[dict[str, Any]]:
    """Wall time of one sim run with and without rendering 1080p frames at every publish period."""
    rows = []
    for rendered in (False, True):
        core = SimBridgeCore(BridgeSettings.defaults(camera_rate=20.0))
        gaits = [SquareGait(GaitConfig.from_degrees(90.0)) for _ in range(core.n_robots)]
        for gait in gaits:
            gait.start(0.0)
        periods = round(seconds / core.settings.publish_period)
        render_time = 0.0
        start = time.perf_counter()
        try:
            for _ in range(periods):
                for k, gait in enumerate(gaits):
                    cmd = gait.command(core.time)
                    core.apply_command(k, list(topics.JOINT_NAMES), list(cmd.targets), [cmd.speed] * 2, core.time_ns)
                core.advance()
                if core.frame_due():
                    if rendered:
                        t0 = time.perf_counter()
                        frame = core.render_frame()
                        array.array('B', frame.tobytes())          # what the node hands to the message
                        render_time += time.perf_counter() - t0
                    else:
                        core.skip_frame()
        finally:
            core.close()
        wall = time.perf_counter() - start
        rows.append({'camera': 'subscribed: render 1920x1080 at 20 Hz' if rendered else 'no subscriber: skip',
                     'wall_s': wall, 'real_time_factor': seconds / wall, 'render_s': render_time})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Measure, print the tables, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='fewer repeats and a shorter run (< 1 min)')
    args = parser.parse_args(argv)
    print(f'# camera benchmark; {machine_line()}')
    costs = render_costs(5 if args.quick else 20)
    print(markdown_table(costs, [('width', 'width', 'd'), ('height', 'height', 'd'), ('backend', 'path', ''),
                                 ('render_ms', 'ms/frame', '.1f'), ('detected', 'detected', '.2f'),
                                 ('pos_median_mm', 'pos median (mm)', '.3f')]))
    print()
    savings = subscription_savings(2.0 if args.quick else 10.0)
    print(markdown_table(savings, [('camera', 'camera', ''), ('wall_s', 'wall (s)', '.2f'),
                                   ('real_time_factor', 'x real time', '.1f'),
                                   ('render_s', 'of which rendering (s)', '.2f')]))
    path = write_csv(out_path('camera.csv'), [{'table': 'render', **r} for r in costs]
                     + [{'table': 'subscription', **r} for r in savings])
    print(f'\nwrote {path}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
