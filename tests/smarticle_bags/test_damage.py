"""Bad input: missing bags, folders without metadata, truncated and corrupt .mcap files, reindex."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from smarticle_bags import mcapfile
from smarticle_bags.errors import BagNotFoundError, CorruptBagError, MetadataError, TopicSelectionError
from smarticle_bags.reader import BagReader
from smarticle_bags.reindex import reindex

from tests.helpers.bags import JOINTS, POSES, make_bag


def _cut(path: Path, keep: float) -> None:
    """Truncate ``path`` to a fraction of its size (as a killed writer would leave it)."""
    data = path.read_bytes()
    path.write_bytes(data[:int(len(data) * keep)])


def test_missing_bag_and_missing_metadata(tmp_path: Path) -> None:
    with pytest.raises(BagNotFoundError, match='does not exist'):
        BagReader(tmp_path / 'nope')
    make_bag(tmp_path / 'bag', 5)
    (tmp_path / 'bag' / 'metadata.yaml').unlink()
    with pytest.raises(MetadataError, match='no metadata.yaml.*reindex'):
        BagReader(tmp_path / 'bag')
    (tmp_path / 'bag' / 'metadata.yaml').write_text('rosbag2_bagfile_information: {version: 9}\n')
    with pytest.raises(MetadataError, match="missing key 'topics_with_message_count'"):
        BagReader(tmp_path / 'bag')


def test_not_an_mcap(tmp_path: Path) -> None:
    path = tmp_path / 'x.mcap'
    path.write_bytes(b'hello, this is not a bag')
    with pytest.raises(CorruptBagError, match='not an MCAP file'):
        BagReader(path)


def test_unknown_topic_is_named(tmp_path: Path) -> None:
    make_bag(tmp_path / 'bag', 3)
    with pytest.raises(TopicSelectionError, match=r'/nothing: no such topic.*/smarticles/poses'):
        list(BagReader(tmp_path / 'bag').messages(['/nothing']))


def test_truncated_file_strict_error_and_salvage(tmp_path: Path) -> None:
    written = make_bag(tmp_path / 'bag', 100)
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    _cut(mcap, 0.6)
    with pytest.raises(CorruptBagError, match='bag_0.mcap.*(cut off|without a footer).*reindex'):
        BagReader(tmp_path / 'bag', strict=True)
    reader = BagReader(tmp_path / 'bag')
    assert reader.problems
    got = [(m.topic, m.log_time, m.data) for m in reader.messages()]
    assert 20 < len(got) < 200
    expected = sorted(((t, time, data) for t in (POSES, JOINTS) for time, data in written[t]),
                      key=lambda item: item[1])
    assert got == expected[:len(got)]  # a prefix of what was written, byte for byte


def test_corrupt_chunk_is_skipped(tmp_path: Path) -> None:
    make_bag(tmp_path / 'bag', 100)
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    scan = mcapfile.scan(mcap)
    assert scan.complete and not scan.problems
    middle = scan.chunks[len(scan.chunks) // 2]
    data = bytearray(mcap.read_bytes())
    for i in range(middle.offset + 60, middle.offset + 80):
        data[i] ^= 0xFF
    mcap.write_bytes(bytes(data))
    reader = BagReader(tmp_path / 'bag')
    count = sum(1 for _ in reader.messages())
    assert 150 <= count < 200
    assert any('damaged' in p for p in reader.problems)


def test_reindex_repairs_and_rebuilds(tmp_path: Path) -> None:
    make_bag(tmp_path / 'bag', 100)
    original = (tmp_path / 'bag' / 'metadata.yaml').read_text()
    shutil.copy(tmp_path / 'bag' / 'bag_0.mcap', tmp_path / 'intact.mcap')
    (tmp_path / 'bag' / 'metadata.yaml').unlink()
    report = reindex(tmp_path / 'bag')
    assert not report.repaired
    assert yaml.safe_load((tmp_path / 'bag' / 'metadata.yaml').read_text()) == yaml.safe_load(original)

    _cut(tmp_path / 'bag' / 'bag_0.mcap', 0.5)
    salvaged = sum(1 for _ in BagReader(tmp_path / 'bag').messages())
    untouched = (tmp_path / 'bag' / 'bag_0.mcap').read_bytes()
    beside = reindex(tmp_path / 'bag')  # default: the repaired bag goes beside the original
    assert beside.output == tmp_path / 'bag.repaired' and beside.repaired
    assert (tmp_path / 'bag' / 'bag_0.mcap').read_bytes() == untouched
    assert BagReader(beside.output, strict=True).info.message_count == salvaged
    assert 'dropped:' in (beside.output / 'reindex_report.txt').read_text()
    report = reindex(tmp_path / 'bag', replace=True)
    assert report.repaired and report.problems
    assert (tmp_path / 'bag' / 'bag_0.mcap.damaged').is_file()  # nothing recorded is deleted
    reader = BagReader(tmp_path / 'bag', strict=True)
    assert reader.info.message_count == salvaged == sum(1 for _ in reader.messages())
    assert {t.name: t.message_count for t in reader.info.topics}[POSES] > 0

    from rosbags.rosbag2 import Reader
    with Reader(tmp_path / 'bag') as other:
        assert other.message_count == salvaged
