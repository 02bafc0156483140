"""The text of ``smarticle-bag info``, laid out like ``ros2 bag info``."""

from __future__ import annotations

import time

from .reader import BagReader
from .timebase import describe


def human_size(size: int) -> str:
    """Return a byte count as rosbag2 prints it (B, KiB, MiB, GiB)."""
    value = float(size)
    for unit in ('B', 'KiB', 'MiB', 'GiB'):
        if value < 1024.0 or unit == 'GiB':
            return f'{value:.0f} {unit}' if unit == 'B' else f'{value:.1f} {unit}'
        value /= 1024.0
    return f'{value:.1f} GiB'


def format_time(ns: int) -> str:
    """Return a time as ``Jan 26 2024 15:53:26.190000000 (1706280806.190000000)`` in local time."""
    sec, nsec = divmod(ns, 1_000_000_000)
    return f'{time.strftime("%b %d %Y %H:%M:%S", time.localtime(sec))}.{nsec:09d} ({sec}.{nsec:09d})'


def format_info(reader: BagReader) -> str:
    """Return the ``ros2 bag info``-style description of an open bag (with any damage noted)."""
    info = reader.info
    size = sum(s.size for s in reader.scans)
    pad = ' ' * 19
    files = ('\n' + pad).join(f.path for f in info.files)
    topics = sorted(info.topics, key=lambda t: t.name)
    width_name = max((len(t.name) for t in topics), default=0)
    width_type = max((len(t.type) for t in topics), default=0)
    lines = [
        '',
        f'Files:             {files}',
        f'Bag size:          {human_size(size)}',
        f'Storage id:        {info.storage_identifier}',
        f'ROS Distro:        {info.ros_distro or "unknown"}',
        f'Duration:          {info.duration // 1_000_000_000}.{info.duration % 1_000_000_000:09d}s',
        f'Start:             {format_time(info.starting_time)}',
        f'End:               {format_time(info.end_time)}',
        f'Messages:          {info.message_count}',
        f'Log time:          {describe(info)}',
    ]
    custom = info.custom_data or {}
    if 'imported_from' in custom:
        lines.append(f'Imported from:     {custom["imported_from"]} ({custom.get("import_units", "")})')
    topic_lines = [f'Topic: {t.name:<{width_name}} | Type: {t.type:<{width_type}} | '
                   f'Count: {t.message_count} | '
                   f'Serialization Format: {t.serialization_format}' for t in topics]
    lines.append('Topic information: ' + ('\n' + pad).join(topic_lines))
    lines += ['Service:           0', 'Service information: ']
    if reader.problems:
        lines.append('')
        lines += [f'WARNING: {p}' for p in reader.problems]
        lines.append('WARNING: the counts above come from metadata; '
                     'run "smarticle-bag reindex" to repair the bag')
    return '\n'.join(lines) + '\n'


def format_check(reader: BagReader) -> tuple[str, bool]:
    """Return the ``smarticle-bag check`` text of a bag opened with ``verify=True`` and whether it is intact."""
    lines = []
    intact = True
    for result in reader.scans:
        chunks = len(result.chunks) + len(result.damaged)
        if not result.problems:
            lines.append(f'{result.path}: OK: {result.message_count} messages in {chunks} chunks, '
                         f'every CRC and record checked')
            continue
        intact = False
        lines.append(f'{result.path}: DAMAGED: {len(result.damaged)} of {chunks} chunks damaged, '
                     f'{result.message_count} messages readable')
        for damaged in result.damaged:
            lines.append(f'  {damaged.describe()}')
        lines += [f'  {p}' for p in result.problems if not (p.startswith('chunk at byte') and 'is damaged' in p)]
    if reader.path.is_dir():
        listed = {f.path: f.message_count for f in reader.info.files}
        for result in reader.scans:
            name = result.path.relative_to(reader.path).as_posix()
            if not result.problems and listed.get(name, result.message_count) != result.message_count:
                intact = False
                lines.append(f'{reader.path / "metadata.yaml"}: says {listed[name]} messages for {name}, the '
                             f'file holds {result.message_count}')
    lines += [f'{p}' for p in reader.unreadable]
    intact = intact and not reader.unreadable
    if not intact:
        lines.append(f'run "smarticle-bag reindex {reader.path}" to salvage the intact chunks')
    return '\n'.join(lines) + '\n', intact
