"""Columnar decoding: every field equals rosbags' deserialiser and our per-message path, any layout mix."""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from smarticle_common.poses import quaternion_heading
from rosbags.rosbag2 import Reader as RosbagsReader

from smarticle_bags import arrays, columnar
from smarticle_bags.reader import BagReader
from smarticle_bags.writer import BagWriter, WriterOptions

from tests.helpers.ros import ROOT
from tests.helpers.bags import STORE, T0

SAMPLES = ROOT / 'bags' / 'samples'
BAGS = sorted(p for p in SAMPLES.iterdir() if (p / 'metadata.yaml').is_file()) if SAMPLES.is_dir() else []
TYPES = STORE.types


def _time(sec: int, nanosec: int) -> Any:
    return TYPES['builtin_interfaces/msg/Time'](sec=sec, nanosec=nanosec)


def _header(i: int, frame: str) -> Any:
    return TYPES['std_msgs/msg/Header'](stamp=_time(i, 1000 * i), frame_id=frame)


def pose_array(i: int, robots: int, frame: str, little: bool = True) -> bytes:
    """A PoseArray of ``robots`` poses with a given frame id (any byte order)."""
    poses = [TYPES['geometry_msgs/msg/Pose'](
        position=TYPES['geometry_msgs/msg/Point'](x=k + i * 0.125, y=-k * 0.3, z=0.5),
        orientation=TYPES['geometry_msgs/msg/Quaternion'](x=0.01 * k, y=0.02, z=math.sin(0.1 * i + k),
                                                          w=math.cos(0.1 * i + k)))
        for k in range(robots)]
    msg = TYPES['geometry_msgs/msg/PoseArray'](header=_header(i, frame), poses=poses)
    if little:
        return bytes(STORE.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray'))
    return bytes(STORE.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray', little_endian=False))


def joint_state(i: int, names: list[str], counts: tuple[int, int, int], frame: str = '') -> bytes:
    """A JointState with ``names`` and position/velocity/effort of the given lengths."""
    def values(n: int, scale: float) -> np.ndarray:
        return np.array([scale * (i + k + 1) for k in range(n)], dtype=np.float64)
    msg = TYPES['sensor_msgs/msg/JointState'](header=_header(i, frame), name=names, position=values(counts[0], 0.1),
                                              velocity=values(counts[1], -1.5), effort=values(counts[2], 3.0))
    return bytes(STORE.serialize_cdr(msg, 'sensor_msgs/msg/JointState'))


def expected_from_rosbags(bag: Path) -> dict[str, list[tuple[int, Any]]]:
    """Every message of the bag decoded by rosbags: topic -> [(log time, message)]."""
    out: dict[str, list[tuple[int, Any]]] = {}
    with RosbagsReader(bag) as reader:
        for connection, timestamp, data in reader.messages():
            out.setdefault(connection.topic, []).append(
                (timestamp, STORE.deserialize_cdr(data, connection.msgtype)))
    for items in out.values():
        items.sort(key=lambda item: item[0])
    return out


def assert_same_joints(a: arrays.JointSeries, b: arrays.JointSeries) -> None:
    assert a.names == b.names
    for name in ('log_time', 'stamp', 'position', 'velocity', 'effort'):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def assert_same_poses(a: arrays.PoseSeries, b: arrays.PoseSeries) -> None:
    np.testing.assert_array_equal(a.log_time, b.log_time)
    np.testing.assert_array_equal(a.stamp, b.stamp)
    np.testing.assert_array_equal(a.xyh[..., :2], b.xyh[..., :2])
    np.testing.assert_allclose(a.xyh[..., 2], b.xyh[..., 2], rtol=0, atol=1e-15)


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: p.name)
def test_every_field_equals_rosbags(bag: Path) -> None:
    reader = BagReader(bag)
    theirs = expected_from_rosbags(bag)
    checked = 0
    for topic, info in reader.topics.items():
        items = theirs.get(topic, [])
        if info.type == columnar.POSE_ARRAY:
            poses = arrays.read_poses(reader, topic)
            assert len(poses.stamp) == len(items) > 0
            for t, (log_time, msg) in enumerate(items):
                assert poses.log_time[t] == log_time * 1e-9
                assert poses.stamp[t] == msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
                for k, pose in enumerate(msg.poses):
                    o = pose.orientation
                    assert poses.xyh[t, k, 0] == pose.position.x and poses.xyh[t, k, 1] == pose.position.y
                    assert poses.xyh[t, k, 2] == pytest.approx(quaternion_heading(o.x, o.y, o.z, o.w), abs=1e-15)
            checked += len(items)
        elif info.type == columnar.JOINT_STATE:
            joints = arrays.read_joints(reader, topic)
            assert len(joints.stamp) == len(items) > 0
            for t, (log_time, msg) in enumerate(items):
                assert joints.log_time[t] == log_time * 1e-9
                assert joints.stamp[t] == msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
                for i, name in enumerate(msg.name):
                    j = joints.names.index(name)
                    for field in ('position', 'velocity', 'effort'):
                        values = getattr(msg, field)
                        got = getattr(joints, field)[t, j]
                        assert got == values[i] if i < len(values) else math.isnan(got)
            checked += len(items)
        elif info.type == columnar.CLOCK:
            clock = arrays.read_clock(reader, topic)
            np.testing.assert_array_equal(clock.clock, [m.clock.sec + 1e-9 * m.clock.nanosec for _, m in items])
            checked += len(items)
    assert checked >= 0.9 * reader.info.message_count


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: p.name)
def test_columnar_equals_per_message_on_samples(bag: Path) -> None:
    reader = BagReader(bag)
    assert_same_poses(arrays.read_poses(reader), arrays.read_poses(reader, columnar=False))
    for key in ('joint_states', 'fsr', 'joint_commands'):
        fast, slow = arrays.read_robot_topic(reader, key), arrays.read_robot_topic(reader, key, columnar=False)
        assert fast.keys() == slow.keys()
        for robot in fast:
            assert_same_joints(fast[robot], slow[robot])


