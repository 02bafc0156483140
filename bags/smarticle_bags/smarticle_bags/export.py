"""``smarticle-bag export``: one CSV file per topic, in SI units and radians.

PoseArray topics become long tables (one row per robot and time: x, y, heading); JointState topics
wide tables (position/velocity/effort per joint name); DiagnosticArray topics one row per status
with its key/values as columns; other types are flattened field by field (short numeric arrays
as ``field[i]``); fields that do not fit a table (images, long arrays) are left out.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from . import arrays
from .errors import BagError
from .reader import BagReader

MAX_ARRAY = 16


@dataclass
class ExportReport:
    """Files written and topics skipped (with the reason)."""

    written: dict[str, Path] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)


def csv_name(topic: str) -> str:
    """Return the CSV file name of a topic: ``/smarticle_0/fsr`` -> ``smarticle_0__fsr.csv``."""
    return topic.strip('/').replace('/', '__') + '.csv'


def _flatten(prefix: str, value: Any, out: dict[str, Any]) -> bool:
    """Flatten a decoded message into scalar columns; return False if it does not fit a table."""
    if isinstance(value, (bool, int, float, str)):
        out[prefix] = value
        return True
    if isinstance(value, (bytes, bytearray, list, tuple)):
        if len(value) > MAX_ARRAY:
            return False
        for i, item in enumerate(value):
            if not _flatten(f'{prefix}[{i}]', item, out):
                return False
        return True
    slots = getattr(value, '__slots__', None)
    if slots is None:
        return False
    return all(_flatten(f'{prefix}.{name}' if prefix else name, getattr(value, name), out) for name in slots)


def _write(path: Path, header: list[str], rows: Iterable[list[Any]]) -> None:
    """Write one CSV file."""
    with open(path, 'w', newline='', encoding='utf-8') as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)


def export_topic(reader: BagReader, topic: str, type_name: str, path: Path) -> str | None:
    """Write one topic to ``path``; return the reason when it cannot be exported."""
    items = [(raw.log_time, msg) for raw, msg in reader.decoded([topic])]
    if type_name == 'geometry_msgs/msg/PoseArray':
        poses = arrays.poses_from_messages(items)
        _write(path, ['log_time', 'stamp', 'robot', 'x', 'y', 'heading'],
               ([f'{poses.log_time[t]:.9f}', f'{poses.stamp[t]:.9f}', k, *poses.xyh[t, k]]
                for t in range(len(poses.log_time)) for k in range(poses.xyh.shape[1])))
    elif type_name == 'sensor_msgs/msg/JointState':
        joints = arrays.joints_from_messages(items)
        header = ['log_time', 'stamp'] + [f'{kind}_{n}' for kind in ('position', 'velocity', 'effort')
                                           for n in joints.names]
        _write(path, header, ([f'{joints.log_time[t]:.9f}', f'{joints.stamp[t]:.9f}', *joints.position[t],
                               *joints.velocity[t], *joints.effort[t]] for t in range(len(joints.log_time))))
    elif type_name == 'diagnostic_msgs/msg/DiagnosticArray':
        table = arrays.diagnostics_from_messages(items)
        keys = list(table.values)
        _write(path, ['log_time', 'stamp', 'name', 'hardware_id', 'level', 'message', *keys],
               ([f'{table.log_time[i]:.9f}', f'{table.stamp[i]:.9f}', table.name[i], table.hardware_id[i],
                 table.level[i], table.message[i], *(table.values[k][i] for k in keys)]
                for i in range(len(table.log_time))))
    else:
        rows: list[dict[str, Any]] = []
        for log_time, msg in items:
            flat: dict[str, Any] = {'log_time': f'{log_time * 1e-9:.9f}'}
            if not _flatten('', msg, flat):
                return f'{type_name} has fields too large for a table'
            rows.append(flat)
        header = list(dict.fromkeys(k for row in rows for k in row))
        _write(path, header or ['log_time'], ([row.get(k, '') for k in header] for row in rows))
    return None


def export_bag(reader: BagReader, out: Path, topics: Iterable[str] | None = None) -> ExportReport:
    """Export the chosen topics (all if None) of a bag to CSV files in folder ``out``."""
    chosen = list(topics) if topics is not None else sorted(reader.topics)
    reader.check_topics(chosen)
    out.mkdir(parents=True, exist_ok=True)
    report = ExportReport()
    for topic in chosen:
        path = out / csv_name(topic)
        reason = export_topic(reader, topic, reader.topics[topic].type, path)
        if reason is None:
            report.written[topic] = path
        else:
            path.unlink(missing_ok=True)
            report.skipped[topic] = reason
    return report


def export_run(reader: BagReader, path: Path, topic: str = '/smarticles/poses') -> Path:
    """Write ``topic``'s poses as a run file (``smarticle_common.runs``, the batch and demo format)."""
    from smarticle_common.facts import BODY_LENGTH
    from smarticle_common.runs import Recording, save_npz

    poses = arrays.read_poses(reader, topic)
    if len(poses.stamp) == 0:
        raise BagError(f'{topic}: no pose messages to export')
    run = Recording.from_poses(poses.stamp - poses.stamp[0], poses.xyh, BODY_LENGTH,
                               {'source': f'bag {reader.path}, topic {topic}', 'stamp0': float(poses.stamp[0])})
    return save_npz(run, path)
