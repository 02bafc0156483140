"""Checked, crash-tolerant reading of one .mcap file: walk its records, verify them, salvage what is intact.

A finished file has a summary (schemas, channels, statistics, chunk indexes) after the data section, a
footer and a closing magic. A recorder that was killed leaves a file that ends somewhere in the data
section, possibly in the middle of a chunk; a disk or copy error leaves flipped or zeroed bytes.

``scan`` walks the records from the start. Every record is parsed on its own: a damaged one becomes
a one-line entry of ``problems`` naming the record and its byte offset, never an exception. After
a record whose length cannot be right, the walk resynchronises on the next intact chunk. Schemas and
channels come from their first intact copy (the summary's copy when the summary's CRC holds).

Chunks are checked when they are read: decompressed, their CRC compared (where the writer stored
one) and their records walked. A chunk that fails is skipped with a warning naming its byte offset,
its log-time range and the messages lost per topic (from the chunk's message index), and is listed
in ``McapScan.damaged``; its bytes are never returned as messages. ``scan(path, verify=True)`` checks
every chunk up front (and the data section's CRC, where written). No ROS import.
"""

from __future__ import annotations

import heapq
import logging
import mmap
import os
import struct
import zlib
from collections import Counter
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import Any, Iterator

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Header, Message, Schema, Statistics

from .errors import CorruptBagError

MAGIC = b'\x89MCAP0\r\n'
_LOG = logging.getLogger(__name__)

try:  # the exception types of the chunk decompressors, when installed
    import zstandard
    from zstandard import ZstdError as _ZstdError
except ImportError:  # pragma: no cover - mcap needs zstandard for zstd chunks anyway
    zstandard = None  # type: ignore[assignment]
    _ZstdError = McapError  # type: ignore[misc,assignment]
try:
    import lz4.frame as _lz4
except ImportError:  # pragma: no cover - optional in mcap
    _lz4 = None

#: What parsing a damaged record or chunk can raise.
RECORD_ERRORS = (McapError, ValueError, RuntimeError, struct.error, EOFError, IndexError, KeyError,
                 TypeError, OverflowError, MemoryError, _ZstdError)
#: Kept for callers of the previous name.
CHUNK_ERRORS = RECORD_ERRORS

#: The data section's CRC is checked on every open up to this size (one pass over the bytes), and for
#: any size by ``scan(verify=True)``.
DATA_CRC_ALWAYS = 2 * 2**30
_PREFIX = struct.Struct('<BQ')
_CHUNK_HEAD = struct.Struct('<QQQII')  # start, end, uncompressed size, crc, compression name length
_MESSAGE_HEAD = struct.Struct('<HIQQ')  # channel, sequence, log time, publish time
_KNOWN = {int(op) for op in Opcode}
_COMPRESSIONS = ('', 'zstd', 'lz4')
_AFTER_CHUNK = {int(Opcode.MESSAGE_INDEX), int(Opcode.CHUNK), int(Opcode.DATA_END), int(Opcode.SCHEMA),
                int(Opcode.CHANNEL), int(Opcode.MESSAGE)}
_NAMES = {int(op): op.name.title().replace('_', '') for op in Opcode}


class ChunkDamaged(CorruptBagError):
    """A chunk whose data cannot be trusted (the message says why)."""


@dataclass
class ChunkRef:
    """A chunk record: where it lies, its log-time range, compression and the counts of its message index."""

    offset: int
    length: int
    start_time: int
    end_time: int
    compression: str = ''
    uncompressed_size: int = 0
    uncompressed_crc: int = 0
    records_offset: int = 0
    records_length: int = 0
    index_counts: dict[int, int] = field(default_factory=dict)
    index_records: dict[int, tuple[int, int, int]] = field(default_factory=dict)


