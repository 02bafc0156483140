"""`smarticle-bag import`: CSV tracks of other trackers (motion capture, tag trackers) into a bag of poses.

Round trips from known trajectories (metres and radians; pixels, degrees and image rows), read back with our
reader and with ``rosbags``; the glider analysis of an imported bag equals that of the bag it came from;
bad rows, gaps and unsorted times are one line each.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from smarticle_bags import arrays, cli
from smarticle_bags.csv_import import ImportSpec, RobotColumns, encode_pose_array, read_tracks
from smarticle_bags.errors import CsvImportError, OptionError
from smarticle_bags.reader import BagReader
from smarticle_bags.timebase import TimeBase, time_base
from smarticle_common.facts import FEEDBACK, SMALL

from tests.helpers.bags import STORE

ROOT = Path(__file__).resolve().parents[2]


def trajectory(steps: int = 200, robots: int = 3, dt: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and poses (T, N, 3) in m, m, rad: robots circling, headings turning past +-pi (unwrapped)."""
    t = 2.0 + dt * np.arange(steps)
    k = np.arange(robots)
    xyh = np.empty((steps, robots, 3))
    xyh[:, :, 0] = 0.1 * np.cos(t[:, None] + k) + 0.02 * k
    xyh[:, :, 1] = 0.1 * np.sin(t[:, None] + k) - 0.01 * k
    xyh[:, :, 2] = 3.0 * t[:, None] + k           # unwrapped: grows through several turns
    return t, xyh


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run smarticle-bag; return (exit code, stdout, stderr)."""
    with pytest.raises(SystemExit) as done:
        cli.main(argv)
    out, err = capsys.readouterr()
    return int(done.value.code or 0), out, err


def wrap(h: np.ndarray) -> np.ndarray:
    """Angles to [-pi, pi)."""
    return np.mod(h + math.pi, 2.0 * math.pi) - math.pi


def test_motion_capture_in_metres_round_trips(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Metres, radians, unwrapped headings, an extra column: the bag's poses equal the CSV's."""
    t, xyh = trajectory()
    header = ['frame', 'time_s'] + [f'rb{k}_{c}' for k in range(3) for c in ('x', 'y', 'yaw')] + ['marker_err']
    rows = [','.join([str(i), repr(float(t[i]))] + [repr(float(v)) for v in xyh[i].ravel()] + ['0.1'])
            for i in range(len(t))]
    (tmp_path / 'mocap.csv').write_text('\n'.join([','.join(header), *rows]) + '\n')
    code, out, err = run(['import', str(tmp_path / 'mocap.csv'), '-o', str(tmp_path / 'bag'), '--time', 'time_s',
                          '--pattern', 'rb{k}_x,rb{k}_y,rb{k}_yaw'], capsys)
    assert code == 0, err
    assert 'gaps: none' in out and err == ''
    reader = BagReader(tmp_path / 'bag', strict=True)
    poses = arrays.read_poses(reader)
    assert np.allclose(poses.stamp, t, atol=1e-9) and np.allclose(poses.log_time, t, atol=1e-9)
    assert np.allclose(poses.xyh[:, :, :2], xyh[:, :, :2], atol=1e-12)
    assert np.allclose(wrap(poses.xyh[:, :, 2] - xyh[:, :, 2]), 0.0, atol=1e-9)
    assert time_base(reader.info) == (TimeBase.TRACKER, True)
    custom = reader.info.custom_data or {}
    assert custom['imported_from'] == 'CSV mocap.csv' and 'length m: x 1 m' in custom['import_units']
    assert custom['import_columns'].startswith('time: time_s; 0: rb0_x,rb0_y,rb0_yaw')
    # an independent reader decodes the same poses
    with AnyReader([tmp_path / 'bag']) as other:
        (conn,) = other.connections
        msgs: list[Any] = [other.deserialize(raw, conn.msgtype) for _, _, raw in other.messages(connections=[conn])]
    assert len(msgs) == len(t)
    assert msgs[7].poses[2].position.x == pytest.approx(xyh[7, 2, 0], abs=1e-12)
    assert msgs[7].header.frame_id == 'arena'


