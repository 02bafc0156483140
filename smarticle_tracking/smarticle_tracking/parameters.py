"""Parameters of the tracking nodes, declared once (ParamSpec tables) and read into frozen configs.

``TRACKER_PARAMS`` (node ``tracker``) and ``MONITOR_PARAMS`` (node ``glider_monitor``) are shipped as
``config/tracker.yaml`` and ``config/glider_monitor.yaml`` (``python -m smarticle_tracking.parameters``
rewrites them; a test keeps them equal). No rclpy here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from smarticle_common.params import ParamSpec, defaults_yaml

from .errors import TrackingError
from .homography import Calibration, load_calibration
from .gliders import DEFAULT_ISOLATION_DISTANCE, DEFAULT_R_BIND, MIN_PERIODS, TRAVEL_MIN_W_PER_100, GliderConfig
from .markers import RobotDims
from smarticle_common.pairs import BODY_LENGTH
from .tracker import TrackerConfig
from smarticle_common.facts import GAIT_PERIOD, PRESETS, SMALL, TAG_DICTIONARY, TAG_SIZE

TRACKER_NODE = 'tracker'
MONITOR_NODE = 'glider_monitor'
CONFIG_DIR = Path(__file__).resolve().parents[1] / 'config'
#: The calibration of the sim camera at its default settings (made by ``smarticle-sim-camera-calibrate``).
SIM_CALIBRATION = CONFIG_DIR / 'sim_overhead_calibration.yaml'

TRACKER_PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('calibration_file', '', 'plane-homography YAML from smarticle-tracker-calibrate; empty = the shipped '
              'calibration of the sim camera at its defaults (config/sim_overhead_calibration.yaml)'),
    ParamSpec('dictionary', TAG_DICTIONARY, 'OpenCV ArUco dictionary of the tags'),
    ParamSpec('tag_ids', [0, 1, 2, 3, 4, 5, 6], 'tag id of each robot (integer list): the k-th id is robot k'),
    ParamSpec('tag_size', TAG_SIZE, 'side of the tag (outer black square) in metres', 0.001, 1.0),
    ParamSpec('size_tolerance', 0.25, 'reject a tag whose mapped side differs from tag_size by more than '
              'this fraction', 0.01, 0.99),
    ParamSpec('threshold_window', 13, 'adaptive-threshold window in pixels (odd; 0 = OpenCV sweep, slower)',
              0, 255),
    ParamSpec('detection_tag_px', 16.0, 'search a frame shrunk by a whole factor while tags still span '
              'this many pixels, then refine corners at full size; full size again if a robot is missing '
              '(0 = always full size)', 0.0, 1000.0),
    ParamSpec('refine', True, 'sub-pixel corner refinement on the full-size frame'),
    ParamSpec('image_reliable', True, 'subscribe to the frames with reliable QoS (large frames survive; the sim '
              'publishes reliable); false = best effort, for camera drivers that publish best effort'),
    ParamSpec('preset', SMALL.name, 'robot preset of /smarticle_<k>/robot_description and TF: '
              f'{", ".join(sorted(PRESETS))}'),
)

MONITOR_PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('period', GAIT_PERIOD, 'gait period T (s)', 0.01, 3600.0),
    ParamSpec('r_bind', DEFAULT_R_BIND, 'a pair is bound in a period if its centre distance falls below '
              'this (m) in any frame of it (the one bound rule, docs/gliders.md)', 1e-4, 10.0),
    ParamSpec('min_periods', MIN_PERIODS, 'K: bound periods in a row that make a bound pair', 1, 100000),
    ParamSpec('travel_min_w_per_100', TRAVEL_MIN_W_PER_100, 'a bound pair is a glider if its centre of mass '
              'travels (net) at least this many W per 100 periods of its run', 0.0, 1000.0),
    ParamSpec('isolation_distance', DEFAULT_ISOLATION_DISTANCE, 'a bound period is crowded if a third robot '
              'comes within this of either robot of the pair (m)', 1e-4, 10.0),
    ParamSpec('isolated_fraction', 0.9, 'a bound pair is isolated (a pair, not a cluster) if at least this '
              'fraction of its periods is not crowded', 0.0, 1.0),
    ParamSpec('class_tolerance_deg', 45.0, 'C1 if the mean phi is within this of 180 deg, C2 of 0 deg',
              0.1, 90.0),
    ParamSpec('body_length', BODY_LENGTH, 'BL = W (m): the unit of r_bl and travel_w in the reports', 1e-4, 10.0),
    ParamSpec('start_at', -1.0, "start of period 0 (s, message time): the gait nodes' start_at (the shared "
              'stack.yaml gives both); negative = the first frame', -1.0, 1e9),
    ParamSpec('history', 100, 'finished bound pairs kept', 1, 100000),
    ParamSpec('publish_period', 0.1, 'message-time seconds between reports (0 = every frame)', 0.0, 3600.0),
    ParamSpec('show_arms', True, 'subscribe to /smarticle_<k>/joint_states and draw the arms'),
    ParamSpec('body_width', SMALL.body_width, 'marker geometry: body width along the joint axis (m)', 1e-4, 1.0),
    ParamSpec('body_depth', 0.022, 'marker geometry: body depth along the normal (m)', 1e-4, 1.0),
    ParamSpec('arm_length', 0.05, 'marker geometry: arm length (m)', 1e-4, 1.0),
    ParamSpec('arm_thickness', 0.003, 'marker geometry: arm thickness (m)', 1e-5, 1.0),
)


class SettingsError(TrackingError):
    """Parameter values that do not make a valid configuration."""


def parse_tag_ids(value: Any) -> tuple[int, ...]:
    """Tag ids from an integer list (or a space/comma-separated string); SettingsError on anything else."""
    items = value.replace(',', ' ').split() if isinstance(value, str) else list(value)
    try:
        ids = tuple(int(item) for item in items if not isinstance(item, (bool, float)))
    except (TypeError, ValueError):
        ids = ()
    if not ids or len(ids) != len(items):
        raise SettingsError(f'{TRACKER_NODE}.tag_ids must be a non-empty list of whole tag ids, got {value!r}')
    return ids


def tracker_config(values: dict[str, Any]) -> TrackerConfig:
    """TrackerConfig from checked TRACKER_PARAMS values (ValueError names the problem)."""
    return TrackerConfig(tag_ids=parse_tag_ids(values['tag_ids']), dictionary=values['dictionary'],
                         tag_size=values['tag_size'], size_tolerance=values['size_tolerance'],
                         threshold_window=values['threshold_window'],
                         detection_tag_px=values['detection_tag_px'], refine=values['refine'])


def tracker_calibration(values: dict[str, Any]) -> Calibration:
    """Load the calibration named by the parameters (CameraCalibrationError if missing or malformed)."""
    return load_calibration(values['calibration_file'] or SIM_CALIBRATION)


@dataclass(frozen=True)
class MonitorSettings:
    """Checked glider-monitor settings."""

    glider: GliderConfig
    t0: float | None
    history: int
    publish_period: float
    show_arms: bool
    dims: RobotDims


def monitor_settings(values: dict[str, Any]) -> MonitorSettings:
    """MonitorSettings from checked MONITOR_PARAMS values (GliderConfigError names the problem)."""
    glider = GliderConfig(period=values['period'], r_bind=values['r_bind'], min_periods=values['min_periods'],
                          isolation_distance=values['isolation_distance'],
                          isolated_fraction=values['isolated_fraction'],
                          travel_min_w_per_100=values['travel_min_w_per_100'],
                          class_tolerance=math.radians(values['class_tolerance_deg']),
                          body_length=values['body_length'], width=values['body_length'])
    dims = RobotDims(values['body_width'], values['body_depth'], values['arm_length'], values['arm_thickness'])
    return MonitorSettings(glider, None if values['start_at'] < 0.0 else values['start_at'], values['history'],
                           values['publish_period'], values['show_arms'], dims)


def defaults(specs: tuple[ParamSpec, ...]) -> dict[str, Any]:
    """The default values of a parameter table."""
    return {spec.name: spec.default for spec in specs}


def write_default_files(folder: Path = CONFIG_DIR) -> list[Path]:
    """Write config/tracker.yaml and config/glider_monitor.yaml from the tables; return the paths."""
    out = []
    for node, specs in ((TRACKER_NODE, TRACKER_PARAMS), (MONITOR_NODE, MONITOR_PARAMS)):
        path = folder / f'{node}.yaml'
        path.write_text(f'# Defaults of the {node} node (smarticle_tracking/settings.py); a test keeps them equal.\n'
                        + defaults_yaml(node, specs), encoding='utf-8')
        out.append(path)
    return out


if __name__ == '__main__':
    for written in write_default_files():
        print(written)
