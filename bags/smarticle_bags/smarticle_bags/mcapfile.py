"""Crash-tolerant reading of one .mcap file: walk its records, salvage what is complete, merge by time.

A finished file has a summary (schemas, channels, statistics) after the data section, a footer and a
closing magic. A recorder that was killed leaves a file that ends somewhere in the data section,
possibly in the middle of a chunk. ``scan`` walks the records from the start, keeps every complete
chunk and stops at the first cut-off or invalid record; it reports what it found in ``problems``.
``iter_messages`` then yields the messages of all readable chunks in log-time order. Chunks whose
data fail their CRC or do not decompress are skipped and reported. No ROS import.
"""

from __future__ import annotations

import heapq
import logging
import os
import struct
from collections import Counter
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import BinaryIO, Iterator

from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Header, McapRecord, Message, Schema, Statistics
from mcap.stream_reader import breakup_chunk

from .errors import CorruptBagError

MAGIC = b'\x89MCAP0\r\n'
_LOG = logging.getLogger(__name__)

try:  # the exception types of the chunk decompressors, when installed
    from zstandard import ZstdError as _ZstdError
except ImportError:  # pragma: no cover - mcap needs zstandard for zstd chunks anyway
    _ZstdError = McapError  # type: ignore[misc,assignment]

#: What a damaged chunk can raise while being decompressed and split into records.
CHUNK_ERRORS = (McapError, ValueError, RuntimeError, struct.error, EOFError, _ZstdError)


@dataclass(frozen=True)
class ChunkRef:
    """Where a chunk record lies in the file and the log-time range of its messages."""

    offset: int
    length: int
    start_time: int
    end_time: int


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
    problems: list[str] = field(default_factory=list)

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
                f'{len(self.chunks)} complete chunks are readable')


def _read_body(handle: BinaryIO, offset: int, length: int) -> ReadDataStream:
    """Return a stream over the body of the record whose 9-byte prefix starts at ``offset``."""
    handle.seek(offset + 9)
    return ReadDataStream(BytesIO(handle.read(length)))


def _opcode_name(opcode: int) -> str:
    """Return the record type name of an opcode."""
    try:
        return Opcode(opcode).name
    except ValueError:
        return f'opcode 0x{opcode:02x}'


def scan(path: Path) -> McapScan:
    """Walk the records of ``path`` and return what is readable; raise CorruptBagError if nothing is."""
    path = Path(path)
    try:
        size = os.path.getsize(path)
        handle = open(path, 'rb')
    except OSError as err:
        raise CorruptBagError(f'{path}: cannot open ({err.strerror})') from err
    result = McapScan(path=path, size=size)
    with handle:
        if handle.read(8) != MAGIC:
            raise CorruptBagError(f'{path}: not an MCAP file (bad or missing magic bytes at the start)')
        offset = 8
        in_summary = False
        statistics: Statistics | None = None
        while True:
            if offset + 9 > size:
                result.problems.append(
                    f'file ends at byte {size} without a footer (the recording was interrupted)')
                break
            handle.seek(offset)
            opcode, length = struct.unpack('<BQ', handle.read(9))
            end = offset + 9 + length
            if opcode == 0 or end > size:
                what = 'invalid record' if opcode == 0 else f'{_opcode_name(opcode)} record cut off'
                result.problems.append(f'{what} at byte {offset} of {size} (truncated or damaged file)')
                break
            if opcode == Opcode.CHUNK:
                handle.seek(offset + 9)
                start_time, end_time = struct.unpack('<QQ', handle.read(16))
                result.chunks.append(ChunkRef(offset, 9 + length, start_time, end_time))
            elif opcode == Opcode.HEADER:
                header = Header.read(_read_body(handle, offset, length))
                result.profile, result.library = header.profile, header.library
            elif opcode == Opcode.SCHEMA:
                schema = Schema.read(_read_body(handle, offset, length))
                result.schemas[schema.id] = schema
            elif opcode == Opcode.CHANNEL:
                channel = Channel.read(_read_body(handle, offset, length))
                result.channels[channel.id] = channel
            elif opcode == Opcode.MESSAGE and not in_summary:
                result.loose.append(Message.read(_read_body(handle, offset, length), length))
            elif opcode == Opcode.STATISTICS:
                statistics = Statistics.read(_read_body(handle, offset, length))
            elif opcode == Opcode.DATA_END:
                in_summary = True
            elif opcode == Opcode.FOOTER:
                handle.seek(end)
                if handle.read(8) == MAGIC:
                    result.complete = True
                else:
                    result.problems.append(f'footer at byte {offset} is not followed by the closing magic')
                break
            offset = end
        if result.complete and statistics is not None:
            result.channel_counts = dict(statistics.channel_message_counts)
            result.start_time, result.end_time = statistics.message_start_time, statistics.message_end_time
        else:
            _count_by_reading(handle, result)
    if not result.complete and not result.problems:
        result.problems.append('no footer')
    return result


def _count_by_reading(handle: BinaryIO, result: McapScan) -> None:
    """Decompress every chunk to find channels and message counts (files without a summary)."""
    counts: Counter[int] = Counter()
    times: list[int] = []
    good: list[ChunkRef] = []
    for ref in result.chunks:
        records = load_chunk(handle, ref, result)
        if records is None:
            continue
        good.append(ref)
        for record in records:
            if isinstance(record, Message):
                counts[record.channel_id] += 1
                times.append(record.log_time)
    for message in result.loose:
        counts[message.channel_id] += 1
        times.append(message.log_time)
    result.chunks = good
    result.channel_counts = dict(counts)
    if times:
        result.start_time, result.end_time = min(times), max(times)


def load_chunk(handle: BinaryIO, ref: ChunkRef, result: McapScan) -> list[McapRecord] | None:
    """Return the records of one chunk (learning its schemas and channels), or None if it is damaged."""
    try:
        chunk = Chunk.read(_read_body(handle, ref.offset, ref.length - 9))
        records = breakup_chunk(chunk, validate_crc=True)
    except CHUNK_ERRORS as err:
        problem = f'chunk at byte {ref.offset} is damaged and was skipped ({err})'
        if problem not in result.problems:
            result.problems.append(problem)
            _LOG.warning('%s: %s', result.path, problem)
        return None
    for record in records:
        if isinstance(record, Schema):
            result.schemas[record.id] = record
        elif isinstance(record, Channel):
            result.channels[record.id] = record
    return records


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
                for record in load_chunk(handle, refs[index], result) or ():
                    if isinstance(record, Message):
                        push(record)
                index += 1
            if heap:
                message = heapq.heappop(heap)[2]
                channel = result.channels.get(message.channel_id)
                if channel is not None:
                    yield channel, message