def test_tag_tracker_pixels_in_degrees_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Pixels (120 px per W of the feedback robot), degrees wrapped to [0, 360), y down, ms, ';' cells."""
    t, xyh = trajectory(robots=2)
    px_per_bl = 120.0
    scale = FEEDBACK.body_length / px_per_bl            # m per pixel
    px = xyh[:, :, 0] / scale
    py = -xyh[:, :, 1] / scale                           # image rows grow downward
    deg = np.mod(np.degrees(-xyh[:, :, 2]), 360.0)       # mirrored too, then wrapped
    lines = ['# exported by a tag tracker', 'id;t_ms;u0;v0;a0;u1;v1;a1']
    lines += [';'.join([str(i), f'{1000 * t[i]:.6f}'] + [f'{v:.9f}' for k in range(2)
                                                          for v in (px[i, k], py[i, k], deg[i, k])])
              for i in range(len(t))]
    (tmp_path / 'tags.csv').write_text('\n'.join(lines) + '\n')
    code, out, err = run(['import', str(tmp_path / 'tags.csv'), '-o', str(tmp_path / 'bag'), '--skip-rows', '1',
                          '--time', 't_ms', '--time-unit', 'ms', '--robot', '0:u0,v0,a0', '--robot', '1:u1,v1,a1',
                          '--px-per-bl', str(px_per_bl), '--robot-preset', 'feedback', '--angle', 'deg',
                          '--y-down'], capsys)
    assert code == 0, err
    assert 'px, 120 px per W (W = 0.065 m, robot feedback)' in out
    poses = arrays.read_poses(BagReader(tmp_path / 'bag'))
    assert np.allclose(poses.stamp, t, atol=1e-8)
    assert np.allclose(poses.xyh[:, :, :2], xyh[:, :, :2], atol=scale * 1e-8)
    assert np.allclose(wrap(poses.xyh[:, :, 2] - xyh[:, :, 2]), 0.0, atol=1e-9)


def test_an_imported_glider_run_gives_the_same_gliders(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The dense sample's poses as a wide CSV in mm and degrees: analyze finds the same bound pairs and gliders."""
    source = ROOT / 'bags' / 'samples' / 'dense7'
    poses = arrays.read_poses(BagReader(source))
    n = poses.xyh.shape[1]
    lines = ['t,' + ','.join(f'x{k},y{k},h{k}' for k in range(n))]
    for s, row in zip(poses.stamp, poses.xyh, strict=True):
        lines.append(repr(float(s)) + ',' + ','.join(f'{1000 * float(x)!r},{1000 * float(y)!r},{math.degrees(h)!r}'
                                                     for x, y, h in row))
    (tmp_path / 'dense.csv').write_text('\n'.join(lines) + '\n')
    code, out, err = run(['import', str(tmp_path / 'dense.csv'), '-o', str(tmp_path / 'bag'), '--time', 't',
                          '--pattern', 'x{k},y{k},h{k}', '--unit', 'mm', '--angle', 'deg'], capsys)
    assert code == 0, err
    code, original, err = run(['analyze', str(source), '--min-periods', '10'], capsys)
    assert code == 0, err
    code, imported, err = run(['analyze', str(tmp_path / 'bag'), '--min-periods', '10'], capsys)
    assert code == 0, err
    assert '3 bound pairs, 3 of them gliders' in original
    assert imported.splitlines()[1:] == original.splitlines()[1:]     # all but the line naming the bag