@dataclass(frozen=True)
class DamagedChunk:
    """A chunk that failed its checks: where, which log times, why, and the messages lost per topic."""

    offset: int
    start_time: int
    end_time: int
    reason: str
    lost: dict[str, int] | None

    @property
    def lost_count(self) -> int | None:
        """Number of messages lost with the chunk (None when its message index is gone too)."""
        return None if self.lost is None else sum(self.lost.values())

    def describe(self) -> str:
        """One line: offset, time range, reason and the messages lost per topic."""
        if self.start_time or self.end_time:
            span = f'log time {self.start_time / 1e9:.3f}..{self.end_time / 1e9:.3f} s'
        else:
            span = 'log time unknown'
        if self.lost is None:
            lost = 'messages lost: unknown (no message index)'
        else:
            lost = (f'{sum(self.lost.values())} messages lost: '
                    + ', '.join(f'{topic} {n}' for topic, n in sorted(self.lost.items())))
        return f'chunk at byte {self.offset} ({span}) is damaged ({self.reason}); {lost}'


@dataclass
class McapScan:
    """What a walk over one .mcap file found: header, schemas, channels, chunks, counts, problems."""

    path: Path
    size: int
    profile: str = ''
    library: str = ''
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    chunks: list[ChunkRef] = field(default_factory=list)
    loose: list[Message] = field(default_factory=list)
    channel_counts: dict[int, int] = field(default_factory=dict)
    start_time: int = 0
    end_time: int = 0
    complete: bool = False
    verified: bool = False
    problems: list[str] = field(default_factory=list)
    damaged: list[DamagedChunk] = field(default_factory=list)
    chunk_index_times: dict[int, tuple[int, int]] = field(default_factory=dict)
    trusted: set[tuple[str, int]] = field(default_factory=set)

    @property
    def message_count(self) -> int:
        """Number of readable messages."""
        return sum(self.channel_counts.values())

    def topic_type(self, channel: Channel) -> str:
        """Return the message type of a channel (its schema name, '' if it has none)."""
        schema = self.schemas.get(channel.schema_id)
        return schema.name if schema is not None else ''

    def describe_problems(self) -> str:
        """Return one line naming the file, what is wrong and what is still readable."""
        return (f'{self.path}: {"; ".join(self.problems)}; {self.message_count} messages in '
                f'{len(self.chunks)} intact chunks are readable')

    def note(self, problem: str) -> bool:
        """Add ``problem`` once; return True if it is new."""
        if problem in self.problems:
            return False
        self.problems.append(problem)
        return True

    def mark_damaged(self, ref: ChunkRef, reason: str) -> DamagedChunk:
        """Record that chunk ``ref`` failed its checks (with what it held) and drop it from ``chunks``."""
        start, end = ref.start_time, ref.end_time
        if ref.offset in self.chunk_index_times:
            start, end = self.chunk_index_times[ref.offset]
        lost: dict[str, int] | None = None
        if ref.index_counts:
            lost = {}
            for channel_id, count in ref.index_counts.items():
                channel = self.channels.get(channel_id)
                topic = channel.topic if channel is not None else f'(channel {channel_id})'
                lost[topic] = lost.get(topic, 0) + count
        damaged = DamagedChunk(ref.offset, start, end, reason, lost)
        if all(d.offset != ref.offset for d in self.damaged):
            self.damaged.append(damaged)
            self.note(damaged.describe())
            _LOG.warning('%s: %s', self.path, damaged.describe())
        self.chunks = [c for c in self.chunks if c.offset != ref.offset]
        return damaged


def _near_magic(head: bytes) -> bool:
    """True if ``head`` starts with the MCAP magic with at most two bytes changed."""
    return len(head) >= 8 and sum(a != b for a, b in zip(head[:8], MAGIC, strict=True)) <= 2


def identify(head: bytes, size: int) -> str:
    """Return what a file that is not an MCAP file looks like, for the error message."""
    if size == 0:
        return 'empty file (0 bytes), not an MCAP file'
    if head.startswith(b'#ROSBAG V'):
        return ('a ROS 1 bag (rosbag format ' + head[9:12].decode('ascii', 'replace') + '), not a ROS 2 '
                'mcap bag; convert it with "rosbags-convert"')
    if head.startswith(b'SQLite format 3'):
        return 'an sqlite3 file (a rosbag2 sqlite3 bag?); convert it to mcap with "ros2 bag convert"'
    if not head.strip(b'\x00'):
        return f'all zero bytes at the start (zeroed or never written), not an MCAP file ({size} bytes)'
    return f'not an MCAP file (bad or missing magic bytes at the start; {size} bytes)'


def _stream(data: bytes) -> ReadDataStream:
    """Return an mcap read stream over ``data``."""
    return ReadDataStream(BytesIO(data))


