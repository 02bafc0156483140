"""Rebuild a bag folder's ``metadata.yaml`` from its .mcap files, repairing files without a footer.

A damaged file (no footer, a cut-off record, a chunk that fails its CRC) is rewritten as a complete
.mcap holding every readable message; the original is kept beside it as ``<name>.mcap.damaged`` so
that nothing recorded is ever deleted.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter

from . import mcapfile
from .errors import BagError, BagNotFoundError, MetadataError
from .metadata import METADATA_FILE, BagInfo, read_metadata, write_metadata
from .reader import info_from_scans
from .writer import LIBRARY

DAMAGED_SUFFIX = '.damaged'


@dataclass
class ReindexReport:
    """What reindex did: the new metadata, the files it repaired and the problems it found."""

    info: BagInfo
    repaired: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)


def _natural_key(path: Path) -> list[object]:
    """Sort key that puts ``bag_2.mcap`` before ``bag_10.mcap``."""
    return [int(part) if part.isdigit() else part for part in re.split(r'(\d+)', path.name)]


def repair(result: mcapfile.McapScan, compression: CompressionType = CompressionType.ZSTD) -> Path:
    """Rewrite a damaged .mcap as a complete file with its readable messages; return the kept original."""
    path = result.path
    tmp = path.with_name(f'.{path.name}.repair')
    with open(tmp, 'wb') as handle:
        writer = McapWriter(handle, compression=compression)
        writer.start(profile=result.profile or 'ros2', library=result.library or LIBRARY)
        schema_ids: dict[int, int] = {}
        channel_ids: dict[int, int] = {}
        for channel, message in mcapfile.iter_messages(result):
            if channel.id not in channel_ids:
                schema = result.schemas.get(channel.schema_id)
                if schema is not None and schema.id not in schema_ids:
                    schema_ids[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
                channel_ids[channel.id] = writer.register_channel(
                    channel.topic, channel.message_encoding,
                    schema_ids.get(channel.schema_id, 0), dict(channel.metadata))
            writer.add_message(channel_ids[channel.id], message.log_time, message.data,
                               message.publish_time, message.sequence)
        writer.finish()
    original = path.with_name(path.name + DAMAGED_SUFFIX)
    counter = 1
    while original.exists():
        original = path.with_name(f'{path.name}{DAMAGED_SUFFIX}.{counter}')
        counter += 1
    os.replace(path, original)
    os.replace(tmp, path)
    return original


def reindex(folder: Path | str, repair_damaged: bool = True) -> ReindexReport:
    """Rebuild ``folder/metadata.yaml`` from the .mcap files in it (repairing damaged ones)."""
    folder = Path(folder)
    if not folder.exists():
        raise BagNotFoundError(f'bag {folder} does not exist')
    if not folder.is_dir():
        raise BagError(f'{folder}: reindex needs a bag folder (the folder holding the .mcap files)')
    paths = sorted(folder.glob('*.mcap'), key=_natural_key)
    if not paths:
        raise BagError(f'{folder}: no .mcap files to index')
    custom: dict[str, str] | None = None
    if (folder / METADATA_FILE).is_file():
        try:
            custom = read_metadata(folder).custom_data
        except MetadataError:
            custom = None
    scans = [mcapfile.scan(p) for p in paths]
    report = ReindexReport(info=BagInfo())
    for index, result in enumerate(scans):
        if not result.problems:
            continue
        report.problems.append(result.describe_problems())
        if repair_damaged:
            original = repair(result)
            report.repaired.append(f'{result.path.name} (original kept as {original.name})')
            scans[index] = mcapfile.scan(result.path)
    report.info = info_from_scans(scans, folder, custom)
    write_metadata(folder, report.info)
    return report
