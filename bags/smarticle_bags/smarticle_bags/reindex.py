"""Rebuild a bag folder's ``metadata.yaml`` from its .mcap files, salvaging damaged ones.

Every file is checked in full (each chunk's CRC, every record). A healthy bag only gets a new
``metadata.yaml``. A damaged file (no footer, a cut-off or damaged record, a chunk that fails its CRC)
is rewritten as a complete .mcap from its intact chunks alone, with schemas and channels from their
first intact copy. By default the repaired bag goes to a new folder beside the original
(``<bag>.repaired``, the original folder is not touched); with ``replace=True`` the repaired file
takes the original's place and the original is kept as ``<name>.mcap.damaged``. Either way
``reindex_report.txt`` in the output folder lists what was found and what was dropped.
"""

from __future__ import annotations

import os
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from collections import Counter

from mcap.records import Channel, Schema
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter
from mcap_ros2._dynamic import generate_dynamic

from . import mcapfile, msgdefs
from .errors import BagError, BagNotFoundError, CorruptBagError, MetadataError
from .metadata import METADATA_FILE, BagInfo, read_metadata, write_metadata
from .reader import info_from_scans
from .writer import LIBRARY

DAMAGED_SUFFIX = '.damaged'
REPAIRED_SUFFIX = '.repaired'
REPORT_FILE = 'reindex_report.txt'


@dataclass
class ReindexReport:
    """What reindex did: the new metadata, where it went, the files repaired, problems and losses."""

    info: BagInfo
    output: Path | None = None
    repaired: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)
    report_path: Path | None = None
    lost: Counter[str] = field(default_factory=Counter)
    lost_unknown: int = 0

    def lost_line(self) -> str:
        """One line: the messages lost in damaged chunks, per topic."""
        total = sum(self.lost.values())
        line = f'lost in damaged chunks: {total} messages'
        if total:
            line += ' (' + ', '.join(f'{t} {n}' for t, n in sorted(self.lost.items())) + ')'
        if self.lost_unknown:
            line += f', plus those of {self.lost_unknown} chunk(s) whose message index is gone too'
        return line

    def text(self) -> str:
        """Return the text of ``reindex_report.txt``."""
        lines = [f'reindex of {len(self.info.files)} file(s): {self.info.message_count} messages kept',
                 self.lost_line()]
        lines += [f'found: {p}' for p in self.problems]
        lines += [f'dropped: {d}' for d in self.dropped] or ['dropped: nothing']
        lines += [f'repaired: {r}' for r in self.repaired]
        for f in self.info.files:
            lines.append(f'kept: {f.path}: {f.message_count} messages')
        return '\n'.join(lines) + '\n'


def _natural_key(path: Path) -> list[object]:
    """Sort key that puts ``bag_2.mcap`` before ``bag_10.mcap``."""
    return [int(part) if part.isdigit() else part for part in re.split(r'(\d+)', path.name)]


def checked_schema(result: mcapfile.McapScan, schema: Schema, notes: list[str]) -> Schema | None:
    """Return ``schema`` if it can be trusted or parses, else the installed definition of its type, else None.

    A copy not covered by a CRC that held is parsed; a ``ros2msg`` text that does not parse is replaced by
    the installed definition of the type (noted in ``notes``), or dropped when the type is not installed.
    """
    if schema.encoding != 'ros2msg' or ('schemas', schema.id) in result.trusted:
        return schema
    try:
        generate_dynamic(schema.name, schema.data.decode())
        return schema
    except Exception as err:  # mcap_ros2's parser of a definition read from a damaged file
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
    try:
        text = msgdefs.full_definition(schema.name)
    except BagError:
        notes.append(f'{result.path.name}: the definition of {schema.name} (schema {schema.id}) is damaged '
                     f'({reason}) and the type is not installed; its messages are dropped')
        return None
    notes.append(f'{result.path.name}: the definition of {schema.name} (schema {schema.id}) is damaged '
                 f'({reason}); replaced by the installed definition')
    return Schema(id=schema.id, name=schema.name, encoding='ros2msg', data=text.encode())


