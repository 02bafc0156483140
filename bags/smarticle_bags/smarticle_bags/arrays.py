"""Offline analysis input: the smarticle topics of a bag as NumPy arrays (no ROS needed).

Times come twice: ``log_time`` (when the recorder received the message) and ``stamp`` (the
message's header stamp; sim time in simulation), both in seconds as float64.

Poses, JointState topics (joint states, commands, FSR) and the clock are decoded column-wise, whole
chunks at a time (``columnar``); ``columnar=False`` decodes message by message with ``mcap_ros2``
(the same values, several times slower). Other types always go message by message.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable

import numpy as np
import numpy.typing as npt

from smarticle_common.poses import quaternion_heading, quaternion_headings
from smarticle_common import topics as contract

from . import columnar as col
from .reader import BagReader

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class PoseSeries:
    """Planar poses of all robots: ``xyh[t, robot] = (x, y, heading)`` in m, m, rad (NaN if missing)."""

    log_time: FloatArray
    stamp: FloatArray
    xyh: FloatArray


@dataclass(frozen=True)
class JointSeries:
    """JointState samples: one column per name, NaN where a message lacks that name or field."""

    names: tuple[str, ...]
    log_time: FloatArray
    stamp: FloatArray
    position: FloatArray
    velocity: FloatArray
    effort: FloatArray


@dataclass(frozen=True)
class ClockSeries:
    """The /clock topic: when each message was logged and the time it carries (both in s)."""

    log_time: FloatArray
    clock: FloatArray


@dataclass(frozen=True)
class DiagnosticsTable:
    """One row per DiagnosticStatus: times, name, hardware id, level, message, and its key/values."""

    log_time: FloatArray
    stamp: FloatArray
    name: npt.NDArray[np.str_]
    hardware_id: npt.NDArray[np.str_]
    level: npt.NDArray[np.int64]
    message: npt.NDArray[np.str_]
    values: dict[str, npt.NDArray[Any]]


def _stamp(msg: Any) -> float:
    """Return the header stamp of a decoded message in seconds."""
    return float(msg.header.stamp.sec) + 1e-9 * float(msg.header.stamp.nanosec)


def _planar(pose: Any) -> tuple[float, float, float]:
    """(x, y, heading) of a decoded Pose; NaN for the contract's unseen pose (``topics.UNSEEN_Z``)."""
    p, q = pose.position, pose.orientation
    if p.z == contract.UNSEEN_Z:
        return (math.nan, math.nan, math.nan)
    return (p.x, p.y, quaternion_heading(q.x, q.y, q.z, q.w))


def poses_from_messages(items: Iterable[tuple[int, Any]]) -> PoseSeries:
    """Build a PoseSeries from (log time ns, decoded PoseArray) pairs; unseen and missing robots are NaN."""
    rows: list[list[tuple[float, float, float]]] = []
    log_time: list[float] = []
    stamp: list[float] = []
    for log_ns, msg in items:
        log_time.append(log_ns * 1e-9)
        stamp.append(_stamp(msg))
        rows.append([_planar(p) for p in msg.poses])
    width = max((len(r) for r in rows), default=0)
    xyh = np.full((len(rows), width, 3), np.nan)
    for t, row in enumerate(rows):
        if row:
            xyh[t, :len(row)] = row
    return PoseSeries(np.array(log_time), np.array(stamp), xyh)


def joints_from_messages(items: Iterable[tuple[int, Any]]) -> JointSeries:
    """Build a JointSeries from (log time ns, decoded JointState) pairs (columns in first-seen order)."""
    names: list[str] = []
    samples: list[tuple[float, float, dict[str, tuple[float, float, float]]]] = []
    for log_ns, msg in items:
        values: dict[str, tuple[float, float, float]] = {}
        for i, name in enumerate(msg.name):
            if name not in names:
                names.append(name)
            values[name] = tuple(  # type: ignore[assignment]
                float(field[i]) if i < len(field) else math.nan
                for field in (msg.position, msg.velocity, msg.effort))
        samples.append((log_ns * 1e-9, _stamp(msg), values))
    data = np.full((3, len(samples), len(names)), np.nan)
    for t, (_, _, values) in enumerate(samples):
        for j, name in enumerate(names):
            if name in values:
                data[:, t, j] = values[name]
    return JointSeries(tuple(names), np.array([s[0] for s in samples]), np.array([s[1] for s in samples]),
                       data[0], data[1], data[2])


