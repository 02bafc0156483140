"""``smarticle-tracker-calibrate``: compute the overhead camera's plane homography and store it as YAML.

Real camera: take one frame with tags at known arena poses on the plane of the robots' tags, then::

    smarticle-tracker-calibrate --image frame.png --targets targets.yaml --out calibration.yaml

where ``targets.yaml`` holds ``tag_size`` (m), optionally ``dictionary``, and ``tags: {id: [x, y,
heading_deg]}`` (tag centres, heading = direction of the tag's top edge). ``--board ROWSxCOLS
--spacing M --first-id N`` stands for a printed board centred on the arena origin instead.

The simulated camera is calibrated by ``smarticle-sim-camera-calibrate`` (``smarticle_bringup.sim_camera``),
which joins the sim's camera and this package's detector. Exit codes: 0 ok, 2 bad input.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from smarticle_common.facts import TAG_DICTIONARY, TAG_SIZE

from .errors import TrackingError
from .homography import board_targets, calibrate, save_calibration
from .tracker import TagDetector, TrackerConfig
from smarticle_common.cli import add_version


def read_targets(path: str) -> tuple[dict[int, tuple[float, float, float]], float, str]:
    """Known tag poses, tag size and dictionary from a targets YAML (ValueError says what is wrong)."""
    data: Any = yaml.safe_load(Path(path).read_text(encoding='utf-8'))
    if not isinstance(data, dict) or not isinstance(data.get('tags'), dict) or 'tag_size' not in data:
        raise ValueError(f'{path}: need keys tag_size (m) and tags: {{id: [x, y, heading_deg]}}')
    tags = {int(k): (float(v[0]), float(v[1]), math.radians(float(v[2]))) for k, v in data['tags'].items()}
    return tags, float(data['tag_size']), str(data.get('dictionary', TAG_DICTIONARY))


def main(argv: list[str] | None = None) -> int:
    """Run the calibration command; return the exit code."""
    parser = argparse.ArgumentParser(prog='smarticle-tracker-calibrate', description=__doc__.split('\n')[0])
    add_version(parser, 'smarticle_tracking')
    parser.add_argument('--out', default=None, help='calibration YAML to write')
    parser.add_argument('--image', help='frame with the calibration tags (any format OpenCV reads)')
    parser.add_argument('--targets', help='YAML with tag_size and tags: {id: [x, y, heading_deg]}')
    parser.add_argument('--board', help='ROWSxCOLS board centred on the origin instead of --targets')
    parser.add_argument('--spacing', type=float, default=0.12, help='board tag spacing (m)')
    parser.add_argument('--first-id', type=int, default=10, help='id of the board\'s first tag')
    parser.add_argument('--tag-size', type=float, default=TAG_SIZE, help='board tag size (m)')
    args = parser.parse_args(argv)
    try:
        import cv2

        if not args.image or not (args.targets or args.board) or not args.out:
            parser.error('give --image, --targets (or --board) and --out '
                         '(the simulated camera: smarticle-sim-camera-calibrate)')
        frame = cv2.imread(args.image, cv2.IMREAD_GRAYSCALE)
        if frame is None:
            raise ValueError(f'cannot read image {args.image!r}')
        if args.targets:
            targets, tag_size, dictionary = read_targets(args.targets)
        else:
            rows, cols = (int(v) for v in args.board.lower().split('x'))
            targets = board_targets(rows, cols, args.spacing, args.first_id)
            tag_size, dictionary = args.tag_size, TAG_DICTIONARY
        found = TagDetector(TrackerConfig(tag_ids=tuple(sorted(targets)), dictionary=dictionary,
                                          tag_size=tag_size)).detect(np.asarray(frame, dtype=np.uint8))
        calibration = calibrate(found.corners, found.ids, targets, tag_size, frame.shape[1],
                                frame.shape[0], source=f'{args.image}, {len(targets)} known tags')
        out = args.out
    except (TrackingError, ValueError, OSError) as err:
        print(f'smarticle-tracker-calibrate: {err}', file=sys.stderr)
        return 2
    save_calibration(out, calibration)
    print(f'wrote {out}: {calibration.tags_used} tags, RMS corner error {calibration.rms_error * 1000:.3f} mm')
    return 0


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
