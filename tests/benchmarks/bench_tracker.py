"""Overhead tracker accuracy and speed against sim ground truth: resolution, tag size, noise, blur.

Ground truth: 7 robots (dense scene, seed 1) running the square gait in the PyBullet world, sampled
every 0.4 s (all arm shapes of the gait). Each sample is rendered by ``smarticle_sim.camera`` (OpenCV
path) and tracked by ``smarticle_tracking.tracker`` with a calibration made the way a user would (a
rendered board, ``smarticle-sim-camera-calibrate``). OpenCV runs on one thread (``cv2.setNumThreads(1)``).
Per setting: detection rate, median and 95th percentile position error (mm) and heading error (deg),
and median tracker time per frame. Writes ``out/benchmarks/tracker.csv`` and ``tracker.png``.

    .venv/bin/python tests/benchmarks/bench_tracker.py --quick     # about 1 minute
    .venv/bin/python tests/benchmarks/bench_tracker.py
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import figure, machine_line, markdown_table, out_path, write_csv
from smarticle_common.gait import GaitConfig
from smarticle_sim.camera import CameraConfig, OverheadCamera
from smarticle_sim.scenes import dense_scene
from smarticle_sim.config_builder import build_config
from smarticle_sim.runner import Runner
from smarticle_bringup.sim_camera import sim_calibration
from smarticle_tracking.tracker import TagTracker, TrackerConfig

RESOLUTIONS = ((640, 480), (1280, 720), (1920, 1080))


def ground_truth(samples: int, seed: int = 1) -> list[tuple[np.ndarray, np.ndarray]]:
    """(poses, arm angles) of a 7-robot dense run sampled every 0.4 s (a quarter period)."""
    config = build_config('small')
    gait = GaitConfig.from_degrees(90.0)
    out = []
    with Runner.with_gaits(config, dense_scene(config.robot, gait, 7, seed=seed)) as run:
        world = run.physics
        run.gaits.start(0.0)
        ticks = world.ticks_for(0.4)
        for _ in range(samples):
            run.run(ticks)
            state = world.state()
            out.append((state.poses.copy(), state.arm_angles.copy()))
    return out


def measure(truth: list[tuple[np.ndarray, np.ndarray]], width: int, height: int, tag_size: float = 0.018,
            noise: float = 0.0, blur: float = 0.0, lighting: float = 0.0, detection_tag_px: float = 16.0,
            ) -> dict[str, Any]:
    """Track every ground-truth sample rendered with these settings; return the row of results."""
    import cv2

    camera = OverheadCamera(CameraConfig(width=width, height=height, tag_size=tag_size, noise=noise, blur=blur,
                                         lighting=lighting, seed=7))
    tracker = TagTracker(TrackerConfig(tag_size=tag_size, detection_tag_px=detection_tag_px),
                         sim_calibration(width, height))
    frames = [camera.render(p, a) for p, a in truth]
    errors, headings, times = [], [], []
    seen = 0
    for (poses, _), frame in zip(truth, frames, strict=True):
        cv2.setNumThreads(1)
        start = time.perf_counter()
        result = tracker.track(frame)
        times.append(time.perf_counter() - start)
        s = result.seen
        seen += int(s.sum())
        errors += list(np.hypot(*(result.poses[s, :2] - poses[s, :2]).T) * 1000.0)
        headings += list(np.degrees(np.abs((result.poses[s, 2] - poses[s, 2] + math.pi) % (2 * math.pi) - math.pi)))
    err = np.array(errors) if errors else np.array([math.nan])
    head = np.array(headings) if headings else np.array([math.nan])
    ms = float(np.median(times)) * 1000.0
    return {'width': width, 'height': height, 'tag_mm': tag_size * 1000.0, 'noise': noise, 'blur': blur,
            'lighting': lighting, 'detect_px': detection_tag_px, 'scale': tracker.scale,
            'detection': seen / (7 * len(truth)),
            'pos_median_mm': float(np.median(err)), 'pos_p95_mm': float(np.percentile(err, 95)),
            'head_median_deg': float(np.median(head)), 'head_p95_deg': float(np.percentile(head, 95)),
            'ms_per_frame': ms, 'fps': 1000.0 / ms}


def sweeps(quick: bool) -> list[tuple[str, dict[str, Any]]]:
    """(sweep name, measure() keyword arguments) of every row."""
    rows: list[tuple[str, dict[str, Any]]] = []
    for w, h in RESOLUTIONS:
        rows.append(('resolution', {'width': w, 'height': h}))
    rows.append(('full-size search', {'width': 1920, 'height': 1080, 'detection_tag_px': 0.0}))
    for tag in ((0.012, 0.015, 0.020) if not quick else (0.012, 0.020)):
        rows.append(('tag size', {'width': 1920, 'height': 1080, 'tag_size': tag}))
        if not quick:
            rows.append(('tag size', {'width': 640, 'height': 480, 'tag_size': tag}))
    for noise in ((5.0, 10.0, 20.0) if not quick else (10.0,)):
        rows.append(('noise', {'width': 1920, 'height': 1080, 'noise': noise}))
    for blur in ((1.0, 2.0, 3.0) if not quick else (1.5,)):
        rows.append(('blur', {'width': 1920, 'height': 1080, 'blur': blur}))
    rows.append(('all faults', {'width': 1920, 'height': 1080, 'noise': 8.0, 'blur': 1.0, 'lighting': 0.4}))
    rows.append(('all faults', {'width': 640, 'height': 480, 'noise': 8.0, 'blur': 1.0, 'lighting': 0.4}))
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run the sweep, print the table, write CSV and PNG."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='20 samples and fewer settings (about a minute)')
    parser.add_argument('--samples', type=int, default=None, help='ground-truth samples (default 20 / 75)')
    args = parser.parse_args(argv)
    samples = args.samples or (20 if args.quick else 75)
    print(f'# tracker benchmark: {samples} frames x 7 robots per row; {machine_line()}')
    truth = ground_truth(samples)
    rows = []
    for name, kwargs in sweeps(args.quick):
        row = {'sweep': name, **measure(truth, **kwargs)}
        rows.append(row)
        print(f'  {name}: {row["width"]}x{row["height"]} tag {row["tag_mm"]:.0f} mm noise {row["noise"]:g} '
              f'blur {row["blur"]:g}: {row["detection"]:.3f} {row["pos_median_mm"]:.3f} mm '
              f'{row["ms_per_frame"]:.1f} ms', file=sys.stderr)
    columns = [('sweep', 'sweep', ''),
               ('width', 'width', 'd'), ('height', 'height', 'd'), ('tag_mm', 'tag (mm)', '.0f'),
               ('noise', 'noise (grey)', '.0f'), ('blur', 'blur (px)', '.1f'), ('lighting', 'light loss', '.1f'),
               ('scale', 'search scale', '.2f'), ('detection', 'detected', '.3f'),
               ('pos_median_mm', 'pos median (mm)', '.3f'), ('pos_p95_mm', 'pos p95 (mm)', '.3f'),
               ('head_median_deg', 'heading median (deg)', '.2f'), ('head_p95_deg', 'heading p95 (deg)', '.2f'),
               ('ms_per_frame', 'ms/frame', '.1f'), ('fps', 'frames/s', '.0f')]
    print(markdown_table(rows, columns))
    csv_path = write_csv(out_path('tracker.csv'), rows)
    fig = figure(8.0, 4.0)
    res = [r for r in rows if r['sweep'] == 'resolution']
    ax = fig.add_subplot(1, 2, 1)
    ax.plot([r['height'] for r in res], [r['pos_median_mm'] for r in res], 'o-', label='median')
    ax.plot([r['height'] for r in res], [r['pos_p95_mm'] for r in res], 's--', label='95th pct')
    ax.set_xlabel('image height (px)')
    ax.set_ylabel('position error (mm)')
    ax.legend()
    ax2 = fig.add_subplot(1, 2, 2)
    ax2.plot([r['height'] for r in res], [r['ms_per_frame'] for r in res], 'o-')
    ax2.set_xlabel('image height (px)')
    ax2.set_ylabel('tracker time per frame (ms, one core)')
    fig.tight_layout()
    png = out_path('tracker.png')
    fig.savefig(png)
    print(f'\nwrote {csv_path} and {png}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
