"""Columnar decoding of fixed-layout ROS 2 messages into NumPy arrays, whole chunks at a time.

The messages of the smarticle contract that analysis reads (``geometry_msgs/PoseArray``,
``sensor_msgs/JointState`` for joint states, commands and FSR, ``rosgraph_msgs/Clock``) have a fixed
CDR layout once their strings and sequence lengths are fixed: every pose message of a run has the
same frame id and robot count, every JointState of a topic the same joint names. So instead of
decoding message by message:

1. each checked chunk is decompressed once and its records are walked to collect the payloads of the
   wanted channels (``gather``);
2. the payloads of a topic are grouped by length and joined into one buffer;
3. the first message of a group is parsed in Python (``*_layout``) to learn where every field sits,
   and every message of the group whose structural bytes (encapsulation, string lengths and texts,
   sequence lengths) equal the template's is read with one ``np.frombuffer`` over a numpy structured
   dtype; the others start a new template. A message of its own layout (a different frame id, joint
   list, robot count, byte order) is thus still decoded correctly, just in a smaller group.

Messages that do not parse are skipped with a warning, as in ``BagReader.decoded``.
"""

from __future__ import annotations

import logging
import struct
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator

import numpy as np
import numpy.typing as npt

from . import mcapfile
from .errors import BagError

_LOG = logging.getLogger(__name__)

POSE_ARRAY = 'geometry_msgs/msg/PoseArray'
JOINT_STATE = 'sensor_msgs/msg/JointState'
CLOCK = 'rosgraph_msgs/msg/Clock'
#: Message types decoded here.
TYPES = (POSE_ARRAY, JOINT_STATE, CLOCK)

_HEAD = struct.Struct('<BQHIQ')  # opcode, record length, channel, sequence, log time
_MAX_TEMPLATES = 64


class LayoutError(BagError):
    """A message whose bytes do not hold the layout of its type."""


@dataclass
class Segment:
    """Payloads lying in one buffer: their start offsets, lengths and log times."""

    buf: npt.NDArray[np.uint8]
    starts: npt.NDArray[np.int64]
    lengths: npt.NDArray[np.int64]
    times: npt.NDArray[np.int64]

    @classmethod
    def of(cls, payloads: list[bytes], times: list[int]) -> Segment:
        """Return a segment holding ``payloads`` (joined into one buffer)."""
        lengths = np.fromiter(map(len, payloads), dtype=np.int64, count=len(payloads))
        starts = np.zeros(len(payloads), dtype=np.int64)
        if len(payloads) > 1:
            np.cumsum(lengths[:-1], out=starts[1:])
        return cls(np.frombuffer(b''.join(payloads), dtype=np.uint8), starts, lengths,
                   np.array(times, dtype=np.int64))

    def compact(self) -> Segment:
        """Return a copy holding only these payloads (so the buffer they were cut from can go)."""
        starts = np.zeros(len(self.starts), dtype=np.int64)
        pieces, at = [], 0
        for length in np.unique(self.lengths):
            mask = self.lengths == length
            count = int(mask.sum())
            rows = np.lib.stride_tricks.sliding_window_view(self.buf, int(length))[self.starts[mask]]
            pieces.append(rows.reshape(-1))
            starts[mask] = at + int(length) * np.arange(count)
            at += int(length) * count
        buf = np.concatenate(pieces) if pieces else np.zeros(0, dtype=np.uint8)
        return Segment(buf, starts, self.lengths, self.times)

    def select(self, keep: npt.NDArray[np.bool_]) -> Segment:
        """Return the segment of the payloads where ``keep`` is true."""
        return Segment(self.buf, self.starts[keep], self.lengths[keep], self.times[keep])


@dataclass
class TopicPayloads:
    """The messages of one topic in log-time order: log times (ns), lengths, and where their bytes lie."""

    topic: str
    type: str
    log_time: npt.NDArray[np.int64]
    lengths: npt.NDArray[np.int64]
    segments: list[tuple[Segment, npt.NDArray[np.int64]]]  # (segment, its payloads' rows in time order)

    def matrix(self, length: int, rows: npt.NDArray[np.int64]) -> npt.NDArray[np.uint8]:
        """Return the payloads of ``rows`` (all ``length`` bytes long, sorted) as a (rows, length) matrix."""
        out = np.empty((len(rows), length), dtype=np.uint8)
        for segment, seg_rows in self.segments:
            mask = segment.lengths == length
            if not mask.any():
                continue
            window = np.lib.stride_tricks.sliding_window_view(segment.buf, length)
            out[np.searchsorted(rows, seg_rows[mask])] = window[segment.starts[mask]]
        return out


