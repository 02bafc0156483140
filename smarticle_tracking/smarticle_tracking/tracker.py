"""Overhead tracker core: ArUco tags in a camera frame -> per-robot planar poses in the arena frame.

Each robot carries one ArUco tag (default dictionary DICT_4X4_50, 18 mm outer black square) centred on
the top of its body, the tag's top edge toward the body normal (the heading) and its left-to-right edge
along the body x axis (joint 1 to joint 2). The tag id says which robot it is: ``tag_ids[k]`` is the
tag of robot ``k``. A calibrated plane homography (``calibration.py``) maps image pixels to arena
metres on the plane of the tags; the four mapped corners give the body centre (their mean) and the
heading (the tag's up and right edges, averaged). No rclpy here (docs/tracking.md).

Speed: tags are searched on a copy of the frame shrunk by a whole factor (while tags still span
``detection_tag_px`` pixels) and their corners refined on the full-size frame; only when a robot's tag is
not found that way is the full-size frame searched as well.

Missing robots: a robot whose tag is not found (or is rejected) gets a NaN pose, never an old one (the node
publishes it as the contract's unseen pose, ``topics.UNSEEN_Z``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from smarticle_common.facts import TAG_DICTIONARY, TAG_SIZE
from smarticle_common.poses import poses_from_corners

from .errors import FrameEncodingError, FrameSizeError, TrackerConfigError, TrackerInputError
from .homography import Calibration

FloatArray = NDArray[np.float64]

#: Image encodings the tracker reads (sensor_msgs/Image names) and their channel counts.
ENCODINGS: dict[str, int] = {'mono8': 1, 'bgr8': 3, 'rgb8': 3, 'bgra8': 4, 'rgba8': 4}


def aruco_dictionary(name: str) -> Any:
    """The predefined OpenCV ArUco dictionary ``name`` (e.g. 'DICT_4X4_50'); TrackerConfigError if unknown."""
    import cv2

    ident = getattr(cv2.aruco, name, None) if isinstance(name, str) and name.startswith('DICT_') else None
    if not isinstance(ident, int):
        raise TrackerConfigError(f'unknown ArUco dictionary {name!r}; use a cv2.aruco.DICT_* name such as '
                                 'DICT_4X4_50')
    return cv2.aruco.getPredefinedDictionary(ident)


@dataclass(frozen=True)
class TrackerConfig:
    """Tag layout and detector settings (SI units)."""

    tag_ids: tuple[int, ...] = tuple(range(7))   # tag id of robot k = tag_ids[k]
    dictionary: str = TAG_DICTIONARY
    tag_size: float = TAG_SIZE                   # m, outer black square
    size_tolerance: float = 0.25                 # reject tags whose mapped side is off by this fraction
    threshold_window: int = 13                   # px, one adaptive-threshold window (0: OpenCV's sweep)
    refine: bool = True                          # sub-pixel corner refinement (on the full-size frame)
    detection_tag_px: float = 16.0               # find tags on a frame shrunk by a whole factor while tags
                                                 # still span this many pixels (0: always at full size)
    robot_of_tag: dict[int, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ids = self.tag_ids
        if not ids or any(isinstance(t, bool) or not isinstance(t, (int, np.integer)) or t < 0 for t in ids):
            raise TrackerConfigError(f'tag_ids must be a non-empty list of tag ids >= 0 (index = robot id), '
                                     f'got {ids!r}')
        if len(set(ids)) != len(ids):
            raise TrackerConfigError(f'tag_ids must not repeat a tag id, got {list(ids)}')
        dictionary = aruco_dictionary(self.dictionary)
        size = dictionary.bytesList.shape[0]
        if max(ids) >= size:
            raise TrackerConfigError(f'tag id {max(ids)} is not in {self.dictionary} (ids 0..{size - 1})')
        if not (math.isfinite(self.tag_size) and 0.001 <= self.tag_size <= 1.0):
            raise TrackerConfigError(f'tag_size must be in [0.001, 1] m, got {self.tag_size!r}')
        if not 0.0 < self.size_tolerance < 1.0:
            raise TrackerConfigError(f'size_tolerance must be in (0, 1), got {self.size_tolerance!r}')
        window = self.threshold_window
        if window != 0 and (window < 3 or window % 2 == 0):
            raise TrackerConfigError(f'threshold_window must be 0 or an odd number of pixels >= 3, got {window!r}')
        if not (math.isfinite(self.detection_tag_px) and (self.detection_tag_px == 0.0
                                                          or 8.0 <= self.detection_tag_px <= 1000.0)):
            raise TrackerConfigError(f'detection_tag_px must be 0 or in [8, 1000] px, got {self.detection_tag_px!r}')
        object.__setattr__(self, 'robot_of_tag', {int(t): k for k, t in enumerate(ids)})

    @property
    def n_robots(self) -> int:
        """Number of robots (the length of tag_ids)."""
        return len(self.tag_ids)


class Detections(NamedTuple):
    """Tags found in one frame: pixel corners (M, 4, 2) in ArUco order and ids (M,)."""

    corners: FloatArray
    ids: NDArray[np.int64]


class TrackResult(NamedTuple):
    """One frame's outcome: poses (N, 3) x, y (m), heading (rad), NaN where unseen; problems found."""

    poses: FloatArray
    seen: NDArray[np.bool_]
    problems: tuple[tuple[str, str], ...]   # (counter, human-readable text), one per rejected tag or issue
    counts: dict[str, int]             # counter name -> occurrences in this frame