def _parse_chunk_head(buf: Any, offset: int, length: int) -> ChunkRef:
    """Parse the fields of the chunk record at ``offset``; raise ChunkDamaged if they do not add up."""
    body = offset + 9
    if length < _CHUNK_HEAD.size + 8:
        raise ChunkDamaged(f'chunk record of {length} bytes is too short')
    start, end, usize, crc, name_len = _CHUNK_HEAD.unpack_from(buf, body)
    if name_len > 16:
        raise ChunkDamaged(f'compression name of {name_len} bytes')
    at = body + _CHUNK_HEAD.size
    if at + name_len + 8 > offset + 9 + length:
        raise ChunkDamaged('chunk header runs past the record')
    try:
        compression = bytes(buf[at:at + name_len]).decode('ascii')
    except UnicodeDecodeError:
        raise ChunkDamaged('compression name is not text') from None
    if compression not in _COMPRESSIONS:
        raise ChunkDamaged(f'unknown compression {compression!r}')
    at += name_len
    (records_length,) = struct.unpack_from('<Q', buf, at)
    at += 8
    if at + records_length != offset + 9 + length:
        raise ChunkDamaged(f'records length {records_length} does not match the record length {length}')
    if end < start:
        raise ChunkDamaged('message end time is before its start time')
    return ChunkRef(offset, 9 + length, start, end, compression, usize, crc, at, records_length)


def _lenient_chunk(buf: Any, offset: int, length: int) -> ChunkRef | None:
    """Return a chunk whose header fields are damaged but whose data pass the CRC it stores, else None.

    The record's own length and the CRC field are trusted; the compression is tried in turn, and the
    log-time range is taken from the messages.
    """
    body = offset + 9
    if length < _CHUNK_HEAD.size + 8:
        return None
    _, _, usize, crc, _ = _CHUNK_HEAD.unpack_from(buf, body)
    if not crc:
        return None
    for compression in _COMPRESSIONS:
        head = _CHUNK_HEAD.size + len(compression) + 8
        ref = ChunkRef(offset, 9 + length, 0, 0, compression, usize, crc, body + head, length - head)
        try:
            data = decompress(ref, bytes(buf[ref.records_offset:ref.records_offset + ref.records_length]))
            times = [log for op, at, _ in walk_chunk(data) if op == Opcode.MESSAGE
                     for _, _, log, _ in [_MESSAGE_HEAD.unpack_from(data, at)]]
        except ChunkDamaged:
            continue
        if times:
            ref.start_time, ref.end_time = min(times), max(times)
        ref.uncompressed_size = len(data)
        return ref
    return None


def _resync(buf: Any, start: int, size: int) -> int | None:
    """Return the offset of the next chunk record at or after ``start`` whose header adds up, or None."""
    at = start
    while True:
        at = buf.find(b'\x06', at, size - 9)
        if at < 0:
            return None
        (length,) = struct.unpack_from('<Q', buf, at + 1)
        if at + 9 + length <= size:
            try:
                _parse_chunk_head(buf, at, length)
                return at
            except (ChunkDamaged, struct.error):
                pass
        at += 1


def decompress(ref: ChunkRef, data: bytes) -> bytes:
    """Return the records of a chunk, decompressed and checked against its CRC; raise ChunkDamaged."""
    try:
        if ref.compression == 'zstd':
            if zstandard is None:  # pragma: no cover
                raise ChunkDamaged('zstd chunks need the zstandard package')
            inflater = zstandard.ZstdDecompressor().decompressobj()
            out = inflater.decompress(data)
            if not inflater.eof:
                raise ChunkDamaged('zstd data end before the end of their frame')
        elif ref.compression == 'lz4':
            if _lz4 is None:  # pragma: no cover
                raise ChunkDamaged('lz4 chunks need the lz4 package')
            out = _lz4.decompress(data)
        else:
            out = bytes(data)
    except ChunkDamaged:
        raise
    except RECORD_ERRORS as err:
        raise ChunkDamaged(f'{ref.compression} data do not decompress: {err}') from None
    if ref.uncompressed_crc and zlib.crc32(out) != ref.uncompressed_crc:
        raise ChunkDamaged(f'CRC mismatch: stored 0x{ref.uncompressed_crc:08x}, data 0x{zlib.crc32(out):08x}')
    if len(out) != ref.uncompressed_size and not ref.uncompressed_crc:
        raise ChunkDamaged(f'{len(out)} bytes after decompression, the chunk says {ref.uncompressed_size}')
    return out