def write_salvaged(result: mcapfile.McapScan, target: Path,
                   compression: CompressionType = CompressionType.ZSTD, notes: list[str] | None = None) -> int:
    """Write the intact messages of a scanned file to a new complete .mcap ``target``; return their count.

    Messages of channels without a usable schema are left out (and counted in ``notes``).
    """
    notes = notes if notes is not None else []
    schemas = {i: checked_schema(result, s, notes) for i, s in sorted(result.schemas.items())}
    skipped: Counter[str] = Counter()
    count = 0
    with open(target, 'xb') as handle:
        writer = McapWriter(handle, compression=compression, enable_data_crcs=True)
        writer.start(profile=result.profile or 'ros2', library=result.library or LIBRARY)
        schema_ids: dict[int, int] = {}
        channel_ids: dict[int, int] = {}

        def register(channel: Channel) -> int:
            schema = schemas.get(channel.schema_id)
            if schema is not None and schema.id not in schema_ids:
                schema_ids[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            channel_ids[channel.id] = writer.register_channel(
                channel.topic, channel.message_encoding, schema_ids.get(channel.schema_id, 0),
                dict(channel.metadata))
            return channel_ids[channel.id]

        for _, channel in sorted(result.channels.items()):
            register(channel)
        for channel, message in mcapfile.iter_messages(result):
            if channel.message_encoding == 'cdr' and schemas.get(channel.schema_id) is None:
                skipped[channel.topic] += 1
                continue
            new_id = channel_ids.get(channel.id)
            if new_id is None:  # learnt from inside a chunk
                new_id = register(channel)
            writer.add_message(new_id, message.log_time, message.data, message.publish_time, message.sequence)
            count += 1
        writer.finish()
    for topic, n in sorted(skipped.items()):
        notes.append(f'{result.path.name}: {n} messages of {topic} dropped (no usable message definition)')
    return count


def repair(result: mcapfile.McapScan, compression: CompressionType = CompressionType.ZSTD,
           notes: list[str] | None = None) -> Path:
    """Replace a damaged .mcap by a complete file of its intact messages; return the kept original."""
    path = result.path
    tmp = path.with_name(f'.{path.name}.repair')
    if tmp.exists():
        tmp.unlink()
    write_salvaged(result, tmp, compression, notes)
    original = _free(path.with_name(path.name + DAMAGED_SUFFIX))
    os.replace(path, original)
    os.replace(tmp, path)
    return original


def _free(path: Path) -> Path:
    """Return ``path``, or ``path.1``, ``path.2``... whichever does not exist yet."""
    candidate, counter = path, 1
    while candidate.exists():
        candidate = path.with_name(f'{path.name}.{counter}')
        counter += 1
    return candidate


def _dropped(result: mcapfile.McapScan) -> list[str]:
    """Describe what of a scanned file cannot be salvaged."""
    lines = [f'{result.path.name}: {d.describe()}' for d in result.damaged]
    lines += [f'{result.path.name}: {p}' for p in result.problems
              if not p.startswith('chunk at byte') or 'is damaged' not in p]
    return lines


def reindex(folder: Path | str, replace: bool = False, output: Path | str | None = None) -> ReindexReport:
    """Check every .mcap of bag ``folder`` and rebuild its metadata, salvaging damaged files.

    A healthy bag gets a new ``metadata.yaml`` in place. If a file is damaged the repaired bag is
    written to ``output`` (default ``<folder>.repaired``, a new folder) unless ``replace`` is set.
    """
    folder = Path(folder)
    if not folder.exists():
        raise BagNotFoundError(f'bag {folder} does not exist')
    if not folder.is_dir():
        raise BagError(f'{folder}: reindex needs a bag folder (the folder holding the .mcap files)')
    paths = sorted(folder.glob('*.mcap'), key=_natural_key)
    if not paths:
        raise BagError(f'{folder}: no .mcap files to index (an empty folder or not a bag)')
    custom: dict[str, str] | None = None
    if (folder / METADATA_FILE).is_file():
        try:
            custom = read_metadata(folder).custom_data
        except MetadataError:
            custom = None
    report = ReindexReport(info=BagInfo())
    scans: list[mcapfile.McapScan] = []
    unreadable: list[Path] = []
    for path in paths:
        try:
            result = mcapfile.scan(path, verify=True)
            mcapfile.require_ros2(result)
            scans.append(result)
        except CorruptBagError as err:
            unreadable.append(path)
            report.problems.append(str(err))
            report.dropped.append(f'{path.name}: the whole file (nothing readable)')
    if not scans:
        raise CorruptBagError(f'{folder}: no readable .mcap file: {"; ".join(report.problems)}')
    if all(s.problems and not s.message_count for s in scans):
        raise CorruptBagError(f'{folder}: nothing to salvage, no intact message in any file: '
                              + '; '.join(s.describe_problems() for s in scans))
    damaged = [s for s in scans if s.problems]
    if not damaged and not unreadable:
        report.info = info_from_scans(scans, folder, custom)
        report.output = folder
        write_metadata(folder, report.info)
        return report
    for result in damaged:
        report.problems.append(result.describe_problems())
        report.dropped += _dropped(result)
        for chunk in result.damaged:
            if chunk.lost is None:
                report.lost_unknown += 1
            else:
                report.lost.update(chunk.lost)
    if replace:
        target = folder
        for result in damaged:
            original = repair(result, notes=report.dropped)
            report.repaired.append(f'{result.path.name} (original kept as {original.name})')
        for path in unreadable:
            kept = _free(path.with_name(path.name + DAMAGED_SUFFIX))
            os.replace(path, kept)
            report.repaired.append(f'{path.name} removed from the bag (kept as {kept.name})')
        new_paths = [s.path for s in scans]
    else:
        target = Path(output) if output is not None else _free(folder.with_name(folder.name + REPAIRED_SUFFIX))
        if target.exists() and (not target.is_dir() or any(target.iterdir())):
            raise BagError(f'{target} exists already and is not empty; choose another output')
        target.mkdir(parents=True, exist_ok=True)
        new_paths = []
        for result in scans:
            new = target / result.path.name
            if result in damaged:
                write_salvaged(result, new, notes=report.dropped)
                report.repaired.append(f'{result.path.name} -> {new}')
            else:
                shutil.copy2(result.path, new)
            new_paths.append(new)
    rescans = [mcapfile.scan(p, verify=True) for p in new_paths]
    report.info = info_from_scans(rescans, target, custom)
    report.output = target
    write_metadata(target, report.info)
    report.report_path = target / REPORT_FILE
    report.report_path.write_text(report.text(), encoding='utf-8')
    return report