def image_from_buffer(encoding: str, height: int, width: int, step: int, data: bytes | bytearray | memoryview,
                      ) -> NDArray[np.uint8]:
    """A grey (height, width) uint8 view/copy of a sensor_msgs/Image buffer; TrackerInputError if unusable."""
    import cv2

    channels = ENCODINGS.get(encoding)
    if channels is None:
        raise FrameEncodingError(f'unsupported image encoding {encoding!r}; use one of {", ".join(ENCODINGS)}')
    if height <= 0 or width <= 0 or step < width * channels:
        raise FrameEncodingError(f'image {width}x{height} {encoding} with step {step} is malformed')
    buffer = np.frombuffer(data, dtype=np.uint8)
    if buffer.size < step * height:
        raise FrameEncodingError(f'image data has {buffer.size} bytes, {encoding} {width}x{height} '
                                f'with step {step} needs {step * height}')
    rows = buffer[:step * height].reshape(height, step)[:, :width * channels]
    if channels == 1:
        return rows
    pixels = rows.reshape(height, width, channels)
    code = {'bgr8': cv2.COLOR_BGR2GRAY, 'rgb8': cv2.COLOR_RGB2GRAY, 'bgra8': cv2.COLOR_BGRA2GRAY,
            'rgba8': cv2.COLOR_RGBA2GRAY}[encoding]
    return np.asarray(cv2.cvtColor(pixels, code), dtype=np.uint8)


class TagDetector:
    """ArUco detection with the tracker's settings, optionally on a shrunk frame with full-size refinement."""

    def __init__(self, config: TrackerConfig) -> None:
        import cv2

        params = cv2.aruco.DetectorParameters()
        if config.threshold_window:
            params.adaptiveThreshWinSizeMin = config.threshold_window
            params.adaptiveThreshWinSizeMax = config.threshold_window
        params.minMarkerPerimeterRate = 0.01      # small tags in a wide view
        self.refine = config.refine
        self._cv2 = cv2
        self._detector = cv2.aruco.ArucoDetector(aruco_dictionary(config.dictionary), params)
        self._criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01)

    def detect(self, image: NDArray[np.uint8], scale: float = 1.0) -> Detections:
        """Find tags in a grey uint8 image, searching a copy shrunk by ``scale`` (<= 1) when below 1."""
        cv2 = self._cv2
        work = image
        if scale < 1.0:
            work = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        corners, ids, _ = self._detector.detectMarkers(work)
        if ids is None or len(ids) == 0:
            return Detections(np.zeros((0, 4, 2)), np.zeros(0, dtype=np.int64))
        pts = np.asarray(corners, dtype=np.float32).reshape(-1, 1, 2)
        if scale < 1.0:   # pixel centres: x_full = (x_small + 0.5) / scale - 0.5
            sx = image.shape[1] / work.shape[1]
            sy = image.shape[0] / work.shape[0]
            pts = ((pts + 0.5) * np.array([sx, sy], dtype=np.float32) - 0.5).astype(np.float32)
        if self.refine:
            win = max(2, int(round(1.5 / min(scale, 1.0))))
            pts = cv2.cornerSubPix(image, pts, (win, win), (-1, -1), self._criteria)
        return Detections(pts.reshape(-1, 4, 2).astype(float), ids.ravel().astype(np.int64))


def detection_scale(config: TrackerConfig, calibration: Calibration) -> float:
    """Shrink factor 1/n (n whole, fast to resize) keeping a tag at the image centre >= ``detection_tag_px`` px."""
    if config.detection_tag_px == 0.0:
        return 1.0
    centre = np.array([[[calibration.width / 2.0, calibration.height / 2.0],
                        [calibration.width / 2.0 + 10.0, calibration.height / 2.0]]])
    metres = float(np.linalg.norm(np.diff(calibration.to_arena(centre)[0], axis=0)))
    tag_px = config.tag_size * 10.0 / max(metres, 1e-12)
    return 1.0 / max(1, math.floor(tag_px / config.detection_tag_px))