def gather(reader: Any, topics: Iterable[str], start: int | None = None,
           end: int | None = None) -> dict[str, TopicPayloads]:
    """Collect where the payloads of ``topics`` lie in the intact chunks of the bag (one pass over the files).

    Messages are found through each chunk's message index (checked against the records it points
    to); a chunk without a usable index is walked record by record.
    """
    wanted = list(dict.fromkeys(topics))
    reader.check_topics(wanted)
    lo = start if start is not None else 0
    hi = end if end is not None else 2**64 - 1
    parts: dict[str, list[Segment]] = {t: [] for t in wanted}
    cache = getattr(reader, 'chunk_cache', None)
    for result in reader.scans:
        by_id = {c.id: c.topic for c in result.channels.values() if c.topic in parts}
        loose: dict[str, tuple[list[bytes], list[int]]] = {}
        for m in result.loose:
            if m.channel_id in by_id and lo <= m.log_time <= hi:
                entry = loose.setdefault(by_id[m.channel_id], ([], []))
                entry[0].append(m.data)
                entry[1].append(m.log_time)
        for topic, (payloads, loose_times) in loose.items():
            parts[topic].append(Segment.of(payloads, loose_times))
        for chunks, streaming in _batches(result, start, end, cache):
            found = _from_index(result, chunks, by_id)
            if found is None:
                found = _from_walk(result, chunks, by_id, set(parts))
            for topic, segment in found.items():
                parts[topic].append(segment.compact() if streaming else segment)
    out = {}
    for topic in wanted:
        segments = [seg if (start is None and end is None) else seg.select((seg.times >= lo) & (seg.times <= hi))
                    for seg in parts[topic]]
        times = np.concatenate([s.times for s in segments]) if segments else np.zeros(0, np.int64)
        lengths = np.concatenate([s.lengths for s in segments]) if segments else np.zeros(0, np.int64)
        rank = np.arange(len(times))
        if len(times) > 1 and np.any(np.diff(times) < 0):
            order = np.argsort(times, kind='stable')
            rank = np.empty(len(times), dtype=np.int64)
            rank[order] = np.arange(len(times))
            times, lengths = times[order], lengths[order]
        placed, at = [], 0
        for segment in segments:
            placed.append((segment, rank[at:at + len(segment.times)]))
            at += len(segment.times)
        out[topic] = TopicPayloads(topic, reader.topics[topic].type, times, lengths, placed)
    return out


_U64 = np.arange(8)


def _field(buf: npt.NDArray[np.uint8], at: npt.NDArray[np.int64], size: int) -> npt.NDArray[Any]:
    """Return the little-endian unsigned integers of ``size`` bytes at offsets ``at`` of ``buf``."""
    raw = np.lib.stride_tricks.sliding_window_view(buf, size)[at]
    return raw.view({2: '<u2', 8: '<u8'}[size]).ravel()


@dataclass
class _FileChunks:
    """The intact chunks of one file, decompressed and joined: their refs, the bytes, where each starts."""

    refs: list[mcapfile.ChunkRef]
    joined: bytes
    bases: list[int]


#: Decompressed bytes of one file handled at once; a larger file is read in batches of this size and
#: only the wanted payloads of each batch are kept (memory stays bounded for long recordings).
BATCH_BYTES = 256 * 2**20


def _joined(pairs: list[tuple[mcapfile.ChunkRef, bytes]]) -> _FileChunks:
    """Join decompressed chunks into one buffer."""
    bases = [0]
    for _, data in pairs:
        bases.append(bases[-1] + len(data))
    return _FileChunks([ref for ref, _ in pairs], b''.join(data for _, data in pairs), bases)


