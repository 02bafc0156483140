"""Checked reads: chunk CRCs, damaged records named with their offset, foreign files, salvage by reindex."""

from __future__ import annotations

import logging
import struct
from pathlib import Path

import pytest
from mcap.writer import Writer as McapWriter

from smarticle_bags import arrays, cli, mcapfile
from smarticle_bags.errors import CorruptBagError
from smarticle_bags.reader import BagReader
from smarticle_bags.reindex import reindex
from smarticle_bags.writer import Compression, WriterOptions

from tests.helpers.bags import JOINTS, POSES, make_bag

OPCODE_NAMES = {1: 'Header', 2: 'Footer', 3: 'Schema', 4: 'Channel', 6: 'Chunk', 7: 'MessageIndex',
                8: 'ChunkIndex', 11: 'Statistics', 14: 'SummaryOffset', 15: 'DataEnd'}


def records(data: bytes) -> list[tuple[int, int, int]]:
    """Return (opcode, offset, total length) of the top-level records of an intact .mcap."""
    out, pos = [], 8
    while pos + 9 <= len(data) - 8:
        opcode, length = struct.unpack_from('<BQ', data, pos)
        out.append((opcode, pos, 9 + length))
        pos += 9 + length
    return out


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run ``smarticle-bag`` in this process; return (exit code, stdout, stderr)."""
    with pytest.raises(SystemExit) as done:
        cli.main(args)
    out, err = capsys.readouterr()
    return int(done.value.code or 0), out, err


def flip_chunk(path: Path, which: int, count: int = 3) -> mcapfile.ChunkRef:
    """Flip ``count`` bytes in the middle of the data of chunk number ``which``; return that chunk."""
    scan = mcapfile.scan(path)
    ref = scan.chunks[which]
    data = bytearray(path.read_bytes())
    middle = ref.records_offset + ref.records_length // 2
    for i in range(count):
        data[middle + 7 * i] ^= 0x5A
    path.write_bytes(bytes(data))
    return ref


@pytest.mark.parametrize('compression', [Compression.ZSTD, Compression.NONE, Compression.LZ4])
def test_chunk_crc_is_checked_everywhere(tmp_path: Path, compression: Compression,
                                         capsys: pytest.CaptureFixture[str],
                                         caplog: pytest.LogCaptureFixture) -> None:
    written = make_bag(tmp_path / 'bag', 100, WriterOptions(compression=compression, chunk_size=2000))
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    intact = mcapfile.scan(mcap, verify=True)
    assert not intact.problems and intact.message_count == 200
    ref = flip_chunk(mcap, len(intact.chunks) // 2)
    # the messages of that chunk, from the intact copy: what must be reported lost and never returned
    lost = {t: sum(1 for time, _ in written[t] if ref.start_time <= time <= ref.end_time) for t in written}
    code, out, _ = run_cli(['check', str(tmp_path / 'bag')], capsys)
    assert code == 2
    assert f'chunk at byte {ref.offset}' in out and 'is damaged' in out
    expected = ', '.join(f'{t} {n}' for t, n in sorted(lost.items()) if n)
    assert f'{sum(lost.values())} messages lost: {expected}' in out
    assert f'{ref.start_time / 1e9:.3f}..{ref.end_time / 1e9:.3f}' in out
    code, _, err = run_cli(['info', str(tmp_path / 'bag'), '--strict'], capsys)
    assert code == 2 and f'chunk at byte {ref.offset}' in err and len(err.strip().splitlines()) == 1
    caplog.set_level(logging.WARNING)
    got = {(m.topic, m.log_time, m.data) for m in BagReader(tmp_path / 'bag').messages()}
    everything = {(t, time, data) for t in written for time, data in written[t]}
    assert got < everything and len(got) == 200 - sum(lost.values())
    assert any('messages lost' in r.getMessage() for r in caplog.records)
    poses = arrays.read_poses(BagReader(tmp_path / 'bag'))
    assert len(poses.stamp) == 100 - lost[POSES]
    report = reindex(tmp_path / 'bag')
    assert report.output is not None and report.info.message_count == len(got)
    text = (report.output / 'reindex_report.txt').read_text()
    assert f'chunk at byte {ref.offset}' in text and 'messages lost' in text
    assert f'lost in damaged chunks: {sum(lost.values())} messages' in text
    assert report.info.message_count + sum(lost.values()) == 200
    from rosbags.rosbag2 import Reader
    with Reader(report.output) as other:
        assert {(c.topic, t, bytes(d)) for c, t, d in other.messages()} == got


def test_damaged_records_are_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    make_bag(tmp_path / 'bag', 40)
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    original = mcap.read_bytes()
    layout = records(original)
    seen = set()
    for opcode, offset, length in layout:
        name = OPCODE_NAMES.get(opcode)
        if name is None or name in seen:
            continue
        seen.add(name)
        data = bytearray(original)
        at = offset + 9 + (length - 9) // 2 if opcode != 6 else offset + 12  # a chunk: its start time
        data[at] ^= 0x10
        mcap.write_bytes(bytes(data))
        code, out, err = run_cli(['check', str(tmp_path / 'bag')], capsys)
        assert code == 2, (name, out, err)
        assert 'byte' in out + err, (name, out)
        reindexed = reindex(tmp_path / 'bag', output=tmp_path / f'fixed_{name}')
        assert BagReader(reindexed.output or tmp_path, strict=True).info.message_count > 0
    assert seen >= {'Header', 'Schema', 'Channel', 'Chunk', 'MessageIndex', 'ChunkIndex', 'Statistics',
                    'SummaryOffset', 'Footer', 'DataEnd'}


def test_damaged_channel_recovered_from_summary_copy(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    make_bag(tmp_path / 'bag', 30)
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    data = bytearray(mcap.read_bytes())
    channel = next((op, off, n) for op, off, n in records(bytes(data)) if op == 4)
    struct.pack_into('<Q', data, channel[1] + 1, 2**40)  # its length: no longer parseable
    mcap.write_bytes(bytes(data))
    code, out, _ = run_cli(['check', str(tmp_path / 'bag')], capsys)
    assert code == 2 and f'Channel record at byte {channel[1]}' in out
    report = reindex(tmp_path / 'bag')
    assert report.output is not None
    assert report.info.message_count == 60  # both topics from the summary's copy of the channel
    assert {t.name for t in report.info.topics} == {POSES, JOINTS}


def _write_foreign(folder: Path, kind: str) -> Path:
    """Write a file that is not a ROS 2 mcap bag into ``folder``; return its path."""
    folder.mkdir(parents=True)
    path = folder / f'{folder.name}_0.mcap'
    if kind == 'ros1':
        path.write_bytes(b'#ROSBAG V2.0\nE\x00\x00\x00\x04\x00\x00\x00op=\x03' + bytes(4000))
    elif kind == 'zeroed':
        path.write_bytes(bytes(5000))
    elif kind == 'empty':
        path.write_bytes(b'')
    elif kind == 'json':
        with open(path, 'wb') as handle:
            writer = McapWriter(handle)
            writer.start(profile='', library='test')
            schema = writer.register_schema('thing', 'jsonschema', b'{}')
            channel = writer.register_channel('/things', 'json', schema)
            writer.add_message(channel, 1, b'{"a": 1}', 1)
            writer.finish()
    return path


@pytest.mark.parametrize('kind', ['ros1', 'zeroed', 'empty', 'json'])
def test_foreign_files_are_one_line_errors(tmp_path: Path, kind: str,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    path = _write_foreign(tmp_path / 'bag', kind)
    before = {p.name: p.read_bytes() for p in (tmp_path / 'bag').iterdir()}
    for command in (['info', str(path)], ['check', str(path)], ['reindex', str(tmp_path / 'bag')],
                    ['info', str(tmp_path / 'bag')]):
        code, out, err = run_cli(command, capsys)
        assert code == 2, (command, out, err)
        assert len(err.strip().splitlines()) == 1, err
        assert 'error:' in err and ('bag_0.mcap' in err or 'metadata.yaml' in err), err
    assert {p.name: p.read_bytes() for p in (tmp_path / 'bag').iterdir()} == before  # nothing written
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag']


def test_empty_folder_and_truncated_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / 'empty').mkdir()
    for command in ('info', 'check', 'reindex'):
        code, _, err = run_cli([command, str(tmp_path / 'empty')], capsys)
        assert code == 2 and str(tmp_path / 'empty') in err and len(err.strip().splitlines()) == 1
    make_bag(tmp_path / 'bag', 50)
    mcap = tmp_path / 'bag' / 'bag_0.mcap'
    mcap.write_bytes(mcap.read_bytes()[:5])
    code, _, err = run_cli(['check', str(tmp_path / 'bag')], capsys)
    assert code == 2 and 'bag_0.mcap' in err
    with pytest.raises(CorruptBagError, match='bag_0.mcap'):
        BagReader(tmp_path / 'bag')


def test_check_of_intact_bags_and_stale_metadata(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for bag in sorted((Path(__file__).resolve().parents[2] / 'bags' / 'samples').iterdir()):
        code, out, _ = run_cli(['check', str(bag)], capsys)
        assert code == 0 and 'OK:' in out and 'every CRC and record checked' in out
    make_bag(tmp_path / 'bag', 10)
    meta = tmp_path / 'bag' / 'metadata.yaml'
    meta.write_text(meta.read_text().replace('message_count: 20', 'message_count: 25'))
    code, out, _ = run_cli(['check', str(tmp_path / 'bag')], capsys)
    assert code == 2 and 'says 25 messages for bag_0.mcap, the file holds 20' in out
