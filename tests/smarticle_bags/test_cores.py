"""Pure cores: topic selection, playback timing, arrays, CSV export, info text, settings, CLI errors."""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import numpy as np
import pytest
from smarticle_common.poses import quaternion_heading
from smarticle_common.runs import load_npz

from smarticle_bags import arrays, cli
from smarticle_bags.errors import OptionError, TopicSelectionError
from smarticle_bags.export import export_bag
from smarticle_bags.info import format_info
from smarticle_bags.playback import PlaybackClock, PlaybackOptions, window
from smarticle_bags.reader import BagReader
from smarticle_bags.selection import TopicFilter, parse_remaps

from tests.helpers.bags import JOINTS, POSES, T0, make_bag

CONFIG = Path(__file__).resolve().parents[2] / 'bags' / 'smarticle_bags' / 'config'


def test_topic_filter() -> None:
    available = [('/a', ['std_msgs/msg/Header']), ('/smarticle_1/fsr', ['sensor_msgs/msg/JointState']),
                 ('/_hidden', ['std_msgs/msg/Header']), ('/two', ['x/msg/A', 'y/msg/B'])]
    assert TopicFilter(topics=('a',)).choose(available) == {'/a': 'std_msgs/msg/Header'}
    assert list(TopicFilter(regex='fsr$').choose(available)) == ['/smarticle_1/fsr']
    assert list(TopicFilter(all=True, exclude_regex='^/a').choose(available)) == ['/smarticle_1/fsr']
    assert '/_hidden' in TopicFilter(all=True, include_hidden=True).choose(available)
    with pytest.raises(TopicSelectionError, match='no topics chosen'):
        TopicFilter()
    with pytest.raises(TopicSelectionError, match='not a valid regular expression'):
        TopicFilter(regex='(')
    with pytest.raises(TopicSelectionError, match='not a valid ROS topic name'):
        TopicFilter(topics=('/bad name!',))
    assert parse_remaps(['/a:=/b c:=/d']) == {'/a': '/b', '/c': '/d'}
    with pytest.raises(TopicSelectionError, match='must look like'):
        parse_remaps(['/a=/b'])


def test_playback_options_and_clock() -> None:
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(OptionError, match='rate'):
            PlaybackOptions(rate=bad)
    with pytest.raises(OptionError, match='start offset'):
        PlaybackOptions(start_offset=-1.0)
    opts = PlaybackOptions(start_offset=1.0, playback_duration=2.0)
    assert window(0, 10 * 10**9, opts) == (10**9, 3 * 10**9)
    with pytest.raises(OptionError, match='past the end'):
        window(0, 10**8, opts)
    clock = PlaybackClock(2.0)
    clock.start(wall=1000, bag=5000, paused=True)
    assert clock.now(9999) == 5000 and clock.wall_of(6000) is None
    clock.resume(2000)
    assert clock.now(2100) == 5200 and clock.wall_of(5200) == 2100
    clock.pause(2500)
    assert clock.now(99999) == 6000
    clock.resume(3000)
    assert clock.now(3050) == 6100


def test_arrays(tmp_path: Path) -> None:
    make_bag(tmp_path / 'bag', 20)
    reader = BagReader(tmp_path / 'bag')
    poses = arrays.read_poses(reader)
    assert poses.xyh.shape == (20, 3, 3)
    assert poses.xyh[5, 2, 0] == pytest.approx(2.05) and poses.xyh[5, 2, 1] == pytest.approx(-2.0)
    np.testing.assert_allclose(poses.xyh[0, :, 2], [0.0, 0.5, 1.0])
    assert poses.stamp[3] == 3.0 and poses.log_time[0] == pytest.approx(T0 * 1e-9)
    joints = arrays.read_robot_topic(reader, 'joint_states')
    assert list(joints) == [0] and joints[0].names == ('arm1', 'arm2')
    assert joints[0].position[4, 1] == pytest.approx(-0.04) and np.isnan(joints[0].effort).all()
    assert quaternion_heading(0.0, 0.0, math.sin(0.5), math.cos(0.5)) == pytest.approx(1.0)


def test_export_and_info(tmp_path: Path) -> None:
    make_bag(tmp_path / 'bag', 10)
    reader = BagReader(tmp_path / 'bag')
    report = export_bag(reader, tmp_path / 'csv')
    assert set(report.written) == {POSES, JOINTS} and not report.skipped
    with open(tmp_path / 'csv' / 'smarticles__poses.csv', newline='') as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 30 and rows[4]['robot'] == '1' and float(rows[4]['x']) == pytest.approx(1.01)
    with open(tmp_path / 'csv' / 'smarticle_0__joint_states.csv', newline='') as handle:
        header = next(csv.reader(handle))
    assert header[:4] == ['log_time', 'stamp', 'position_arm1', 'position_arm2']
    text = format_info(reader)
    assert 'Messages:          20' in text and 'Storage id:        mcap' in text
    assert re.search(r'Topic: /smarticles/poses +\| Type: geometry_msgs/msg/PoseArray +\| Count: 10 \| '
                     r'Serialization Format: cdr', text)


def test_export_run_writes_the_one_run_format(tmp_path: Path) -> None:
    """The bag's poses come out as a run file that load_npz reads like a batch trial's."""
    make_bag(tmp_path / 'bag', 10)
    with pytest.raises(SystemExit) as ended:
        cli.main(['export', str(tmp_path / 'bag'), '-o', str(tmp_path / 'csv'), '--run', str(tmp_path / 'run.npz')])
    assert ended.value.code == 0
    run = load_npz(tmp_path / 'run.npz')
    poses = arrays.read_poses(BagReader(tmp_path / 'bag'))
    assert np.array_equal(run.poses, poses.xyh, equal_nan=True)
    assert run.time[0] == 0.0 and np.allclose(run.time, poses.stamp - poses.stamp[0])
    assert np.isnan(run.arm_angles).all() and not run.meta['fsr_recorded']


def test_cli_errors_and_info(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['info', str(tmp_path / 'missing')])
    assert exit_info.value.code == 2
    assert 'does not exist' in capsys.readouterr().err
    make_bag(tmp_path / 'bag', 4)
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['info', str(tmp_path / 'bag')])
    assert exit_info.value.code == 0 and 'Messages:          8' in capsys.readouterr().out
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['export', str(tmp_path / 'bag'), '-o', str(tmp_path / 'out'), '--topics', '/nope'])
    assert exit_info.value.code == 2 and '/nope: no such topic' in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag')])
    out = capsys.readouterr().out
    assert exit_info.value.code == 0 and ': no bound pair, no glider' in out and out.endswith('\n  none\n'), out
