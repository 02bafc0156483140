"""The bag folder's ``metadata.yaml`` (rosbag2 ``rosbag2_bagfile_information``, version 9)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import MetadataError
from .qos import QosRecord, load_profiles

METADATA_FILE = 'metadata.yaml'
VERSION = 9
ROS_DISTRO = 'jazzy'


@dataclass
class TopicInfo:
    """One topic of a bag: name, type, serialization format, offered QoS, type hash and count."""

    name: str
    type: str
    serialization_format: str = 'cdr'
    offered_qos_profiles: list[QosRecord] = field(default_factory=list)
    type_description_hash: str = ''
    message_count: int = 0


@dataclass
class FileInfo:
    """One storage file of a bag: relative path, first message time, duration and count."""

    path: str
    starting_time: int = 0
    duration: int = 0
    message_count: int = 0


@dataclass
class BagInfo:
    """The whole ``rosbag2_bagfile_information`` record."""

    topics: list[TopicInfo] = field(default_factory=list)
    files: list[FileInfo] = field(default_factory=list)
    storage_identifier: str = 'mcap'
    compression_format: str = ''
    compression_mode: str = ''
    custom_data: dict[str, str] | None = None
    ros_distro: str = ROS_DISTRO
    version: int = VERSION

    @property
    def message_count(self) -> int:
        """Total number of messages in all files."""
        return sum(f.message_count for f in self.files)

    @property
    def starting_time(self) -> int:
        """Log time of the first message in nanoseconds since the epoch (0 for an empty bag)."""
        starts = [f.starting_time for f in self.files if f.message_count]
        return min(starts) if starts else 0

    @property
    def end_time(self) -> int:
        """Log time of the last message in nanoseconds since the epoch."""
        ends = [f.starting_time + f.duration for f in self.files if f.message_count]
        return max(ends) if ends else 0

    @property
    def duration(self) -> int:
        """Time from the first to the last message in nanoseconds."""
        return max(0, self.end_time - self.starting_time)

    def topic(self, name: str) -> TopicInfo | None:
        """Return the topic called ``name`` or None."""
        return next((t for t in self.topics if t.name == name), None)

    def to_dict(self) -> dict[str, Any]:
        """Return the mapping written to metadata.yaml."""
        return {'rosbag2_bagfile_information': {
            'version': self.version,
            'storage_identifier': self.storage_identifier,
            'duration': {'nanoseconds': self.duration},
            'starting_time': {'nanoseconds_since_epoch': self.starting_time},
            'message_count': self.message_count,
            'topics_with_message_count': [
                {'topic_metadata': {
                    'name': t.name,
                    'type': t.type,
                    'serialization_format': t.serialization_format,
                    'offered_qos_profiles': [q.to_dict() for q in t.offered_qos_profiles],
                    'type_description_hash': t.type_description_hash,
                 },
                 'message_count': t.message_count}
                for t in self.topics],
            'compression_format': self.compression_format,
            'compression_mode': self.compression_mode,
            'relative_file_paths': [f.path for f in self.files],
            'files': [
                {'path': f.path,
                 'starting_time': {'nanoseconds_since_epoch': f.starting_time},
                 'duration': {'nanoseconds': f.duration},
                 'message_count': f.message_count}
                for f in self.files],
            'custom_data': self.custom_data,
            'ros_distro': self.ros_distro,
        }}

    def to_yaml(self) -> str:
        """Return the text of metadata.yaml."""
        return yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=False)


def write_metadata(folder: Path, info: BagInfo) -> None:
    """Write ``folder/metadata.yaml`` atomically (a reader never sees half a file)."""
    target = folder / METADATA_FILE
    tmp = folder / f'.{METADATA_FILE}.tmp'
    with open(tmp, 'w', encoding='utf-8') as handle:
        handle.write(info.to_yaml())
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(tmp, target)


def _need(data: dict[str, Any], key: str, where: str) -> Any:
    """Return ``data[key]`` or raise MetadataError naming the missing key."""
    if not isinstance(data, dict) or key not in data:
        raise MetadataError(f'{where}: missing key {key!r}')
    return data[key]


def read_metadata(folder: Path) -> BagInfo:
    """Read and check ``folder/metadata.yaml``; raise MetadataError saying what is wrong."""
    path = folder / METADATA_FILE
    if not path.is_file():
        raise MetadataError(
            f'{folder} has no {METADATA_FILE}: not a rosbag2 bag folder, or a recording that never '
            f'finished; run "smarticle-bag reindex {folder}" to rebuild it from the .mcap files')
    try:
        data = yaml.load(path.read_text(encoding='utf-8'), Loader=getattr(yaml, 'CSafeLoader', yaml.SafeLoader))
    except (OSError, yaml.YAMLError) as err:
        raise MetadataError(f'{path}: not valid YAML ({err}); run "smarticle-bag reindex {folder}"') from err
    where = str(path)
    info = _need(data, 'rosbag2_bagfile_information', where)
    try:
        version = int(_need(info, 'version', where))
        if version > VERSION:
            raise MetadataError(f'{where}: metadata version {version} is newer than the supported {VERSION}')
        topics = []
        for item in _need(info, 'topics_with_message_count', where) or []:
            meta = _need(item, 'topic_metadata', where)
            topics.append(TopicInfo(
                name=str(_need(meta, 'name', where)), type=str(_need(meta, 'type', where)),
                serialization_format=str(meta.get('serialization_format', 'cdr')),
                offered_qos_profiles=load_profiles(meta.get('offered_qos_profiles')),
                type_description_hash=str(meta.get('type_description_hash', '') or ''),
                message_count=int(item.get('message_count', 0))))
        files = []
        if info.get('files'):
            for item in info['files']:
                files.append(FileInfo(
                    path=str(_need(item, 'path', where)),
                    starting_time=int(_need(item, 'starting_time', where)['nanoseconds_since_epoch']),
                    duration=int(_need(item, 'duration', where)['nanoseconds']),
                    message_count=int(item.get('message_count', 0))))
        else:
            # older versions list only the paths; the bag-wide times belong to the whole bag
            paths = [str(p) for p in _need(info, 'relative_file_paths', where) or []]
            files = [FileInfo(path=p) for p in paths]
            if files:
                files[0].starting_time = int(info['starting_time']['nanoseconds_since_epoch'])
                files[0].duration = int(info['duration']['nanoseconds'])
                files[0].message_count = int(info.get('message_count', 0))
        custom = info.get('custom_data')
        return BagInfo(
            topics=topics, files=files, storage_identifier=str(info.get('storage_identifier', 'mcap')),
            compression_format=str(info.get('compression_format', '') or ''),
            compression_mode=str(info.get('compression_mode', '') or ''),
            custom_data={str(k): str(v) for k, v in custom.items()} if isinstance(custom, dict) else None,
            ros_distro=str(info.get('ros_distro', '') or ''), version=version)
    except (TypeError, ValueError, KeyError) as err:
        raise MetadataError(
            f'{where}: malformed entry ({err}); run "smarticle-bag reindex {folder}"') from err
