"""The time base of log times: the recorder's sim-time stamping, metadata, ``info``, and playback of a sim bag."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.rosbag2 import Reader as RosbagsReader

from smarticle_bags import cli
from smarticle_bags.metadata import BagInfo, FileInfo, read_metadata
from smarticle_bags.playback import PlaybackOptions, window
from smarticle_bags.reader import BagReader
from smarticle_bags.reindex import reindex
from smarticle_bags.timebase import NS, TIME_BASE_KEY, SimLogClock, TimeBase, custom_data, describe, time_base
from smarticle_bags.writer import BagWriter, WriterOptions

from tests.helpers.bags import POSES, T0, make_sim_bag, pose_array


def test_messages_before_the_first_clock_are_held_then_stamped_with_it() -> None:
    clock = SimLogClock()
    assert clock.stamp('/smarticles/start', b'go') == [] and not clock.started
    assert clock.stamp(POSES, b'p0') == []
    assert clock.on_clock(5 * NS) == [('/smarticles/start', b'go', 5 * NS), (POSES, b'p0', 5 * NS)]
    assert clock.held == [] and clock.started
    assert clock.stamp(POSES, b'p1') == [(POSES, b'p1', 5 * NS)]
    assert clock.on_clock(5 * NS + NS // 60) == []
    assert clock.stamp(POSES, b'p2') == [(POSES, b'p2', 5 * NS + NS // 60)]   # the latest /clock


def test_held_messages_are_bounded_and_the_rest_counted() -> None:
    clock = SimLogClock(max_held_bytes=10)
    for _ in range(4):
        clock.stamp(POSES, b'abcd')
    assert len(clock.held) == 2 and clock.held_bytes == 8 and clock.dropped == 2
    assert len(clock.on_clock(0)) == 2      # a sim that starts at time 0 is a started clock too
    assert clock.stamp(POSES, b'x') == [(POSES, b'x', 0)]


def info_of(start: int, custom: dict[str, str] | None) -> BagInfo:
    return BagInfo(files=[FileInfo('b_0.mcap', start, 20 * NS, 10)], custom_data=custom)


def test_time_base_stated_or_inferred() -> None:
    assert time_base(info_of(0, custom_data(TimeBase.SIM))) == (TimeBase.SIM, True)
    assert time_base(info_of(T0, custom_data(TimeBase.WALL))) == (TimeBase.WALL, True)
    assert time_base(info_of(2 * NS, None)) == (TimeBase.SIM, False)      # an old sim bag: log times near 0
    assert time_base(info_of(T0, None)) == (TimeBase.WALL, False)         # rosbag2's, or an old wall bag
    assert time_base(info_of(T0, {'other': 'x'})) == (TimeBase.WALL, False)
    assert describe(info_of(0, custom_data(TimeBase.SIM))).startswith('sim time (/clock')
    assert 'inferred' in describe(info_of(2 * NS, None))
    assert describe(info_of(T0, None)) == 'wall time (assumed: the bag does not say)'


def test_a_sim_bag_says_so_and_lasts_its_sim_time(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    count = make_sim_bag(tmp_path / 'sim', 20.0)
    with pytest.raises(SystemExit) as ended:
        cli.main(['info', str(tmp_path / 'sim')])
    out = capsys.readouterr().out
    assert ended.value.code == 0
    assert 'Duration:          20.000000000s' in out
    assert 'Log time:          sim time (/clock, recorded with use_sim_time)' in out
    # the independent reader agrees on the span and keeps the metadata
    with RosbagsReader(tmp_path / 'sim') as other:
        assert other.duration == 20 * NS + 1 and other.message_count == count   # rosbags: end - start + 1
        assert other.start_time == 0
    assert read_metadata(tmp_path / 'sim').custom_data == {TIME_BASE_KEY: 'sim'}
    # at rate 1 the player plays the whole window, 20 s of bag time from 0
    reader = BagReader(tmp_path / 'sim')
    first, last = window(reader.info.starting_time, reader.info.end_time, PlaybackOptions(rate=1.0))
    assert (first, last) == (0, 20 * NS)
    # reindex keeps the time base
    reindex(tmp_path / 'sim')
    assert time_base(BagReader(tmp_path / 'sim').info) == (TimeBase.SIM, True)


def test_info_of_a_bag_that_does_not_say(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with BagWriter(tmp_path / 'wall', WriterOptions()) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        writer.write(POSES, pose_array(0), T0)
    with pytest.raises(SystemExit):
        cli.main(['info', str(tmp_path / 'wall')])
    assert 'Log time:          wall time (assumed: the bag does not say)' in capsys.readouterr().out
