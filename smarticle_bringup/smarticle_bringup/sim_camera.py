"""The overhead tracker calibrated against the simulated camera: the sim's camera meets the tracker here.

``smarticle-sim-camera-calibrate [--width 1920 --height 1080 --out FILE]`` renders a board of tags with
``smarticle_sim.camera`` at the tags' height, finds them with ``smarticle_tracking``'s detector and
writes the plane homography (the shipped ``smarticle_tracking/config/sim_overhead_calibration.yaml`` was
made this way). Exit codes: 0 ok, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np
from smarticle_sim.camera import CameraConfig, OverheadCamera
from smarticle_tracking.homography import Calibration, board_targets, calibrate, save_calibration
from smarticle_tracking.errors import TrackingError
from smarticle_tracking.tracker import TagDetector, TrackerConfig
from smarticle_common.cli import add_version


def sim_calibration(width: int = 1920, height: int = 1080, **camera: Any) -> Calibration:
    """Calibrate the simulated camera (``smarticle_sim.camera.CameraConfig`` fields) from a rendered board."""
    targets = board_targets()
    ids = sorted(targets)
    config = CameraConfig(width=width, height=height, tag_ids=tuple(ids), **camera)
    frame = OverheadCamera(config).render(np.array([targets[i] for i in ids]))
    found = TagDetector(TrackerConfig(tag_ids=tuple(ids), dictionary=config.dictionary,
                                      tag_size=config.tag_size)).detect(frame)
    return calibrate(found.corners, found.ids, targets, config.tag_size, width, height,
                     source=f'sim camera {width}x{height}, board of {len(ids)} tags')


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``smarticle-sim-camera-calibrate``; return the exit code."""
    parser = argparse.ArgumentParser(prog='smarticle-sim-camera-calibrate', description=__doc__.split('\n')[0])
    add_version(parser, 'smarticle_bringup')
    parser.add_argument('--width', type=int, default=1920, help='image width (px)')
    parser.add_argument('--height', type=int, default=1080, help='image height (px)')
    parser.add_argument('--out', default=None, help='calibration YAML to write (default: print a summary only)')
    args = parser.parse_args(argv)
    try:
        result = sim_calibration(args.width, args.height)
        if args.out:
            save_calibration(args.out, result)
    except (TrackingError, ValueError, OSError) as err:
        print(f'smarticle-sim-camera-calibrate: {err}', file=sys.stderr)
        return 2
    print(f'{result.source}: {result.tags_used} tags, RMS corner error {result.rms_error * 1000:.3f} mm'
          + (f'; written to {args.out}' if args.out else ''))
    return 0


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