def test_gaps_are_reported_not_filled(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Missing cells make the robot unseen (NaN when read) on those lines; a long time step is named."""
    text = ('t,x0,y0,h0,x1,y1,h1\n'
            '0.0,0.1,0.2,0.0,0.3,0.4,1.0\n'
            '0.1,0.1,0.2,0.0,,,\n'
            '0.2,0.1,0.2,0.0,nan,0.4,1.0\n'
            '0.3,0.1,0.2,0.0,0.3,0.4,1.0\n'
            '\n'
            '1.0,0.1,0.2,0.0,0.3,0.4,1.0\n'
            '1.1,0.1,0.2,0.0,0.3,0.4,1.0\n')
    (tmp_path / 'gaps.csv').write_text(text)
    code, out, err = run(['import', str(tmp_path / 'gaps.csv'), '-o', str(tmp_path / 'bag'), '--time', 't',
                          '--pattern', 'x{k},y{k},h{k}'], capsys)
    assert code == 0, err
    gaps = err.strip().splitlines()
    assert gaps == [
        'smarticle-bag import: gap: gaps.csv lines 3-4: robot 1 has no pose (t = 0.1 to 0.2 s, 2 rows); '
        'written as unseen, not interpolated',
        'smarticle-bag import: gap: gaps.csv lines 5-7: 0.7 s between rows, 7.0x the median step 0.1 s; '
        'nothing filled in']
    assert 'gaps: 2 (listed above; not filled in)' in out
    poses = arrays.read_poses(BagReader(tmp_path / 'bag'))
    assert len(poses.stamp) == 6                               # no row added
    assert np.isnan(poses.xyh[1:3, 1]).all() and np.isfinite(poses.xyh[[0, 3, 4, 5], 1]).all()
    assert np.isfinite(poses.xyh[:, 0]).all()


@pytest.mark.parametrize(('text', 'args', 'expected'), [
    ('t,x0,y0,h0\n0,1,2,3\n0.1,1,abc,3\n0.2,1,2,3\n', [],
     ["bad.csv line 3, column 'y0': 'abc' is not a finite number"]),
    ('t,x0,y0,h0\n0,1,2,3\n,1,2,3\n0.2,1,2,3\n', [], ["bad.csv line 3, column 't': no time"]),
    ('t,x0,y0,h0\n0,1,2,3\n0.1,1,2,inf\n0.2,1,2\n', [],
     ["bad.csv line 3, column 'h0': 'inf' is not a finite number", 'bad.csv line 4: 3 cells, the header has 4']),
    ('t,x0,y0,h0\n0,1,2,3\n0.2,1,2,3\n0.1,1,2,3\n0.1,1,2,3\n', [],
     ["bad.csv line 4: time 0.1 s is not after line 3's 0.2 s (sort the rows by time or remove the repeated ones)",
      "bad.csv line 5: time 0.1 s is not after line 4's 0.1 s (sort the rows by time or remove the repeated ones)"]),
    ('t,x0,y0,h0\n-2.5,1,2,3\n0.1,1,2,3\n', [],
     ["bad.csv line 2: time -2.5 s is before 0; a bag's times start at 0 or later: add --time-offset 3"]),
    ('t,x0,y0,h0\n0,1,2,3\n0.1,1,2,3\n', ['--time', 'T'],
     ["bad.csv: column 'T' is not in the header (columns: t, x0, y0, h0)"]),
    ('t,x0,y0,h0\n0,1,2,3\n', [], ['bad.csv: 1 row(s) of tracks; at least 2 are needed']),
])
def test_bad_rows_are_one_line_each(tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str,
                                    args: list[str], expected: list[str]) -> None:
    (tmp_path / 'bad.csv').write_text(text)
    code, out, err = run(['import', str(tmp_path / 'bad.csv'), '-o', str(tmp_path / 'bag'),
                          '--robot', '0:x0,y0,h0', *(args or ['--time', 't'])], capsys)
    assert code == 2 and out == ''
    assert err.splitlines() == [f'smarticle-bag import: error: {line}' for line in expected]
    assert 'Traceback' not in err and not (tmp_path / 'bag').exists()


@pytest.mark.parametrize(('args', 'expected'), [
    (['--robot', '0:x0;y0'], "--robot '0:x0;y0': give ROBOT_ID:X_COLUMN,Y_COLUMN,HEADING_COLUMN"),
    (['--pattern', 'x{k},y{k}'], 'give three column names with {k}'),
    (['--pattern', 'u{k},v{k},w{k}'], "--pattern 'u{k},v{k},w{k}' matches no robot's three columns"),
    ([], 'name the robots\' columns with --robot'),
    (['--robot', '0:x0,y0,h0', '--px-per-bl', '0'], 'pixel tracks need --px-per-bl > 0'),
    (['--robot', '0:x0,y0,h0', '--unit', 'cm', '--px-per-bl', '100'], '--px-per-bl is for pixel tracks'),
    (['--robot', '0:x0,y0,h0', '--robot', '0:x0,y0,h0'], 'a robot id is given twice'),
    (['--robot', '0:x0,y0,h0', '--gap-factor', '0.5'], 'gap factor must be > 1'),
])
def test_bad_options_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
                                  expected: str) -> None:
    (tmp_path / 'ok.csv').write_text('t,x0,y0,h0\n0,1,2,3\n0.1,1,2,3\n')
    code, out, err = run(['import', str(tmp_path / 'ok.csv'), '-o', str(tmp_path / 'bag'), '--time', 't', *args],
                         capsys)
    assert code == 2 and expected in err and len(err.strip().splitlines()) == 1, err


def test_the_pose_encoder_matches_rosbags(tmp_path: Path) -> None:
    """Our CDR of a PoseArray decodes with rosbags to the same poses; an unseen robot is the contract's pose."""
    xyh = np.array([[0.1, -0.2, 2.5], [np.nan, np.nan, np.nan], [1e-3, 4.0, -3.1]])
    data = encode_pose_array(12_345_678_901, xyh, 'arena')
    msg: Any = STORE.deserialize_cdr(data, 'geometry_msgs/msg/PoseArray')
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (12, 345_678_901, 'arena')
    assert [p.position.z for p in msg.poses] == [0.0, -1.0, 0.0]
    assert msg.poses[2].orientation.z == pytest.approx(math.sin(-3.1 / 2))
    assert msg.poses[1].orientation.w == 1.0 and msg.poses[1].position.x == 0.0
    for frame in ('', 'a', 'ab', 'abc', 'arena_frame'):      # every alignment of the sequence after the string
        again: Any = STORE.deserialize_cdr(encode_pose_array(5, xyh[:1], frame), 'geometry_msgs/msg/PoseArray')
        assert again.header.frame_id == frame and again.poses[0].position.y == pytest.approx(-0.2)


def test_pixel_scale_uses_the_presets_width() -> None:
    spec = ImportSpec(time='t', robots=(RobotColumns(0, 'x', 'y', 'h'),), length_unit='px', px_per_bl=100.0)
    assert spec.length_scale == pytest.approx(SMALL.body_length / 100.0)
    with pytest.raises(OptionError, match='robot preset'):
        ImportSpec(time='t', robots=(RobotColumns(0, 'x', 'y', 'h'),), length_unit='px', px_per_bl=1.0,
                   body_preset='huge')


def test_problems_beyond_twenty_are_counted(tmp_path: Path) -> None:
    (tmp_path / 'many.csv').write_text('t,x,y,h\n' + ''.join(f'{i},a,0,0\n' for i in range(30)))
    spec = ImportSpec(time='t', robots=(RobotColumns(0, 'x', 'y', 'h'),))
    with pytest.raises(CsvImportError) as err:
        read_tracks(tmp_path / 'many.csv', spec)
    assert len(err.value.problems) == 21 and err.value.problems[-1] == '... and 10 more'