def walk_chunk(data: bytes) -> Iterator[tuple[int, int, int]]:
    """Yield (opcode, body offset, body length) of the records in decompressed chunk ``data``.

    Raises ChunkDamaged at a record that is cut off or of an impossible kind.
    """
    pos, size = 0, len(data)
    unpack = _PREFIX.unpack_from
    while pos < size:
        if pos + 9 > size:
            raise ChunkDamaged(f'record at byte {pos} of the chunk data is cut off')
        opcode, length = unpack(data, pos)
        end = pos + 9 + length
        if end > size or opcode == 0 or (opcode == Opcode.MESSAGE and length < _MESSAGE_HEAD.size):
            raise ChunkDamaged(f'invalid record (opcode 0x{opcode:02x}, {length} bytes) at byte {pos} of '
                               f'the chunk data')
        yield opcode, pos + 9, length
        pos = end


def chunk_messages(result: McapScan, ref: ChunkRef, data: bytes) -> list[Message]:
    """Return the messages of decompressed chunk ``data`` (learning schemas and channels it holds)."""
    messages: list[Message] = []
    unpack = _MESSAGE_HEAD.unpack_from
    for opcode, at, length in walk_chunk(data):
        if opcode == Opcode.MESSAGE:
            channel, sequence, log_time, publish_time = unpack(data, at)
            messages.append(Message(channel_id=channel, sequence=sequence, log_time=log_time,
                                    publish_time=publish_time, data=data[at + 22:at + length]))
        elif opcode in (Opcode.SCHEMA, Opcode.CHANNEL):
            try:
                record: Any = (Schema if opcode == Opcode.SCHEMA else Channel).read(
                    _stream(data[at:at + length]))
            except RECORD_ERRORS as err:
                raise ChunkDamaged(f'damaged {_NAMES[opcode]} record in the chunk data ({err})') from None
            kind = 'schemas' if opcode == Opcode.SCHEMA else 'channels'
            if (kind, record.id) not in result.trusted:  # a copy inside a chunk passed the chunk's CRC
                table: dict[int, Any] = getattr(result, kind)
                if record.id in table and table[record.id] != record:
                    result.note(f'{_NAMES[opcode]} id {record.id}: the copy in the chunk at byte {ref.offset} '
                                f'differs from the one outside; using the chunk\'s (CRC-checked)')
                table[record.id] = record
                result.trusted.add((kind, record.id))
    return messages


def read_chunk(handle: Any, result: McapScan, ref: ChunkRef) -> bytes | None:
    """Return the checked, decompressed records of chunk ``ref``, or None (warning, damaged list)."""
    try:
        handle.seek(ref.records_offset)
        raw = handle.read(ref.records_length)
        if len(raw) != ref.records_length:
            raise ChunkDamaged('file ends inside the chunk')
        data = decompress(ref, raw)
    except ChunkDamaged as err:
        result.mark_damaged(ref, str(err))
        return None
    if len(data) != ref.uncompressed_size:
        result.note(f'chunk at byte {ref.offset} says {ref.uncompressed_size} bytes uncompressed but holds '
                    f'{len(data)} (damaged chunk header; the data pass their CRC)')
    return data


def load_chunk(handle: Any, ref: ChunkRef, result: McapScan) -> list[Message] | None:
    """Return the messages of one chunk, or None if it is damaged (it is then skipped with a warning)."""
    data = read_chunk(handle, result, ref)
    if data is None:
        return None
    try:
        return chunk_messages(result, ref, data)
    except ChunkDamaged as err:
        result.mark_damaged(ref, str(err))
        return None


