"""The overhead tracker core on frames of the sim camera: accuracy, calibration round trip, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from smarticle_sim.bridge import BridgeSettings, SimBridgeCore
from smarticle_sim.camera import CameraConfig, OverheadCamera
from smarticle_tracking.homography import (Calibration, board_targets, calibrate, load_calibration,
                                            save_calibration)
from smarticle_tracking.homography_cli import main as calibrate_main
from smarticle_bringup.sim_camera import sim_calibration
from smarticle_tracking.errors import CameraCalibrationError, TrackerConfigError, TrackerInputError
from smarticle_tracking.parameters import SIM_CALIBRATION
from smarticle_common.poses import poses_from_corners, tag_corners
from smarticle_tracking.tracker import TagDetector, TagTracker, TrackerConfig, image_from_buffer


def heading_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Unsigned angle differences (rad)."""
    return np.abs((a - b + math.pi) % (2 * math.pi) - math.pi)


@pytest.fixture(scope='module')
def scenes() -> list[tuple[np.ndarray, np.ndarray]]:
    """Ground truth (poses, arm angles) of sim scenes: the dense 7-robot start and two random scenes."""
    out = []
    for kind, seed in (('dense', 1), ('random', 2), ('random', 5)):
        core = SimBridgeCore(BridgeSettings.defaults(scene=kind, seed=seed, robots=7))
        try:
            core.advance()
            state = core.physics.state()
            out.append((state.poses.copy(), state.arm_angles.copy()))
        finally:
            core.close()
    return out


def test_tag_layout_agrees_between_camera_and_tracker() -> None:
    poses = np.array([[0.01, -0.02, 0.3], [0.1, 0.05, -2.0]])
    camera = OverheadCamera(CameraConfig())
    assert np.allclose(camera.tag_corners(poses), tag_corners(poses, 0.018))
    assert np.allclose(poses_from_corners(tag_corners(poses, 0.018)), poses)


def test_tracker_matches_sim_ground_truth_on_clean_1080p_frames(scenes) -> None:  # type: ignore[no-untyped-def]
    camera = OverheadCamera(CameraConfig())
    tracker = TagTracker(TrackerConfig(), load_calibration(SIM_CALIBRATION))
    errors, headings, seen = [], [], 0
    for poses, arms in scenes:
        result = tracker.track(camera.render(poses, arms))
        seen += int(result.seen.sum())
        errors += list(np.hypot(*(result.poses[result.seen, :2] - poses[result.seen, :2]).T))
        headings += list(heading_error(result.poses[result.seen, 2], poses[result.seen, 2]))
    assert seen == 7 * len(scenes)
    assert np.median(errors) < 0.5e-3 and np.max(errors) < 1.5e-3
    assert np.degrees(np.median(headings)) < 1.0 and np.degrees(np.max(headings)) < 3.0


def test_tracker_survives_noise_blur_and_uneven_light_at_vga(scenes) -> None:  # type: ignore[no-untyped-def]
    config = CameraConfig(width=640, height=480, noise=4.0, blur=0.7, lighting=0.4, seed=3)
    camera = OverheadCamera(config)
    tracker = TagTracker(TrackerConfig(), sim_calibration(640, 480))
    poses, arms = scenes[0]
    result = tracker.track(camera.render(poses, arms))
    assert result.seen.sum() >= 6
    err = np.hypot(*(result.poses[result.seen, :2] - poses[result.seen, :2]).T)
    assert np.median(err) < 2e-3


def test_missing_robot_gets_nan_never_a_stale_pose(scenes) -> None:  # type: ignore[no-untyped-def]
    camera = OverheadCamera(CameraConfig())
    tracker = TagTracker(TrackerConfig(), load_calibration(SIM_CALIBRATION))
    poses, arms = scenes[0]
    assert tracker.track(camera.render(poses, arms)).seen.all()
    hidden = poses.copy()
    hidden[3] = np.nan                     # robot 3 is not drawn
    result = tracker.track(camera.render(hidden, arms))
    assert not result.seen[3] and np.all(np.isnan(result.poses[3]))
    assert result.seen.sum() == 6


def test_homography_calibration_round_trip(tmp_path: Path) -> None:
    config = CameraConfig(width=1280, height=960, tilt=math.radians(2.0), yaw=math.radians(20.0))
    targets = board_targets(3, 4, 0.1, first_id=20)
    ids = sorted(targets)
    board = OverheadCamera(CameraConfig(width=1280, height=960, tilt=config.tilt, yaw=config.yaw,
                                        tag_ids=tuple(ids)))
    frame = board.render(np.array([targets[i] for i in ids]))
    found = TagDetector(TrackerConfig(tag_ids=tuple(ids))).detect(frame)
    calibration = calibrate(found.corners, found.ids, targets, 0.018, 1280, 960, source='test')
    assert calibration.tags_used == 12 and calibration.rms_error < 0.3e-3
    # the fitted map inverts the camera's own plane projection (arena -> pixels) at the tags' height
    truth = np.linalg.inv(board.plane_homography())
    pixels = np.array([[100.0, 100.0], [640.0, 480.0], [1200.0, 900.0]])
    ideal = (truth @ np.column_stack([pixels, np.ones(3)]).T).T
    assert np.allclose(calibration.to_arena(pixels), ideal[:, :2] / ideal[:, 2:], atol=0.5e-3)
    path = save_calibration(tmp_path / 'cal' / 'overhead.yaml', calibration)
    loaded = load_calibration(path)
    assert np.allclose(loaded.homography, calibration.homography) and (loaded.width, loaded.height) == (1280, 960)
    assert loaded.tags_used == 12 and loaded.source == 'test'