def _column(values: list[str]) -> npt.NDArray[Any]:
    """Return a float column if every non-empty value parses as a number, else a string column."""
    try:
        return np.array([float(v) if v != '' else math.nan for v in values])
    except ValueError:
        return np.array(values, dtype=str)


def diagnostics_from_messages(items: Iterable[tuple[int, Any]]) -> DiagnosticsTable:
    """Flatten (log time ns, decoded DiagnosticArray) pairs into one row per status."""
    rows: list[tuple[float, float, Any]] = []
    for log_ns, msg in items:
        for status in msg.status:
            rows.append((log_ns * 1e-9, _stamp(msg), status))
    keys: list[str] = []
    for _, _, status in rows:
        for kv in status.values:
            if kv.key not in keys:
                keys.append(kv.key)
    values = {key: _column([next((kv.value for kv in s.values if kv.key == key), '') for _, _, s in rows])
              for key in keys}
    return DiagnosticsTable(
        np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
        np.array([r[2].name for r in rows], dtype=str), np.array([r[2].hardware_id for r in rows], dtype=str),
        np.array([int.from_bytes(r[2].level, 'little') if isinstance(r[2].level, bytes) else int(r[2].level)
                  for r in rows], dtype=np.int64),
        np.array([r[2].message for r in rows], dtype=str), values)


def _decoded(reader: BagReader, topic: str) -> list[tuple[int, Any]]:
    """Return (log time, decoded message) pairs of one topic of the bag."""
    return [(raw.log_time, msg) for raw, msg in reader.decoded([topic])]


def _seconds(ns: npt.NDArray[np.int64]) -> FloatArray:
    """Return nanosecond times as float64 seconds (as ``ns * 1e-9`` per message does)."""
    return ns.astype(np.float64) * 1e-9


def _columnar_ok(reader: BagReader, topics: Iterable[str], type_name: str) -> bool:
    """True if every topic exists and has ``type_name`` (else the per-message path is used)."""
    reader.check_topics(topics)
    return all(reader.topics[t].type == type_name for t in topics)


def poses_from_groups(item: col.TopicPayloads, groups: list[col.Group]) -> PoseSeries:
    """Build a PoseSeries from the columnar groups of a PoseArray topic."""
    rows = col.decoded_rows(groups)
    width = max((g.layout.counts['poses'] for g in groups), default=0)
    xyh = np.full((len(rows), width, 3), np.nan)
    stamp = col.stamps_of(groups, len(item.log_time))[rows]
    for group in groups:
        count = group.layout.counts['poses']
        if not count:
            continue
        at = np.searchsorted(rows, group.rows)
        poses = group.values['poses']
        qx, qy, qz, qw = poses[..., 3], poses[..., 4], poses[..., 5], poses[..., 6]
        unseen = poses[..., 2] == contract.UNSEEN_Z            # the contract's unseen pose: a NaN row
        xyh[at, :count, 0] = np.where(unseen, np.nan, poses[..., 0])
        xyh[at, :count, 1] = np.where(unseen, np.nan, poses[..., 1])
        xyh[at, :count, 2] = np.where(unseen, np.nan, quaternion_headings(qx, qy, qz, qw))
    return PoseSeries(_seconds(item.log_time[rows]), stamp, xyh)