class _Walker:
    """The record walk of ``scan`` over a memory map of the file."""

    def __init__(self, result: McapScan, buf: Any, verify: bool) -> None:
        self.result, self.buf, self.size, self.verify = result, buf, result.size, verify
        self.summary: dict[str, dict[int, Any]] = {'schemas': {}, 'channels': {}}
        self.data_copies: dict[str, dict[int, tuple[int, Any]]] = {'schemas': {}, 'channels': {}}
        self.statistics: Statistics | None = None
        self.in_summary = False
        self.summary_ok = False
        self.data_end_at: int | None = None
        self.last_chunk: ChunkRef | None = None
        self.bad_chunks: list[tuple[ChunkRef, str]] = []
        self._next = 0

    def problem(self, text: str) -> None:
        """Note one problem of the file."""
        self.result.note(text)

    def run(self, offset: int) -> None:
        """Walk the records from ``offset`` to the footer (or the point where nothing more is readable)."""
        buf, size = self.buf, self.size
        while True:
            if offset == size:
                self.problem(f'file ends at byte {size} without a footer (the recording was interrupted '
                             f'or the file was cut)')
                return
            if offset + 9 > size:
                self.problem(f'record at byte {offset} is cut off (file ends at byte {size})')
                return
            opcode, length = _PREFIX.unpack_from(buf, offset)
            end = offset + 9 + length
            if opcode not in _KNOWN or end > size:
                if opcode == Opcode.CHUNK and offset + 9 + 16 <= size:  # its time range is still there
                    start, stop = struct.unpack_from('<QQ', buf, offset + 9)
                    if start <= stop:
                        self.bad_chunks.append((ChunkRef(offset, size - offset, start, stop),
                                                f'cut off at byte {size}, the end of the file'))
                if opcode in _KNOWN:
                    what = (f'{_NAMES[opcode]} record at byte {offset} is cut off or has a damaged length '
                            f'({length} bytes declared, file ends at byte {size})')
                else:
                    what = f'invalid record (opcode 0x{opcode:02x}) at byte {offset}'
                if not self._skip_to_next_chunk(offset, what):
                    return
                offset = self._next
                continue
            if opcode == Opcode.CHUNK:
                try:
                    ref = _parse_chunk_head(buf, offset, length)
                except ChunkDamaged as err:
                    kept = _lenient_chunk(buf, offset, length) if end + 9 <= size and buf[end] in _AFTER_CHUNK \
                        else None
                    if kept is not None:
                        self.problem(f'damaged Chunk record at byte {offset} ({err}); its data pass their CRC '
                                     f'and are kept')
                        self.result.chunks.append(kept)
                        self.last_chunk = kept
                        offset = end
                        continue
                    if end + 9 <= size and buf[end] in _AFTER_CHUNK:
                        self.last_chunk = ChunkRef(offset, 9 + length, 0, 0)
                        self.bad_chunks.append((self.last_chunk, f'damaged chunk header: {err}'))
                        offset = end
                        continue
                    if not self._skip_to_next_chunk(offset, f'damaged Chunk record at byte {offset} ({err})'):
                        return
                    offset = self._next
                    continue
                self.result.chunks.append(ref)
                self.last_chunk = ref
            elif opcode == Opcode.FOOTER:
                self._footer(offset, length)
                return
            else:
                try:
                    self._record(opcode, offset, length)
                except RECORD_ERRORS as err:
                    self.problem(f'damaged {_NAMES[opcode]} record at byte {offset} ({err})')
            offset = end

    def _skip_to_next_chunk(self, offset: int, what: str) -> bool:
        """Note ``what`` and find the next intact chunk; return False when there is none."""
        found = _resync(self.buf, offset + 1, self.size)
        if found is None:
            self.problem(f'{what}; nothing readable after it')
            return False
        self.problem(f'{what}; skipped {found - offset} bytes to the next intact chunk at byte {found}')
        self._next = found
        self.in_summary = False
        return True

    def _body(self, offset: int, length: int) -> bytes:
        """Return the body bytes of the record at ``offset``."""
        return bytes(self.buf[offset + 9:offset + 9 + length])

    def _record(self, opcode: int, offset: int, length: int) -> None:
        """Parse one record other than a chunk or the footer."""
        result = self.result
        if opcode == Opcode.HEADER:
            header = Header.read(_stream(self._body(offset, length)))
            result.profile, result.library = header.profile, header.library
        elif opcode in (Opcode.SCHEMA, Opcode.CHANNEL):
            record: Any = (Schema if opcode == Opcode.SCHEMA else Channel).read(_stream(self._body(offset, length)))
            kind = 'schemas' if opcode == Opcode.SCHEMA else 'channels'
            if self.in_summary:
                self.summary[kind].setdefault(record.id, (offset, record))
            else:
                first = self.data_copies[kind].setdefault(record.id, (offset, record))
                if first[1] != record:
                    self.problem(f'{_NAMES[opcode]} record at byte {offset} differs from the copy at byte '
                                 f'{first[0]} (id {record.id}); using the first')
        elif opcode == Opcode.MESSAGE:
            if not self.in_summary:
                body = self._body(offset, length)
                if len(body) < _MESSAGE_HEAD.size:
                    raise McapError('message record too short')
                channel, sequence, log_time, publish_time = _MESSAGE_HEAD.unpack_from(body)
                result.loose.append(Message(channel_id=channel, sequence=sequence, log_time=log_time,
                                           publish_time=publish_time, data=body[22:]))
        elif opcode == Opcode.MESSAGE_INDEX:
            channel_id, records_length = struct.unpack_from('<HI', self.buf, offset + 9)
            if records_length % 16 or 6 + records_length > length:
                raise McapError(f'{records_length} bytes of index entries do not fit')
            if self.last_chunk is not None and not self.in_summary:
                self.last_chunk.index_counts[channel_id] = records_length // 16
                self.last_chunk.index_records[channel_id] = (offset, offset + 15, records_length)
        elif opcode == Opcode.CHUNK_INDEX:
            start, end, chunk_offset = struct.unpack_from('<QQQ', self.buf, offset + 9)
            if length < 24 + 8 + 4:
                raise McapError('chunk index too short')
            self.result.chunk_index_times[chunk_offset] = (start, end)
        elif opcode == Opcode.STATISTICS:
            self.statistics = Statistics.read(_stream(self._body(offset, length)))
        elif opcode == Opcode.DATA_END:
            (crc,) = struct.unpack_from('<I', self.buf, offset + 9)
            self.in_summary = True
            self.data_end_at = offset
            if crc and (self.verify or offset <= DATA_CRC_ALWAYS):
                actual = zlib.crc32(memoryview(self.buf)[:offset])
                if actual != crc:
                    self.problem(f'data section CRC mismatch (DataEnd record at byte {offset}: stored '
                                 f'0x{crc:08x}, data 0x{actual:08x})')
        elif opcode == Opcode.SUMMARY_OFFSET:
            group, start, group_length = struct.unpack_from('<BQQ', self.buf, offset + 9)
            if group not in _KNOWN or start + group_length > self.size or (group_length and self.buf[start] != group):
                raise McapError(f'points to byte {start}, where no {_NAMES.get(group, "known")} group starts')

    def _footer(self, offset: int, length: int) -> None:
        """Check the footer, the closing magic and the summary CRC."""
        result = self.result
        end = offset + 9 + length
        if length < 20:
            self.problem(f'damaged Footer record at byte {offset} ({length} bytes)')
            return
        summary_start, _, summary_crc = struct.unpack_from('<QQI', self.buf, offset + 9)
        if bytes(self.buf[end:end + 8]) != MAGIC:
            self.problem(f'footer at byte {offset} is not followed by the closing magic')
            return
        if summary_start:
            if summary_crc:
                actual = zlib.crc32(memoryview(self.buf)[summary_start:offset + 9 + 16]) \
                    if summary_start < offset else -1
                if actual != summary_crc:
                    self.problem(f'summary CRC mismatch (footer at byte {offset}, summary at byte '
                                 f'{summary_start}); the summary is ignored')
                    return
                self.summary_ok = True
            if self.data_end_at is not None and summary_start != self.data_end_at + 13:
                self.problem(f'footer at byte {offset} points to a summary at byte {summary_start}, '
                             f'but the data section ends at byte {self.data_end_at + 13}')
                self.summary_ok = False
                return
        result.complete = True

    def finish(self) -> None:
        """Choose the copy of every schema and channel to use; list chunks whose header is damaged."""
        result = self.result
        for kind in ('schemas', 'channels'):
            table: dict[int, Any] = getattr(result, kind)
            for record_id, (_, record) in self.data_copies[kind].items():
                table[record_id] = record
            for record_id, (at, record) in self.summary[kind].items():
                if record_id not in table:
                    table[record_id] = record
                    if self.summary_ok:
                        result.trusted.add((kind, record_id))
                elif table[record_id] != record:
                    if self.summary_ok:
                        table[record_id] = record  # covered by a CRC that holds
                        result.trusted.add((kind, record_id))
                    self.problem(f'{_NAMES[Opcode.SCHEMA if kind == "schemas" else Opcode.CHANNEL]} '
                                 f'record at byte {at} (summary) differs from the data section\'s copy '
                                 f'(id {record_id}); using the {"summary" if self.summary_ok else "first"} '
                                 f'copy')
        for ref, reason in self.bad_chunks:
            result.chunks.append(ref)
            result.mark_damaged(ref, reason)