def test_calibrate_command_writes_a_file_that_tracks(tmp_path: Path) -> None:
    import cv2

    targets = board_targets(2, 3, 0.15, first_id=30)
    ids = sorted(targets)
    camera = OverheadCamera(CameraConfig(width=800, height=600, tag_ids=tuple(ids)))
    image = tmp_path / 'board.png'
    cv2.imwrite(str(image), camera.render(np.array([targets[i] for i in ids])))
    out = tmp_path / 'cal.yaml'
    assert calibrate_main(['--image', str(image), '--board', '2x3', '--spacing', '0.15', '--first-id', '30',
                           '--out', str(out)]) == 0
    assert load_calibration(out).tags_used == 6
    assert calibrate_main(['--image', str(tmp_path / 'none.png'), '--board', '2x3', '--out', str(out)]) == 2


def test_calibration_needs_two_known_tags() -> None:
    corners = tag_corners(np.array([[0.0, 0.0, 1.0]]), 0.018) * 1000 + 500
    with pytest.raises(CameraCalibrationError, match='need at least 2'):
        calibrate(corners, np.array([10]), {10: (0.0, 0.0, 1.0), 11: (0.1, 0.0, 1.0)}, 0.018, 1000, 1000)


@pytest.mark.parametrize('text, match', [
    (None, 'does not exist'),
    ('foo: [1, 2', 'not readable YAML'),
    ('something_else: {}', 'no .overhead_calibration. section'),
    ('overhead_calibration: {width: 640, height: 480}', 'missing or malformed'),
    ('overhead_calibration: {width: 640, height: 480, homography: [[1, 0], [0, 1]]}', 'invertible 3x3'),
])
def test_bad_calibration_files_say_what_is_wrong(tmp_path: Path, text: str | None, match: str) -> None:
    path = tmp_path / 'cal.yaml'
    if text is not None:
        path.write_text(text)
    with pytest.raises(CameraCalibrationError, match=match):
        load_calibration(path)


def test_frame_problems_are_reported_not_raised(scenes) -> None:  # type: ignore[no-untyped-def]
    poses, arms = scenes[0]
    config = TrackerConfig(tag_ids=(0, 1, 2, 3, 4, 5))
    tracker = TagTracker(config, load_calibration(SIM_CALIBRATION))
    empty = tracker.track(OverheadCamera(CameraConfig()).render(np.full((2, 3), np.nan)))
    assert not empty.seen.any() and empty.counts == {'frames_without_tags': 1}
    twins = OverheadCamera(CameraConfig(tag_ids=(0, 1, 2, 3, 4, 9, 1)))    # tag 9 is nobody's; 1 twice
    result = tracker.track(twins.render(poses, arms))
    assert result.counts == {'unknown_tags': 1, 'duplicate_tags': 1}
    assert result.seen.tolist() == [True, False, True, True, True, False]
    assert ('duplicate_tags', 'tag id 1 seen 2 times: robot 1 left out of this frame') in result.problems
    wrong_size = TagTracker(TrackerConfig(tag_size=0.03), load_calibration(SIM_CALIBRATION))
    rejected = wrong_size.track(OverheadCamera(CameraConfig()).render(poses, arms))
    assert not rejected.seen.any() and rejected.counts['implausible_tags'] == 7


def test_unusable_frames_raise_clear_errors() -> None:
    tracker = TagTracker(TrackerConfig(), load_calibration(SIM_CALIBRATION))
    with pytest.raises(TrackerInputError, match='calibration is for 1920x1080'):
        tracker.track(np.zeros((480, 640), dtype=np.uint8))
    with pytest.raises(TrackerInputError, match='uint8'):
        tracker.track(np.zeros((1080, 1920), dtype=np.float32))
    with pytest.raises(TrackerInputError, match="unsupported image encoding '16UC1'"):
        image_from_buffer('16UC1', 4, 4, 8, bytes(32))
    with pytest.raises(TrackerInputError, match='needs 48'):
        image_from_buffer('bgr8', 4, 4, 12, bytes(20))
    rgb = np.zeros((4, 5, 3), dtype=np.uint8)
    rgb[..., 0] = 255                                             # pure red in rgb8
    grey = image_from_buffer('rgb8', 4, 5, 15, rgb.tobytes())
    assert grey.shape == (4, 5) and 70 < grey[0, 0] < 80          # 0.299 * 255


@pytest.mark.parametrize('changes, match', [
    ({'tag_ids': (0, 0)}, 'repeat'), ({'tag_ids': ()}, 'non-empty'), ({'dictionary': 'DICT_9X9'}, 'unknown'),
    ({'tag_ids': (60,)}, 'not in DICT_4X4_50'), ({'threshold_window': 4}, 'odd'), ({'tag_size': 0.0}, 'tag_size'),
])
def test_invalid_tracker_config(changes: dict[str, object], match: str) -> None:
    with pytest.raises(TrackerConfigError, match=match):
        TrackerConfig(**changes)  # type: ignore[arg-type]


def test_calibration_type_checks_its_fields() -> None:
    with pytest.raises(CameraCalibrationError):
        Calibration(np.eye(3), 0, 10)
