"""End to end over real DDS: publisher -> recorder process -> bag; bag -> player process -> subscriber."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import Any, Callable

import pytest

from smarticle_bags.reader import BagReader
from smarticle_bags.reindex import reindex
from smarticle_bags.writer import BagWriter, WriterOptions

from tests.helpers.ros import NodeProcesses, spin_until
from tests.helpers.bags import POSES, T0, pose_array

pytestmark = pytest.mark.integration

TOPIC = '/smarticle_7/joint_states'


def _reliable() -> Any:
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    return QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def _start_recording(nodes: NodeProcesses, ros_node: Callable[[str], Any], out: Path,
                     *extra: str) -> tuple[Any, Any, Any]:
    """Start a recorder of TOPIC and a test publisher; return (process, node, publisher) once matched."""
    from sensor_msgs.msg import JointState

    proc = nodes.start('smarticle-bag', 'record', TOPIC, '-o', str(out), '--flush-interval', '0.2',
                       '--polling-interval', '0.1', *extra)
    node = ros_node('bag_test_publisher')
    publisher = node.create_publisher(JointState, TOPIC, _reliable())
    matched = spin_until(node, lambda: publisher.get_subscription_count() > 0, 20.0)
    assert matched, nodes.output(proc)
    return proc, node, publisher


def _joint_state(i: int) -> Any:
    from sensor_msgs.msg import JointState
    msg = JointState(name=['arm1', 'arm2'], position=[0.001 * i, -0.001 * i])
    msg.header.stamp.sec = i
    return msg


def test_publisher_to_recorder_to_bag(nodes: NodeProcesses, ros_node: Callable[[str], Any],
                                      tmp_path: Path) -> None:
    out = tmp_path / 'rec'
    proc, node, publisher = _start_recording(nodes, ros_node, out)
    for i in range(40):
        publisher.publish(_joint_state(i))
        spin_until(node, lambda: False, 0.01)
    time.sleep(0.5)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=10) == 0, nodes.output(proc)
    reader = BagReader(out, strict=True)
    assert reader.topics[TOPIC].type == 'sensor_msgs/msg/JointState'
    assert reader.topics[TOPIC].offered_qos_profiles[0].reliability == 'reliable'
    got = [(list(msg.name), list(msg.position), msg.header.stamp.sec) for _, msg in reader.decoded([TOPIC])]
    assert got == [(['arm1', 'arm2'], [0.001 * i, -0.001 * i], i) for i in range(40)]


def test_killed_recorder_leaves_readable_bag(nodes: NodeProcesses, ros_node: Callable[[str], Any],
                                             tmp_path: Path) -> None:
    out = tmp_path / 'killed'
    proc, node, publisher = _start_recording(nodes, ros_node, out)
    for i in range(60):
        publisher.publish(_joint_state(i))
        spin_until(node, lambda: False, 0.01)
    time.sleep(0.8)  # several flush intervals: everything so far is on disk
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=5)
    reader = BagReader(out)  # salvages: no footer
    assert reader.problems
    stamps = [msg.header.stamp.sec for _, msg in reader.decoded([TOPIC])]
    assert stamps == list(range(60))
    report = reindex(out, replace=True)
    assert report.repaired
    assert BagReader(out, strict=True).info.message_count == 60


def test_killed_split_recording(nodes: NodeProcesses, ros_node: Callable[[str], Any], tmp_path: Path) -> None:
    from rosbags.rosbag2 import Reader

    out = tmp_path / 'split'
    proc, node, publisher = _start_recording(nodes, ros_node, out, '--max-bag-duration', '0.5')
    for i in range(120):
        publisher.publish(_joint_state(i))
        spin_until(node, lambda: False, 0.015)
    time.sleep(0.8)  # several flush intervals: everything so far is on disk
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=5)
    files = sorted(out.glob('*.mcap'), key=lambda p: int(p.stem.rsplit('_', 1)[1]))
    assert len(files) >= 3, nodes.output(proc)
    for index, path in enumerate(files[:-1]):  # closed files: complete, rosbags reads them as they are
        single = tmp_path / f'single_{index}'
        single.mkdir()
        single.joinpath(path.name).write_bytes(path.read_bytes())
        assert not reindex(single).repaired
        with Reader(single) as other:
            assert other.message_count > 0
    reader = BagReader(out)  # one bag over all files, the last one salvaged
    stamps = [msg.header.stamp.sec for _, msg in reader.decoded([TOPIC])]
    assert stamps == list(range(120))
    reindex(out, replace=True)
    with Reader(out) as other:
        assert other.message_count == 120


def test_player_timing_and_unknown_type(nodes: NodeProcesses, ros_node: Callable[[str], Any],
                                        tmp_path: Path) -> None:
    from geometry_msgs.msg import PoseArray

    bag = tmp_path / 'play'
    step = 50_000_000
    with BagWriter(bag, WriterOptions(chunk_size=4000)) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        writer.add_topic('/mystery', 'mystery_msgs/msg/Thing', definition='int32 x\n', type_hash='')
        for i in range(30):
            writer.write(POSES, pose_array(i), T0 + i * step)
            writer.write('/mystery', b'\x00\x01\x00\x00\x05\x00\x00\x00', T0 + i * step + 1)
    node = ros_node('bag_test_subscriber')
    received: list[tuple[float, int]] = []
    node.create_subscription(PoseArray, '/replayed/poses',
                             lambda msg: received.append((time.monotonic(), msg.header.stamp.sec)),
                             _reliable())
    proc = nodes.start('smarticle-bag', 'play', str(bag), '--remap', f'{POSES}:=/replayed/poses',
                       '-r', '2.0', '--start-paused')
    # resume through the documented topic once both directions are matched
    from std_msgs.msg import Bool
    pause = node.create_publisher(Bool, '/player/pause', _reliable())
    assert spin_until(node, lambda: pause.get_subscription_count() > 0
                      and node.count_publishers('/replayed/poses') > 0, 20.0), nodes.output(proc)
    spin_until(node, lambda: False, 0.5)
    assert not received  # paused
    pause.publish(Bool(data=False))
    assert spin_until(node, lambda: len(received) == 30, 20.0), nodes.output(proc)
    assert proc.wait(timeout=10) == 0
    assert [s for _, s in received] == list(range(30))
    span = received[-1][0] - received[0][0]
    assert span == pytest.approx(29 * step * 1e-9 / 2.0, abs=0.15)
    gaps = [b[0] - a[0] for a, b in zip(received, received[1:], strict=False)]
    assert max(abs(g - 0.025) for g in gaps) < 0.1
    log = nodes.output(proc)
    assert 'skipping /mystery: unknown message type mystery_msgs/msg/Thing' in log


def test_player_plays_a_split_bag_as_one(nodes: NodeProcesses, ros_node: Callable[[str], Any],
                                         tmp_path: Path) -> None:
    from geometry_msgs.msg import PoseArray

    bag = tmp_path / 'split'
    step = 50_000_000
    with BagWriter(bag, WriterOptions(chunk_size=4000, max_bag_duration=500_000_000)) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        for i in range(30):
            writer.write(POSES, pose_array(i), T0 + i * step)
    assert len(BagReader(bag).info.files) == 3
    node = ros_node('bag_split_subscriber')
    received: list[int] = []
    node.create_subscription(PoseArray, POSES, lambda msg: received.append(msg.header.stamp.sec), _reliable())
    proc = nodes.start('smarticle-bag', 'play', str(bag), '-r', '4.0', '--start-paused')
    from std_msgs.msg import Bool
    pause = node.create_publisher(Bool, '/player/pause', _reliable())
    assert spin_until(node, lambda: pause.get_subscription_count() > 0 and node.count_publishers(POSES) > 0,
                      20.0), nodes.output(proc)
    spin_until(node, lambda: False, 0.5)  # let both directions match
    pause.publish(Bool(data=False))
    assert spin_until(node, lambda: len(received) == 30, 30.0), nodes.output(proc)
    assert proc.wait(timeout=10) == 0
    assert received == list(range(30))


def test_play_rejects_bad_rate_and_missing_topic(nodes: NodeProcesses, tmp_path: Path) -> None:
    bag = tmp_path / 'b'
    with BagWriter(bag) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray')
        writer.write(POSES, pose_array(0), T0)
    bad_rate = nodes.start('smarticle-bag', 'play', str(bag), '-r', '0')
    missing = nodes.start('smarticle-bag', 'play', str(bag), '--topics', '/nothing')
    assert bad_rate.wait(timeout=15) != 0 and missing.wait(timeout=15) != 0
    assert 'rate' in nodes.output(bad_rate)
    assert '/nothing: no such topic' in nodes.output(missing)