def scan(path: Path, verify: bool = False) -> McapScan:
    """Walk the records of ``path`` and return what is readable; raise CorruptBagError if nothing is.

    With ``verify`` every chunk is decompressed and checked now (damaged ones are listed in
    ``damaged``), and the message counts come from the chunks rather than the summary.
    """
    path = Path(path)
    try:
        size = os.path.getsize(path)
        handle = open(path, 'rb')
    except OSError as err:
        raise CorruptBagError(f'{path}: cannot open ({err.strerror})') from err
    result = McapScan(path=path, size=size)
    with handle:
        head = handle.read(64)
        if head[:8] != MAGIC:
            if not (_near_magic(head) and size > 9 and head[8] == Opcode.HEADER):
                raise CorruptBagError(f'{path}: {identify(head, size)}')
            result.note('the magic bytes at byte 0 are damaged')
        with mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ) as buf:
            walker = _Walker(result, buf, verify)
            walker.run(8)
            walker.finish()
        if result.complete and not result.problems and walker.statistics is not None and not verify:
            statistics = walker.statistics
            result.channel_counts = dict(statistics.channel_message_counts)
            result.start_time, result.end_time = statistics.message_start_time, statistics.message_end_time
        else:
            _count_by_reading(handle, result, walker.statistics if result.complete else None)
    if not result.complete and not result.problems:
        result.note('no footer')
    return result