def make_mixed_bag(folder: Path) -> None:
    """Poses and joint states whose layouts change from message to message, one of them big-endian."""
    frames = ['', 'a', 'arena', 'world_frame_1', 'arena']
    name_sets = [['arm1', 'arm2'], ['arm2', 'arm1'], ['arm1', 'arm3'], ['arm1'], [], ['arm1', 'arm2', 'x']]
    counts = [(2, 2, 0), (2, 2, 0), (2, 0, 2), (1, 1, 1), (0, 0, 0), (3, 1, 0)]
    with BagWriter(folder, WriterOptions(chunk_size=1500)) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        writer.add_topic('/smarticle_0/joint_states', 'sensor_msgs/msg/JointState')
        for i in range(60):
            robots = [3, 3, 0, 1, 5][i % 5]
            data = pose_array(i, robots, frames[(i // 3) % len(frames)], little=i % 7 != 3)
            writer.write('/smarticles/poses', data, T0 + i * 1000)
            k = (i // 2) % len(name_sets)
            names = name_sets[k]
            position, velocity, effort = counts[k]
            writer.write('/smarticle_0/joint_states',
                         joint_state(i, names, (min(position, len(names) + 1), velocity, effort), frames[i % 5]),
                         T0 + i * 1000 + (i % 3))


def test_changing_layouts_decode_like_per_message(tmp_path: Path) -> None:
    make_mixed_bag(tmp_path / 'bag')
    reader = BagReader(tmp_path / 'bag')
    fast = arrays.read_poses(reader)
    assert_same_poses(fast, arrays.read_poses(reader, columnar=False))
    assert fast.xyh.shape == (60, 5, 3)
    assert np.isnan(fast.xyh[2]).all() and not np.isnan(fast.xyh[4]).any()
    assert_same_joints(arrays.read_joints(reader, '/smarticle_0/joint_states'),
                       arrays.read_joints(reader, '/smarticle_0/joint_states', columnar=False))
    groups = columnar.decode_groups(columnar.gather(reader, ['/smarticles/poses'])['/smarticles/poses'])
    assert len(groups) > 5  # several layouts, each decoded as a block


def test_without_message_index_and_time_window(tmp_path: Path) -> None:
    make_mixed_bag(tmp_path / 'bag')
    indexed = BagReader(tmp_path / 'bag')
    walked = BagReader(tmp_path / 'bag')
    for result in walked.scans:
        for ref in result.chunks:
            ref.index_records.clear()  # as written by a writer without message indexes
    assert_same_joints(arrays.read_joints(indexed, '/smarticle_0/joint_states'),
                       arrays.read_joints(walked, '/smarticle_0/joint_states'))
    start, end = T0 + 10_000, T0 + 20_000
    item = columnar.gather(indexed, ['/smarticles/poses'], start, end)['/smarticles/poses']
    assert list(item.log_time) == [T0 + i * 1000 for i in range(10, 21)]


def test_malformed_messages_are_skipped_with_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(10):
            data = pose_array(i, 2, 'arena')
            writer.write('/smarticles/poses', data[:30] if i == 4 else data, T0 + i)
    caplog.set_level(logging.WARNING)
    poses = arrays.read_poses(BagReader(tmp_path / 'bag'))
    assert len(poses.stamp) == 9 and 4.0 not in poses.stamp
    assert any('cannot decode' in r.getMessage() for r in caplog.records)


def test_large_files_are_read_in_batches(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    make_mixed_bag(tmp_path / 'bag')
    whole = BagReader(tmp_path / 'bag')
    expected_poses = arrays.read_poses(whole)
    expected_joints = arrays.read_joints(whole, '/smarticle_0/joint_states')
    monkeypatch.setattr(columnar, 'BATCH_BYTES', 3000)  # several batches of a few chunks each
    batched = BagReader(tmp_path / 'bag')
    assert_same_poses(arrays.read_poses(batched), expected_poses)
    assert_same_joints(arrays.read_joints(batched, '/smarticle_0/joint_states'), expected_joints)
    assert not batched.chunk_cache.data  # nothing kept between calls when streaming


def test_the_unseen_pose_reads_as_nan_on_both_paths(tmp_path: Path) -> None:
    from smarticle_common import topics

    def frame(i: int) -> bytes:
        seen = [(0.1 * k, -0.05 * k, 0.0) for k in range(3)]
        poses = [TYPES['geometry_msgs/msg/Pose'](
            position=TYPES['geometry_msgs/msg/Point'](x=x, y=y, z=z),
            orientation=TYPES['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0))
            for x, y, z in seen]
        if i % 2:       # robot 1 not seen in odd frames: the contract's unseen pose
            poses[1].position.x, poses[1].position.y, poses[1].position.z = 0.0, 0.0, topics.UNSEEN_Z
        msg = TYPES['geometry_msgs/msg/PoseArray'](header=_header(i, 'arena'), poses=poses)
        return bytes(STORE.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray'))
    with BagWriter(tmp_path / 'bag', WriterOptions(chunk_size=2000)) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(20):
            writer.write('/smarticles/poses', frame(i), T0 + i * 10_000_000)
    reader = BagReader(tmp_path / 'bag')
    fast, slow = arrays.read_poses(reader), arrays.read_poses(reader, columnar=False)
    assert_same_poses(fast, slow)
    assert np.all(np.isnan(fast.xyh[1::2, 1])) and np.all(np.isfinite(fast.xyh[0::2, 1]))
    assert np.all(np.isfinite(fast.xyh[:, [0, 2]]))
