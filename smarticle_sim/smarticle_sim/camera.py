"""Simulated overhead camera: a top-down image of the robots with their ArUco tags, plus camera_info.

The camera is a pinhole (no lens distortion) ``elevation`` metres above the plate centre, looking straight
down, optionally tilted about its x axis and turned about the vertical. Image x runs along arena +x and
image y (down) along arena -y when untilted and unturned. Each robot carries one ArUco tag centred on
the top face of its body (z = body height), the tag's top edge toward the body normal (the heading)
and its left-to-right edge along the body x axis (joint 1 to joint 2); see docs/tracking.md.

Two rendering paths give the same picture of the same geometry:

* ``opencv`` (default, the faster one, see docs/tracking.md): the known geometry is drawn directly:
  anti-aliased ``fillPoly`` of the arms and the white body top, then each tag's bitmap warped onto its
  body top inside a small region of interest.
* ``pybullet``: ``getCameraImage`` (TINY renderer) of ``Physics.client`` with the same intrinsics and pose,
  then the same tag warp (PyBullet's boxes carry no tag texture).

Noise, blur and uneven lighting are optional and seeded. No rclpy here; the sim bridge node publishes
the frames as sensor_msgs/Image (mono8) with ``camera_info``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from smarticle_common.facts import SMALL, TAG_DICTIONARY, TAG_SIZE, RobotSpec
from smarticle_common.poses import tag_corners

from .errors import ConfigError

BACKENDS = ('opencv', 'pybullet')
_SHIFT = 4                       # fixed-point bits of fillPoly's sub-pixel coordinates
_PLATE_GREY, _OUTSIDE_GREY, _ARM_GREY, _BODY_GREY = 110, 40, 70, 235


def aruco_dictionary(name: str) -> Any:
    """The predefined OpenCV ArUco dictionary called ``name`` (e.g. 'DICT_4X4_50'); ConfigError if unknown."""
    import cv2

    ident = getattr(cv2.aruco, name, None) if name.startswith('DICT_') else None
    if not isinstance(ident, int):
        raise ConfigError(f'unknown ArUco dictionary {name!r}; use one of cv2.aruco.DICT_*, e.g. DICT_4X4_50')
    return cv2.aruco.getPredefinedDictionary(ident)


@dataclass(frozen=True)
class CameraConfig:
    """The simulated overhead camera: image size, optics, tags and image faults (SI units, radians)."""

    width: int = 1920
    height: int = 1080
    view: float = 0.6               # m of the plate plane seen across the shorter image side
    elevation: float = 1.5          # m, camera centre above the plate
    tilt: float = 0.0               # rad, rotation about the camera x axis
    yaw: float = 0.0                # rad, rotation about the vertical
    tag_size: float = TAG_SIZE      # m, outer black square of the tag
    dictionary: str = TAG_DICTIONARY
    tag_ids: tuple[int, ...] | None = None   # tag id of robot k (None: k)
    noise: float = 0.0              # standard deviation of Gaussian pixel noise (grey levels)
    blur: float = 0.0               # sigma of a Gaussian blur (px)
    lighting: float = 0.0           # brightness falls by this fraction from the image centre to a corner
    seed: int = 0
    backend: str = 'opencv'
    plate_size: float = 0.6         # m, the square plate drawn as background
    robot: RobotSpec = field(default=SMALL)

    def __post_init__(self) -> None:
        for name in ('width', 'height'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 16 <= value <= 8192:
                raise ConfigError(f'CameraConfig.{name} must be a whole number of pixels in 16..8192, '
                                  f'got {value!r}')
        for name in ('view', 'elevation', 'tag_size', 'plate_size'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise ConfigError(f'CameraConfig.{name} must be a positive length in metres, got {value!r}')
        if self.elevation <= self.robot.body_height * 2:
            raise ConfigError(f'CameraConfig.elevation {self.elevation} m is too low above robots '
                              f'{self.robot.body_height} m tall')
        if self.tag_size > min(self.robot.body_width, self.robot.body_depth):
            raise ConfigError(f'CameraConfig.tag_size {self.tag_size} m does not fit on the body top '
                              f'({self.robot.body_width} x {self.robot.body_depth} m)')
        for name, top in (('noise', 255.0), ('blur', 50.0), ('lighting', 0.95)):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 <= value <= top):
                raise ConfigError(f'CameraConfig.{name} must be in [0, {top}], got {value!r}')
        if not abs(self.tilt) < math.radians(60.0):
            raise ConfigError(f'CameraConfig.tilt must be within +-60 deg, got {math.degrees(self.tilt)} deg')
        if self.backend not in BACKENDS:
            raise ConfigError(f'CameraConfig.backend must be one of {", ".join(BACKENDS)}, got {self.backend!r}')
        aruco_dictionary(self.dictionary)

    @property
    def focal(self) -> float:
        """Focal length (px): the shorter image side covers ``view`` metres of the plate."""
        return min(self.width, self.height) * self.elevation / self.view

    @property
    def tag_z(self) -> float:
        """Height of the tag plane (the body top) above the plate (m)."""
        return self.robot.body_height

    def tag_id(self, robot: int) -> int:
        """Tag id carried by robot ``robot``."""
        return robot if self.tag_ids is None else self.tag_ids[robot]


class CameraInfo(NamedTuple):
    """Intrinsics as sensor_msgs/CameraInfo holds them (row-major lists, plumb_bob model)."""

    width: int
    height: int
    k: list[float]
    d: list[float]
    r: list[float]
    p: list[float]
    distortion_model: str


class OverheadCamera:
    """Renders frames of one CameraConfig; holds the precomputed background, lighting and tag bitmaps."""

    def __init__(self, config: CameraConfig) -> None:
        import cv2

        self.config = config
        c = config
        self.camera_matrix = np.array([[c.focal, 0.0, (c.width - 1) / 2.0],
                                       [0.0, c.focal, (c.height - 1) / 2.0], [0.0, 0.0, 1.0]])
        # camera axes in the arena frame: x along arena x, y along -y, z down, then yaw and tilt
        cy, sy = math.cos(c.yaw), math.sin(c.yaw)
        ct, st = math.cos(c.tilt), math.sin(c.tilt)
        base = np.array([[cy, sy, 0.0], [sy, -cy, 0.0], [0.0, 0.0, -1.0]]).T   # columns: camera axes
        tilt = np.array([[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]])
        self.rotation = base @ tilt                   # camera-to-arena rotation
        self.centre = np.array([0.0, 0.0, c.elevation])
        self._dictionary = aruco_dictionary(c.dictionary)
        self._bitmaps: dict[int, np.ndarray] = {}
        self._rng = np.random.default_rng(c.seed)
        self._background = self._draw_background()
        self._shade: np.ndarray | None = None
        if c.lighting > 0.0:
            ys, xs = np.mgrid[0:c.height, 0:c.width].astype(np.float32)
            rho = np.hypot(xs - (c.width - 1) / 2.0, ys - (c.height - 1) / 2.0)
            self._shade = (1.0 - c.lighting * (rho / rho.max()) ** 2).astype(np.float32)
        self._cv2 = cv2

    # ----------------------------------------------------------------- geometry
    def project(self, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates (M, 2) of arena points (M, 3)."""
        cam = (np.asarray(points, dtype=float) - self.centre) @ self.rotation
        uv = cam[:, :2] / cam[:, 2:3]
        return uv @ self.camera_matrix[:2, :2].T + self.camera_matrix[:2, 2]

    def plane_homography(self, z: float | None = None) -> np.ndarray:
        """3x3 homography from arena (x, y) on the plane at height ``z`` (default: the tags) to pixels."""
        z = self.config.tag_z if z is None else z
        src = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
        dst = self.project(np.column_stack([src, np.full(4, z)]))
        import cv2

        return cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32)).astype(float)

    def camera_info(self) -> CameraInfo:
        """Intrinsics of the rendered frames (no distortion)."""
        k = self.camera_matrix
        p = np.hstack([k, np.zeros((3, 1))])
        return CameraInfo(self.config.width, self.config.height, [float(v) for v in k.ravel()],
                          [0.0] * 5, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                          [float(v) for v in p.ravel()], 'plumb_bob')

    def tag_corners(self, poses: np.ndarray) -> np.ndarray:
        """Arena corners (N, 4, 2) of the robots' tags of this camera's tag size (``poses.tag_corners``)."""
        return tag_corners(poses, self.config.tag_size)

    # ----------------------------------------------------------------- drawing
    def _draw_background(self) -> np.ndarray:
        """The empty plate, drawn once."""
        import cv2

        c = self.config
        image = np.full((c.height, c.width), _OUTSIDE_GREY, dtype=np.uint8)
        half = c.plate_size / 2.0
        corners = np.array([[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]])
        cv2.fillPoly(image, [self._fixed(self.project(corners))], _PLATE_GREY, cv2.LINE_AA, _SHIFT)
        return image

    @staticmethod
    def _fixed(uv: np.ndarray) -> np.ndarray:
        """Pixel coordinates as fillPoly's fixed-point int32 points."""
        return np.round(uv * (1 << _SHIFT)).astype(np.int32)

    def _bitmap(self, tag_id: int) -> np.ndarray:
        """The tag's image (black border + bits), cached per id."""
        if tag_id not in self._bitmaps:
            cells = self._dictionary.markerSize + 2
            self._bitmaps[tag_id] = self._cv2.aruco.generateImageMarker(self._dictionary, tag_id, cells * 8,
                                                                        borderBits=1)
        return self._bitmaps[tag_id]

    def _robot_polygons(self, poses: np.ndarray, arm_angles: np.ndarray | None) -> list[tuple[np.ndarray, int]]:
        """(fixed-point polygon, grey) of every arm, then every body top (bodies stand higher than arms)."""
        spec = self.config.robot
        out: list[tuple[np.ndarray, int]] = []
        bodies: list[tuple[np.ndarray, int]] = []
        arm_top = spec.arm_clearance + spec.arm_height
        for k, (x, y, heading) in enumerate(poses):
            yaw = heading - math.pi / 2.0
            ex = np.array([math.cos(yaw), math.sin(yaw)])
            ey = np.array([-ex[1], ex[0]])
            hw, hd = spec.body_width / 2.0, spec.body_depth / 2.0
            if arm_angles is not None:
                for sign, alpha in ((-1.0, arm_angles[k, 0]), (1.0, arm_angles[k, 1])):
                    d = yaw + math.pi - alpha if sign < 0 else yaw + alpha
                    u = np.array([math.cos(d), math.sin(d)])
                    v = np.array([-u[1], u[0]]) * spec.arm_thickness / 2.0
                    joint = np.array([x, y]) + sign * hw * ex
                    tip = joint + spec.arm_length * u
                    quad = np.array([joint + v, tip + v, tip - v, joint - v])
                    out.append((self._fixed(self.project(np.column_stack([quad, np.full(4, arm_top)]))),
                                _ARM_GREY))
            centre = np.array([x, y])
            top = np.array([centre + hw * ex + hd * ey, centre - hw * ex + hd * ey,
                            centre - hw * ex - hd * ey, centre + hw * ex - hd * ey])
            bodies.append((self._fixed(self.project(np.column_stack([top, np.full(4, spec.body_height)]))),
                           _BODY_GREY))
        return out + bodies

    def _warp_tags(self, image: np.ndarray, poses: np.ndarray, robots: np.ndarray) -> None:
        """Warp the tag bitmap of each robot ``robots[i]`` at ``poses[i]`` onto its body top (in a small ROI)."""
        cv2 = self._cv2
        corners = self.tag_corners(poses)
        z = self.config.tag_z
        height, width = image.shape[:2]
        for k in range(len(poses)):
            bitmap = self._bitmap(self.config.tag_id(int(robots[k])))
            side = bitmap.shape[0]
            uv = self.project(np.column_stack([corners[k], np.full(4, z)]))
            x0, y0 = np.floor(uv.min(axis=0)).astype(int) - 1
            x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 2
            x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, width), min(y1, height)
            if x1 <= x0 or y1 <= y0:
                continue
            # bitmap pixel centres sit at 0..side-1; the tag's outer edges at -0.5 and side-0.5
            src = np.array([[-0.5, -0.5], [side - 0.5, -0.5], [side - 0.5, side - 0.5], [-0.5, side - 0.5]],
                           dtype=np.float32)
            dst = (uv - [x0, y0]).astype(np.float32)
            h = cv2.getPerspectiveTransform(src, dst)
            patch = image[y0:y1, x0:x1].copy()
            flags = cv2.INTER_AREA if side > 4 * (x1 - x0) else cv2.INTER_LINEAR
            patch = cv2.warpPerspective(bitmap, h, (x1 - x0, y1 - y0), dst=patch, flags=flags,
                                        borderMode=cv2.BORDER_TRANSPARENT)
            image[y0:y1, x0:x1] = patch

    def _finish(self, image: np.ndarray) -> np.ndarray:
        """Apply lighting, blur and noise."""
        cv2 = self._cv2
        c = self.config
        if self._shade is not None:
            image = cv2.multiply(image, self._shade, dtype=cv2.CV_8U)
        if c.blur > 0.0:
            image = cv2.GaussianBlur(image, (0, 0), c.blur)
        if c.noise > 0.0:
            noise = np.empty(image.shape, dtype=np.int16)
            cv2.setRNGSeed(int(self._rng.integers(2**31 - 1)))
            cv2.randn(noise, 0.0, c.noise)
            image = cv2.add(image, noise, dtype=cv2.CV_8U)
        return image

    def render(self, poses: np.ndarray, arm_angles: np.ndarray | None = None, physics: Any = None) -> np.ndarray:
        """A mono8 frame (height, width) of robots at ``poses`` (N, 3) with ``arm_angles`` (N, 2) or no arms.

        The ``pybullet`` backend renders ``physics`` (a Physics whose robots are at these poses) instead of
        drawing the bodies and arms; the tags are warped on in both paths. Robots with a non-finite pose
        are not drawn.
        """
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        drawn = np.all(np.isfinite(poses), axis=1)
        if self.config.backend == 'pybullet':
            if physics is None:
                raise ConfigError('the pybullet camera backend renders a Physics: pass physics=')
            image = self._render_pybullet(physics)
        else:
            image = self._background.copy()
            arms = None if arm_angles is None else np.asarray(arm_angles, dtype=float)[drawn]
            for polygon, grey in self._robot_polygons(poses[drawn], arms):
                self._cv2.fillPoly(image, [polygon], grey, self._cv2.LINE_AA, _SHIFT)
        self._warp_tags(image, poses[drawn], np.flatnonzero(drawn))
        return self._finish(image)

    def _render_pybullet(self, physics: Any) -> np.ndarray:
        """getCameraImage of the physics' client with this camera's intrinsics and pose (TINY renderer)."""
        import pybullet

        c = self.config
        near, far = 0.1, c.elevation + 1.0
        target = self.centre + self.rotation[:, 2]
        up = -self.rotation[:, 1]
        view = physics.client.computeViewMatrix(self.centre.tolist(), target.tolist(), up.tolist())
        fx, fy = self.camera_matrix[0, 0], self.camera_matrix[1, 1]
        cx, cy = self.camera_matrix[0, 2], self.camera_matrix[1, 2]
        w, h = c.width, c.height
        # OpenGL projection (column-major) matching the pinhole K
        proj = [2 * fx / w, 0.0, 0.0, 0.0,
                0.0, 2 * fy / h, 0.0, 0.0,
                1.0 - 2 * (cx + 0.5) / w, 2 * (cy + 0.5) / h - 1.0, -(far + near) / (far - near), -1.0,
                0.0, 0.0, -2.0 * far * near / (far - near), 0.0]
        _, _, rgba, _, _ = physics.client.getCameraImage(w, h, view, proj, renderer=pybullet.ER_TINY_RENDERER,
                                                       flags=pybullet.ER_NO_SEGMENTATION_MASK)
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(h, w, 4)[:, :, :3]
        return self._cv2.cvtColor(rgb, self._cv2.COLOR_RGB2GRAY)

