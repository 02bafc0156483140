"""Plane-homography calibration of the overhead camera: pixels -> arena metres on the plane of the tags.

Place tags at known arena poses on the plane the robots' tags will be on (tags on robots at known
places, or a printed board raised to the robots' body height), take one frame, and ``calibrate`` fits
the homography to all their corners (least squares). ``save_calibration`` / ``load_calibration`` store
it as YAML::

    overhead_calibration:
      width: 1920            # image size the homography belongs to (px)
      height: 1080
      homography: [[...], [...], [...]]   # image (u, v, 1) -> arena (x, y, 1), row-major
      rms_error: 0.00004     # m, residual of the tag corners used
      tags_used: 16
      source: board 4x4 ...

No rclpy here; the ``smarticle-tracker-calibrate`` command is in ``homography_cli.py``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from .errors import CameraCalibrationError

FloatArray = NDArray[np.float64]
SECTION = 'overhead_calibration'


@dataclass(frozen=True)
class Calibration:
    """A homography from image pixels to arena metres, valid for frames of ``width`` x ``height``."""

    homography: FloatArray
    width: int
    height: int
    rms_error: float = math.nan
    tags_used: int = 0
    source: str = ''

    def __post_init__(self) -> None:
        h = np.asarray(self.homography, dtype=float)
        if h.shape != (3, 3) or not np.all(np.isfinite(h)) or abs(np.linalg.det(h)) < 1e-300:
            raise CameraCalibrationError(f'homography must be a finite, invertible 3x3 matrix, got {h.tolist()!r}')
        if not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (self.width, self.height)):
            raise CameraCalibrationError(f'calibration image size must be positive whole pixels, got '
                                   f'{self.width!r} x {self.height!r}')
        object.__setattr__(self, 'homography', h)

    def to_arena(self, pixels: FloatArray, camera_matrix: FloatArray | None = None,
                 dist_coeffs: FloatArray | None = None) -> FloatArray:
        """Map pixel points (..., 2) to arena (x, y) metres (undistorting first if distortion is given)."""
        import cv2

        pts = np.asarray(pixels, dtype=np.float64)
        shape = pts.shape
        flat = pts.reshape(-1, 1, 2)
        if camera_matrix is not None and dist_coeffs is not None and np.any(np.asarray(dist_coeffs) != 0.0):
            k = np.asarray(camera_matrix, dtype=np.float64).reshape(3, 3)
            flat = np.asarray(cv2.undistortPoints(flat, k, np.asarray(dist_coeffs, dtype=np.float64), P=k),
                              dtype=np.float64)
        return np.asarray(cv2.perspectiveTransform(flat, self.homography), dtype=np.float64).reshape(shape)


def fit_homography(pixels: FloatArray, arena: FloatArray) -> tuple[FloatArray, float]:
    """Least-squares homography pixel -> arena from matched points (M, 2), M >= 4; and its RMS error (m)."""
    import cv2

    src = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    dst = np.asarray(arena, dtype=np.float64).reshape(-1, 2)
    if src.shape != dst.shape or len(src) < 4:
        raise CameraCalibrationError(f'need at least 4 matched points, got {len(src)} pixel and {len(dst)} arena')
    # normalise the arena side to pixel-like magnitudes for a well-conditioned DLT
    scale = 1000.0
    h, _ = cv2.findHomography(src, dst * scale, 0)
    if h is None:
        raise CameraCalibrationError('the points do not determine a homography (collinear or repeated?)')
    h = np.diag([1.0 / scale, 1.0 / scale, 1.0]) @ h
    mapped = cv2.perspectiveTransform(src.reshape(-1, 1, 2), h).reshape(-1, 2)
    rms = float(np.sqrt(np.mean(np.sum((mapped - dst) ** 2, axis=1))))
    return h / h[2, 2], rms


def calibrate(pixel_corners: FloatArray, ids: NDArray[np.int64], targets: Mapping[int, tuple[float, float, float]],
              tag_size: float, width: int, height: int, source: str = '',
              camera_matrix: FloatArray | None = None, dist_coeffs: FloatArray | None = None) -> Calibration:
    """Fit a Calibration from detected tags (corners (M, 4, 2), ids (M,)) at known poses ``targets``."""
    import cv2

    from smarticle_common.poses import tag_corners

    ids_list = [int(t) for t in np.asarray(ids).ravel()]
    used = [m for m, t in enumerate(ids_list) if t in targets and ids_list.count(t) == 1]
    if len(used) < 2:
        raise CameraCalibrationError(f'found {len(used)} of the {len(targets)} calibration tags '
                               f'({sorted(targets)}) in the frame (tags seen: {sorted(ids_list)}); '
                               'need at least 2 spread over the arena')
    px = np.asarray(pixel_corners, dtype=np.float64).reshape(-1, 4, 2)[used]
    if camera_matrix is not None and dist_coeffs is not None and np.any(np.asarray(dist_coeffs) != 0.0):
        k = np.asarray(camera_matrix, dtype=np.float64).reshape(3, 3)
        px = np.asarray(cv2.undistortPoints(px.reshape(-1, 1, 2), k, np.asarray(dist_coeffs, dtype=np.float64),
                                            P=k), dtype=np.float64).reshape(-1, 4, 2)
    poses = np.array([targets[ids_list[m]] for m in used], dtype=float)
    arena = tag_corners(poses, tag_size)
    h, rms = fit_homography(px.reshape(-1, 2), arena.reshape(-1, 2))
    return Calibration(h, int(width), int(height), rms, len(used), source)


def board_targets(rows: int = 4, cols: int = 4, spacing: float = 0.12, first_id: int = 10,
                  ) -> dict[int, tuple[float, float, float]]:
    """Tag poses of a rows x cols calibration board centred on the origin (ids from ``first_id``, heading 90 deg)."""
    if rows < 1 or cols < 1 or rows * cols < 2 or not spacing > 0.0:
        raise CameraCalibrationError(f'a board needs at least 2 tags and a positive spacing, got {rows}x{cols}, '
                               f'{spacing!r} m')
    out: dict[int, tuple[float, float, float]] = {}
    for r in range(rows):
        for c in range(cols):
            x = (c - (cols - 1) / 2.0) * spacing
            y = ((rows - 1) / 2.0 - r) * spacing
            out[first_id + r * cols + c] = (x, y, math.pi / 2.0)
    return out


def save_calibration(path: str | Path, calibration: Calibration) -> Path:
    """Write ``calibration`` as YAML to ``path`` (folders created); return the path."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    data = {SECTION: {
        'width': calibration.width, 'height': calibration.height,
        'homography': [[float(v) for v in row] for row in calibration.homography],
        'rms_error': float(calibration.rms_error), 'tags_used': int(calibration.tags_used),
        'source': calibration.source}}
    target.write_text('# Plane homography of the overhead camera (smarticle_tracking/calibration.py)\n'
                      + yaml.safe_dump(data, sort_keys=False), encoding='utf-8')
    return target


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration YAML; CameraCalibrationError says what is missing or wrong and how to make one."""
    source = Path(path)
    hint = 'make one with smarticle-tracker-calibrate (or smarticle-sim-camera-calibrate for the sim camera)'
    if not source.is_file():
        raise CameraCalibrationError(f'calibration file {str(source)!r} does not exist; {hint}')
    try:
        data: Any = yaml.safe_load(source.read_text(encoding='utf-8'))
    except (OSError, yaml.YAMLError) as err:
        raise CameraCalibrationError(f'calibration file {str(source)!r} is not readable YAML: {err}') from err
    if not isinstance(data, dict) or not isinstance(data.get(SECTION), dict):
        raise CameraCalibrationError(f'calibration file {str(source)!r} has no {SECTION!r} section; {hint}')
    body = data[SECTION]
    try:
        return Calibration(np.array(body['homography'], dtype=float), body['width'], body['height'],
                           float(body.get('rms_error', math.nan)), int(body.get('tags_used', 0)),
                           str(body.get('source', '')))
    except (KeyError, TypeError, ValueError) as err:
        if isinstance(err, CameraCalibrationError):
            raise CameraCalibrationError(f'{source}: {err}') from err
        raise CameraCalibrationError(f'calibration file {str(source)!r}: missing or malformed field ({err}); '
                               f'{hint}') from err