def require_ros2(result: McapScan) -> None:
    """Raise CorruptBagError if the file holds messages, but none in ROS 2's cdr encoding."""
    encodings = {c.message_encoding for c in result.channels.values()}
    if encodings and 'cdr' not in encodings:
        raise CorruptBagError(
            f'{result.path}: an MCAP file of profile {result.profile or "(none)"!r} with '
            f'{", ".join(sorted(encodings))} messages, not a ROS 2 bag (profile ros2, cdr messages)')


def _count_by_reading(handle: Any, result: McapScan, statistics: Statistics | None) -> None:
    """Check every chunk and count the readable messages (the summary is not used)."""
    counts: Counter[int] = Counter()
    lo, hi = 2**64, -1
    for ref in list(result.chunks):
        data = read_chunk(handle, result, ref)
        if data is None:
            continue
        try:
            messages = chunk_messages(result, ref, data)
        except ChunkDamaged as err:
            result.mark_damaged(ref, str(err))
            continue
        _check_index(handle, result, ref, data)
        if messages:
            first = min(m.log_time for m in messages)
            last = max(m.log_time for m in messages)
            if (first, last) != (ref.start_time, ref.end_time):
                result.note(f'chunk at byte {ref.offset} says log time {ref.start_time}..{ref.end_time} but '
                            f'holds {first}..{last} (damaged chunk header; the messages are intact)')
                ref.start_time, ref.end_time = first, last
            lo, hi = min(lo, first), max(hi, last)
        for message in messages:
            counts[message.channel_id] += 1
    for message in result.loose:
        counts[message.channel_id] += 1
        lo, hi = min(lo, message.log_time), max(hi, message.log_time)
    unknown = sorted(set(counts) - set(result.channels))
    if unknown:
        lost = sum(counts.pop(c) for c in unknown)
        result.note(f'{lost} messages of channel(s) {", ".join(map(str, unknown))} whose Channel record is '
                    f'lost cannot be read')
    result.channel_counts = dict(counts)
    if hi >= 0:
        result.start_time, result.end_time = lo, hi
    result.verified = True
    if statistics is not None and not result.damaged and not unknown:
        if statistics.message_count != sum(counts.values()):
            result.note(f'the Statistics record says {statistics.message_count} messages, the chunks hold '
                        f'{sum(counts.values())}')