def _batches(result: mcapfile.McapScan, start: int | None, end: int | None,
             cache: Any) -> Iterator[tuple[_FileChunks, bool]]:
    """Yield (checked, decompressed chunks joined, streaming) of ``result`` in read order.

    A file whose chunks decompress to at most BATCH_BYTES comes as one batch (kept in ``cache`` for
    the next call when it fits); a larger one in batches of about BATCH_BYTES (streaming: the caller
    must copy what it keeps out of each batch).
    """
    key = ('joined', result.path, start, end)
    if cache is not None and key in cache.data:
        yield cache.data[key], False
        return
    streaming = sum(ref.uncompressed_size for ref in result.chunks) > BATCH_BYTES
    pairs: list[tuple[mcapfile.ChunkRef, bytes]] = []
    size = 0
    for ref, data in mcapfile.iter_chunk_data(result, start, end):
        pairs.append((ref, data))
        size += len(data)
        if streaming and size >= BATCH_BYTES:
            yield _joined(pairs), True
            pairs, size = [], 0
    if streaming:
        if pairs:
            yield _joined(pairs), True
        return
    chunks = _joined(pairs)
    if cache is not None and cache.used + len(chunks.joined) <= cache.budget:
        cache.data[key] = chunks
        cache.used += len(chunks.joined)
    yield chunks, False


def _from_index(result: mcapfile.McapScan, chunks: _FileChunks, by_id: dict[int, str]) -> dict[str, Segment] | None:
    """Find the wanted messages through the chunks' message indexes; None if an index is missing or wrong."""
    if not chunks.refs or any(not ref.index_records for ref in chunks.refs):
        return None if chunks.refs else {}
    bases = chunks.bases
    buf = np.frombuffer(chunks.joined, dtype=np.uint8)
    found: dict[str, list[tuple[Any, Any, Any]]] = {}
    with open(result.path, 'rb') as handle:
        for channel, topic in by_id.items():
            offsets, times, limits = [], [], []
            for ref, base, limit in zip(chunks.refs, bases[:-1], bases[1:], strict=True):
                entry = ref.index_records.get(channel)
                if entry is None:
                    continue
                handle.seek(entry[1])
                raw = handle.read(entry[2])
                if len(raw) != entry[2]:
                    return None
                pairs = np.frombuffer(raw, dtype='<u8').reshape(-1, 2)
                if limit - base < 31 or np.any(pairs[:, 1] > np.uint64(limit - base - 31)):
                    return None  # an entry pointing outside its chunk: the index is damaged
                times.append(pairs[:, 0])
                offsets.append(pairs[:, 1].astype(np.int64) + base)
                limits.append(np.full(len(pairs), limit, dtype=np.int64))
            if not offsets:
                continue
            at = np.concatenate(offsets)
            stamp = np.concatenate(times)
            limit_at = np.concatenate(limits)
            length = _field(buf, at + 1, 8).astype(np.int64)
            good = ((buf[at] == 5) & (_field(buf, at + 9, 2) == channel) & (_field(buf, at + 15, 8) == stamp)
                    & (length >= 22) & (length <= limit_at - at - 9))
            if not np.all(good):
                return None
            found.setdefault(topic, []).append((at, stamp.astype(np.int64), length - 22))
    out = {}
    for topic, pieces in found.items():
        at = np.concatenate([p[0] for p in pieces])
        stamp = np.concatenate([p[1] for p in pieces])
        size = np.concatenate([p[2] for p in pieces])
        order = np.lexsort((at, stamp))  # log time, then place in the file: the reader's order
        out[topic] = Segment(buf, at[order] + 31, size[order], stamp[order])
    return out


def _from_walk(result: mcapfile.McapScan, chunks: _FileChunks,
               by_id: dict[int, str], wanted: set[str]) -> dict[str, Segment]:
    """Find the wanted messages by walking the records of every chunk."""
    times: dict[str, list[int]] = {t: [] for t in wanted}
    data: dict[str, list[Any]] = {t: [] for t in wanted}
    for ref, base, limit in zip(chunks.refs, chunks.bases[:-1], chunks.bases[1:], strict=True):
        try:
            _walk(chunks.joined[base:limit], by_id, times, data, result, ref)
        except mcapfile.RECORD_ERRORS as err:
            result.mark_damaged(ref, f'records do not add up: {err}')
        except mcapfile.ChunkDamaged as err:
            result.mark_damaged(ref, f'records do not add up: {err}')
    return {t: Segment.of(data[t], times[t]) for t in times if times[t]}


