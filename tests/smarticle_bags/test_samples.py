"""The sample bags in bags/samples/ (made by bags/scripts/make_samples.py with the real nodes).

Each must be small, read completely with our reader and with the independent ``rosbags`` reader (the
same messages, the same values), and ``smarticle-bag info`` must work on it.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader as RosbagsReader
from rosbags.typesys import Stores, get_typestore

from smarticle_bags import arrays
from smarticle_bags.reader import BagReader

from tests.helpers.ros import ROOT, executable

SAMPLES = ROOT / 'bags' / 'samples'
BAGS = sorted(p for p in SAMPLES.iterdir() if (p / 'metadata.yaml').is_file()) if SAMPLES.is_dir() else []
STORE = get_typestore(Stores.ROS2_JAZZY)
PUBLISH_PERIOD_NS = 50_000_000


def test_samples_exist() -> None:
    assert {p.name for p in BAGS} >= {'pair_c1', 'dense7'}


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: p.name)
def test_sample_is_small_and_complete(bag: Path) -> None:
    assert sum(f.stat().st_size for f in bag.iterdir()) < 2 * 1024 * 1024
    reader = BagReader(bag, strict=True)
    assert not reader.problems
    assert sum(1 for _ in reader.messages()) == reader.info.message_count > 0
    decoded = sum(1 for _ in reader.decoded())
    assert decoded == reader.info.message_count
    poses = arrays.read_poses(reader)
    assert np.all(np.isfinite(poses.xyh))
    # lock-step sim: one pose per publish period from t = 0, none missing
    stamps_ns = np.round(poses.stamp * 1e9).astype(np.int64)
    assert stamps_ns[0] == 0
    assert np.all(np.diff(stamps_ns) == PUBLISH_PERIOD_NS)
    assert reader.topics['/smarticles/start'].message_count == 1


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: p.name)
def test_sample_reads_with_rosbags(bag: Path) -> None:
    ours = BagReader(bag)
    by_topic: dict[str, list[tuple[int, bytes]]] = {}
    for raw in ours.messages():
        by_topic.setdefault(raw.topic, []).append((raw.log_time, raw.data))
    with RosbagsReader(bag) as reader:
        assert reader.message_count == ours.info.message_count
        assert {c.topic: c.msgtype for c in reader.connections} == {t.name: t.type for t in ours.info.topics}
        theirs: dict[str, list[tuple[int, bytes]]] = {}
        for connection, timestamp, data in reader.messages():
            STORE.deserialize_cdr(data, connection.msgtype)  # raises on any malformed message
            theirs.setdefault(connection.topic, []).append((timestamp, bytes(data)))
    assert theirs == by_topic
    # the same values through both decoders
    first_raw = by_topic['/smarticles/poses'][-1][1]
    mine = next(m for r, m in ours.decoded(['/smarticles/poses']) if r.data == first_raw)
    other = STORE.deserialize_cdr(first_raw, 'geometry_msgs/msg/PoseArray')
    assert [(p.position.x, p.orientation.w) for p in mine.poses] == \
        [(p.position.x, p.orientation.w) for p in other.poses]


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: p.name)
def test_sample_info_command(bag: Path) -> None:
    done = subprocess.run([executable('smarticle-bag'), 'info', str(bag), '--strict'], capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert 'Storage id:        mcap' in done.stdout
    for topic in BagReader(bag).topics:
        assert f'Topic: {topic} ' in done.stdout