def _check_index(handle: Any, result: McapScan, ref: ChunkRef, data: bytes) -> None:
    """Compare the message index records of a chunk with the messages it holds; note any mismatch."""
    if not ref.index_records:
        return
    actual: dict[int, list[tuple[int, int]]] = {}
    for opcode, at, _ in walk_chunk(data):
        if opcode == Opcode.MESSAGE:
            channel, _, log_time, _ = _MESSAGE_HEAD.unpack_from(data, at)
            actual.setdefault(channel, []).append((log_time, at - 9))
    for channel, (record_offset, start, length) in sorted(ref.index_records.items()):
        handle.seek(start)
        entries = sorted(struct.iter_unpack('<QQ', handle.read(length)))
        if entries != sorted(actual.get(channel, [])):
            result.note(f'damaged MessageIndex record at byte {record_offset} (channel {channel}: its '
                        f'entries do not match the chunk at byte {ref.offset}; the messages are intact)')
    unindexed = sorted(set(actual) - set(ref.index_records))
    if unindexed:
        result.note(f'chunk at byte {ref.offset} has no MessageIndex record for channel(s) '
                    f'{", ".join(map(str, unindexed))} (lost or damaged; the messages are intact)')


def iter_messages(result: McapScan, channel_ids: set[int] | None = None, start: int | None = None,
                  end: int | None = None) -> Iterator[tuple[Channel, Message]]:
    """Yield (channel, message) of readable messages in log-time order, optionally filtered."""
    lo = start if start is not None else 0
    hi = end if end is not None else 2**64
    refs = sorted((r for r in result.chunks if r.end_time >= lo and r.start_time <= hi),
                  key=lambda r: (r.start_time, r.offset))
    heap: list[tuple[int, int, Message]] = []
    sequence = 0

    def push(message: Message) -> None:
        nonlocal sequence
        if lo <= message.log_time <= hi and (channel_ids is None or message.channel_id in channel_ids):
            heapq.heappush(heap, (message.log_time, sequence, message))
            sequence += 1

    for message in result.loose:
        push(message)
    with open(result.path, 'rb') as handle:
        index = 0
        while index < len(refs) or heap:
            while index < len(refs) and (not heap or refs[index].start_time <= heap[0][0]):
                for message in load_chunk(handle, refs[index], result) or ():
                    push(message)
                index += 1
            if heap:
                message = heapq.heappop(heap)[2]
                channel = result.channels.get(message.channel_id)
                if channel is not None:
                    yield channel, message


class ChunkCache:
    """Decompressed, checked chunks kept for the next pass over the same bag, up to ``budget`` bytes."""

    def __init__(self, budget: int = 256 * 2**20) -> None:
        self.budget = budget
        self.used = 0
        self.data: dict[Any, Any] = {}

    def get(self, result: McapScan, ref: ChunkRef) -> bytes | None:
        """Return the cached records of a chunk, or None."""
        return self.data.get((result.path, ref.offset))

    def put(self, result: McapScan, ref: ChunkRef, data: bytes) -> None:
        """Keep the records of a chunk while the budget allows."""
        if self.used + len(data) <= self.budget:
            self.data[(result.path, ref.offset)] = data
            self.used += len(data)


def iter_chunk_data(result: McapScan, start: int | None = None, end: int | None = None,
                    cache: ChunkCache | None = None) -> Iterator[tuple[ChunkRef, bytes]]:
    """Yield (chunk, checked decompressed records) of the intact chunks overlapping [start, end] in read order."""
    lo = start if start is not None else 0
    hi = end if end is not None else 2**64
    refs = sorted((r for r in result.chunks if r.end_time >= lo and r.start_time <= hi),
                  key=lambda r: (r.start_time, r.offset))
    with open(result.path, 'rb') as handle:
        for ref in refs:
            data = cache.get(result, ref) if cache is not None else None
            if data is None:
                data = read_chunk(handle, result, ref)
                if data is None:
                    continue
                if cache is not None:
                    cache.put(result, ref, data)
            yield ref, data