def _walk(chunk: bytes, by_id: dict[int, str], times: dict[str, list[int]], data: dict[str, list[Any]],
          result: mcapfile.McapScan, ref: mcapfile.ChunkRef) -> None:
    """Append the wanted messages of one decompressed chunk to ``times``/``data`` (channels learnt too)."""
    pos, size = 0, len(chunk)
    unpack = _HEAD.unpack_from
    while pos < size:
        if pos + 23 > size:
            list(mcapfile.walk_chunk(chunk[pos:]))  # raises ChunkDamaged if really cut off
            return
        opcode, length, channel, _, log_time = unpack(chunk, pos)
        if opcode == 5:
            topic = by_id.get(channel)
            if topic is not None:
                times[topic].append(log_time)
                data[topic].append(chunk[pos + 31:pos + 9 + length])
        elif opcode == 4 and channel not in by_id:  # a Channel record inside the chunk
            record = mcapfile.Channel.read(mcapfile._stream(chunk[pos + 9:pos + 9 + length]))
            result.channels.setdefault(record.id, record)
            if record.topic in times:
                by_id[record.id] = record.topic
        pos += 9 + length
    if pos != size:
        raise mcapfile.ChunkDamaged('the last record runs past the end of the chunk')


# -- layouts: where the fields of one message sit ------------------------------------------------


class _Cursor:
    """Reads CDR from one message (after its 4-byte encapsulation header), noting structural bytes."""

    def __init__(self, payload: bytes) -> None:
        if len(payload) < 4 or payload[0] != 0 or payload[1] not in (0, 1):
            raise LayoutError('not plain CDR (encapsulation header)')
        self.data = payload
        self.endian = '<' if payload[1] == 1 else '>'
        self.pos = 0  # relative to the body (alignment is relative to it)
        self.key: list[tuple[int, int]] = [(0, 4)]

    def align(self, size: int) -> None:
        """Skip the padding before a value of ``size`` bytes."""
        self.pos = (self.pos + size - 1) & -size

    def take(self, size: int) -> int:
        """Return the absolute offset of the next ``size`` bytes and move past them."""
        at = 4 + self.pos
        if at + size > len(self.data):
            raise LayoutError(f'message ends at byte {len(self.data)}, field needs {at + size}')
        self.pos += size
        return at

    def count(self) -> int:
        """Read a uint32 sequence or string length (a structural value)."""
        self.align(4)
        at = self.take(4)
        self.key.append((at, at + 4))
        return int(struct.unpack_from(self.endian + 'I', self.data, at)[0])

    def string(self) -> str:
        """Read a string (structural: its bytes are part of the layout key)."""
        size = self.count()
        at = self.take(size)
        self.key.append((at, at + size))
        raw = self.data[at:at + size]
        return raw[:-1].decode() if raw.endswith(b'\x00') else raw.decode()

    def array(self, size: int, count: int) -> tuple[int, int]:
        """Return (offset, count) of ``count`` values of ``size`` bytes, aligned as CDR does."""
        if count:
            self.align(size)
        return self.take(size * count), count

    def stamp(self) -> int:
        """Return the offset of a builtin_interfaces/Time (int32 sec, uint32 nanosec)."""
        self.align(4)
        return self.take(8)


@dataclass
class Layout:
    """Where the fields of a message sit: the structural byte spans, a structured dtype and extras."""

    key: list[tuple[int, int]]
    dtype: np.dtype[Any]
    names: tuple[str, ...] = ()
    counts: dict[str, int] = field(default_factory=dict)


_Fields = dict[str, tuple[int, str, tuple[int, ...]]]


def _dtype(length: int, endian: str, fields: _Fields) -> np.dtype[Any]:
    """Return a structured dtype of ``length`` bytes with ``fields`` = name -> (offset, type, shape)."""
    names = list(fields)
    return np.dtype({'names': names,
                     'formats': [(endian + fields[n][1], fields[n][2]) if fields[n][2] else endian + fields[n][1]
                                 for n in names],
                     'offsets': [fields[n][0] for n in names], 'itemsize': length})


def _trailing(cur: _Cursor, payload: bytes) -> None:
    """Raise LayoutError if more than 8 bytes follow the message (rclpy pads some by up to 8)."""
    extra = len(payload) - 4 - cur.pos
    if extra > 8:
        raise LayoutError(f'{extra} bytes after the end of the message')