def joints_from_groups(item: col.TopicPayloads, groups: list[col.Group]) -> JointSeries:
    """Build a JointSeries from the columnar groups of a JointState topic (columns in first-seen order)."""
    rows = col.decoded_rows(groups)
    names: list[str] = []
    for group in sorted(groups, key=lambda g: int(g.rows[0])):
        names += [n for n in group.layout.names if n not in names]
    column = {name: j for j, name in enumerate(names)}
    data = np.full((3, len(rows), len(names)), np.nan)
    for group in groups:
        at = np.searchsorted(rows, group.rows)
        for i, name in enumerate(group.layout.names):
            for f, key in enumerate(('position', 'velocity', 'effort')):
                if i < group.layout.counts[key]:
                    data[f, at, column[name]] = group.values[key][:, i]
                else:
                    data[f, at, column[name]] = np.nan
    stamp = col.stamps_of(groups, len(item.log_time))[rows]
    return JointSeries(tuple(names), _seconds(item.log_time[rows]), stamp, data[0], data[1], data[2])


def read_poses(reader: BagReader, topic: str = contract.topic('poses'), columnar: bool = True) -> PoseSeries:
    """Return the PoseArray topic (default ``/smarticles/poses``) as (T, N, 3) x, y, heading."""
    if columnar and _columnar_ok(reader, [topic], col.POSE_ARRAY):
        item = col.gather(reader, [topic])[topic]
        return poses_from_groups(item, col.decode_groups(item))
    return poses_from_messages(_decoded(reader, topic))


def read_joints(reader: BagReader, topic: str, columnar: bool = True) -> JointSeries:
    """Return a JointState topic (joint states, joint commands or FSR) as arrays."""
    if columnar and _columnar_ok(reader, [topic], col.JOINT_STATE):
        item = col.gather(reader, [topic])[topic]
        return joints_from_groups(item, col.decode_groups(item))
    return joints_from_messages(_decoded(reader, topic))


def read_clock(reader: BagReader, topic: str = '/clock') -> ClockSeries:
    """Return a rosgraph_msgs/Clock topic: log time and clock time, in seconds."""
    reader.check_topics([topic])
    item = col.gather(reader, [topic])[topic]
    groups = col.decode_groups(item)
    rows = col.decoded_rows(groups)
    return ClockSeries(_seconds(item.log_time[rows]), col.stamps_of(groups, len(item.log_time))[rows])


def read_robot_topic(reader: BagReader, key: str, columnar: bool = True) -> dict[int, JointSeries]:
    """Return a per-robot JointState topic (``joint_states``, ``joint_commands``, ``fsr``) for every robot."""
    contract.spec_of(key)
    robots: dict[str, int] = {}
    for name in sorted(reader.topics):
        parsed = contract.parse_robot_topic(name)
        if parsed is not None and parsed[1] == key:
            robots[name] = parsed[0]
    order = sorted(robots, key=robots.__getitem__)
    if columnar and _columnar_ok(reader, robots, col.JOINT_STATE):
        gathered = col.gather(reader, list(robots))  # one pass over the bag for all robots
        return {robots[name]: joints_from_groups(gathered[name], col.decode_groups(gathered[name]))
                for name in order}
    items: dict[str, list[tuple[int, Any]]] = {name: [] for name in robots}
    if robots:  # one pass over the bag for all robots (each pass decompresses every chunk)
        for raw, msg in reader.decoded(list(robots)):
            items[raw.topic].append((raw.log_time, msg))
    return {robots[name]: joints_from_messages(items[name]) for name in order}


def read_fsr(reader: BagReader, columnar: bool = True) -> dict[int, JointSeries]:
    """Return the FSR forces of every robot (``effort`` columns, in N, named by face)."""
    return read_robot_topic(reader, 'fsr', columnar)


def read_gliders(reader: BagReader, topic: str = contract.topic('gliders')) -> DiagnosticsTable:
    """Return the glider monitor's DiagnosticArray topic as one row per bound pair and time."""
    return diagnostics_from_messages(_decoded(reader, topic))