def side_lengths(corners: FloatArray) -> FloatArray:
    """Mean side length (M,) of quadrilaterals (M, 4, 2)."""
    c = np.asarray(corners, dtype=float).reshape(-1, 4, 2)
    return np.linalg.norm(c - np.roll(c, -1, axis=1), axis=2).mean(axis=1)


class TagTracker:
    """Frames in, poses out: detection, plane homography, identity, plausibility checks."""

    def __init__(self, config: TrackerConfig, calibration: Calibration) -> None:
        self.config = config
        self.calibration = calibration
        self.detector = TagDetector(config)
        self.scale = detection_scale(config, calibration)

    def check_frame(self, image: NDArray[Any]) -> NDArray[np.uint8]:
        """Return ``image`` as grey uint8 or raise TrackerInputError (shape, dtype, size vs calibration)."""
        import cv2

        if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.ndim not in (2, 3):
            raise TrackerInputError('a frame must be a uint8 array (H, W) or (H, W, 3)')
        if image.ndim == 3:
            if image.shape[2] != 3:
                raise TrackerInputError(f'a colour frame must have 3 channels (BGR), got {image.shape[2]}')
            image = np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), dtype=np.uint8)
        h, w = image.shape
        cal = self.calibration
        if (w, h) != (cal.width, cal.height):
            raise FrameSizeError(f'frame is {w}x{h} px but the calibration is for {cal.width}x{cal.height}; '
                                    'recalibrate for this resolution (smarticle-tracker-calibrate)')
        return image

    def to_arena(self, pixel_corners: FloatArray, camera_matrix: FloatArray | None = None,
                 dist_coeffs: FloatArray | None = None) -> FloatArray:
        """Map pixel corners (M, 4, 2) to arena metres, undistorting first when distortion is given."""
        return self.calibration.to_arena(pixel_corners, camera_matrix, dist_coeffs)

    def track(self, image: NDArray[Any], camera_matrix: FloatArray | None = None,
              dist_coeffs: FloatArray | None = None) -> TrackResult:
        """Poses of every robot in one frame (TrackerInputError for a frame that cannot be used)."""
        grey = self.check_frame(image)
        found = self.detector.detect(grey, self.scale)
        if self.scale < 1.0 and not set(self.config.tag_ids) <= set(found.ids.tolist()):
            found = self.detector.detect(grey, 1.0)    # a robot is missing: search the full-size frame
        return self.poses_from_detections(found, camera_matrix, dist_coeffs)

    def poses_from_detections(self, found: Detections, camera_matrix: FloatArray | None = None,
                              dist_coeffs: FloatArray | None = None) -> TrackResult:
        """Turn detections into per-robot poses, rejecting unknown, duplicate and implausible tags."""
        cfg = self.config
        n = cfg.n_robots
        poses = np.full((n, 3), np.nan)
        seen = np.zeros(n, dtype=bool)
        problems: list[tuple[str, str]] = []
        counts: dict[str, int] = {}

        def report(counter: str, text: str) -> None:
            counts[counter] = counts.get(counter, 0) + 1
            problems.append((counter, text))

        if len(found.ids) == 0:
            report('frames_without_tags', 'no tags in the frame')
            return TrackResult(poses, seen, tuple(problems), counts)
        arena = self.to_arena(found.corners, camera_matrix, dist_coeffs)
        sides = side_lengths(arena)
        unique, occurrences = np.unique(found.ids, return_counts=True)
        duplicated = set(unique[occurrences > 1].tolist())
        estimates = poses_from_corners(arena)
        for m, tag in enumerate(found.ids.tolist()):
            robot = cfg.robot_of_tag.get(tag)
            if robot is None:
                report('unknown_tags', f'tag id {tag} belongs to no robot (tag_ids = {list(cfg.tag_ids)})')
                continue
            if tag in duplicated:
                if m == int(np.flatnonzero(found.ids == tag)[0]):
                    report('duplicate_tags', f'tag id {tag} seen {int(np.sum(found.ids == tag))} times: '
                           f'robot {robot} left out of this frame')
                continue
            if not abs(sides[m] / cfg.tag_size - 1.0) <= cfg.size_tolerance or not np.all(np.isfinite(estimates[m])):
                report('implausible_tags', f'tag id {tag}: side {sides[m] * 1000:.1f} mm, expected '
                       f'{cfg.tag_size * 1000:.1f} mm (wrong calibration or tag_size?)')
                continue
            poses[robot] = estimates[m]
            seen[robot] = True
        return TrackResult(poses, seen, tuple(problems), counts)