def pose_array_layout(payload: bytes) -> Layout:
    """Parse one PoseArray: header stamp, frame id, and the poses as (count, 7) float64."""
    cur = _Cursor(payload)
    stamp = cur.stamp()
    cur.string()
    count = cur.count()
    poses, _ = cur.array(8, count * 7)
    _trailing(cur, payload)
    fields: _Fields = {'sec': (stamp, 'i4', ()), 'nanosec': (stamp + 4, 'u4', ())}
    if count:
        fields['poses'] = (poses, 'f8', (count, 7))
    return Layout(cur.key, _dtype(len(payload), cur.endian, fields), counts={'poses': count})


def joint_state_layout(payload: bytes) -> Layout:
    """Parse one JointState: header stamp, frame id, names, and position, velocity, effort arrays."""
    cur = _Cursor(payload)
    stamp = cur.stamp()
    cur.string()
    names = tuple(cur.string() for _ in range(cur.count()))
    fields: _Fields = {'sec': (stamp, 'i4', ()), 'nanosec': (stamp + 4, 'u4', ())}
    counts = {}
    for name in ('position', 'velocity', 'effort'):
        at, count = cur.array(8, cur.count())
        counts[name] = count
        if count:
            fields[name] = (at, 'f8', (count,))
    _trailing(cur, payload)
    return Layout(cur.key, _dtype(len(payload), cur.endian, fields), names, counts)


def clock_layout(payload: bytes) -> Layout:
    """Parse one Clock message: its time."""
    cur = _Cursor(payload)
    stamp = cur.stamp()
    fields: _Fields = {'sec': (stamp, 'i4', ()), 'nanosec': (stamp + 4, 'u4', ())}
    return Layout(cur.key, _dtype(len(payload), cur.endian, fields))


LAYOUTS: dict[str, Callable[[bytes], Layout]] = {
    POSE_ARRAY: pose_array_layout, JOINT_STATE: joint_state_layout, CLOCK: clock_layout}


@dataclass
class Group:
    """Messages of one layout: their row numbers in the topic (time order), the layout and the values."""

    rows: npt.NDArray[np.int64]
    layout: Layout
    values: np.ndarray[Any, Any]


def decode_groups(item: TopicPayloads) -> list[Group]:
    """Decode every message of a topic, grouped by layout; undecodable ones are skipped with a warning."""
    parse = LAYOUTS.get(item.type)
    if parse is None:
        raise BagError(f'{item.topic}: columnar decoding supports {", ".join(TYPES)}, not {item.type}')
    groups: list[Group] = []
    skipped = 0
    for length in np.unique(item.lengths):
        rows = np.flatnonzero(item.lengths == length)
        matrix = item.matrix(int(length), rows)
        pending = np.arange(len(rows))
        templates = 0
        while len(pending):
            first = int(pending[0])
            try:
                layout = parse(matrix[first].tobytes())
            except (LayoutError, UnicodeDecodeError, struct.error) as err:
                skipped += 1
                _LOG.warning('%s at t=%d: cannot decode %s message (%s); skipped', item.topic,
                             int(item.log_time[rows[first]]), item.type, err)
                pending = pending[1:]
                continue
            templates += 1
            if templates > _MAX_TEMPLATES:  # every message its own layout: decode them one by one
                match = np.zeros(len(pending), dtype=bool)
                match[0] = True
            else:
                columns = np.concatenate([np.arange(a, b) for a, b in layout.key])
                match = np.all(matrix[:, columns][pending] == matrix[first, columns], axis=1)
            chosen = pending[match]
            records = np.ascontiguousarray(matrix[chosen]).view(layout.dtype)[:, 0]
            groups.append(Group(rows[chosen], layout, records))
            pending = pending[~match]
    if skipped:
        _LOG.warning('%s: %d messages could not be decoded', item.topic, skipped)
    return groups


def stamps_of(groups: list[Group], count: int) -> npt.NDArray[np.float64]:
    """Return the header stamps (s) of the decoded rows, NaN where a row was not decoded."""
    stamp = np.full(count, np.nan)
    for group in groups:
        stamp[group.rows] = group.values['sec'].astype(np.float64) + 1e-9 * group.values['nanosec'].astype(
            np.float64)
    return stamp


def decoded_rows(groups: list[Group]) -> npt.NDArray[np.int64]:
    """Return the sorted row numbers that were decoded."""
    if not groups:
        return np.zeros(0, dtype=np.int64)
    return np.sort(np.concatenate([g.rows for g in groups]))
