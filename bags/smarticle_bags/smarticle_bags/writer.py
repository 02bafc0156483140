"""Write rosbag2-compatible bag folders: ``metadata.yaml`` plus ``<name>_<i>.mcap`` files of CDR messages.

Each .mcap has profile ``ros2``; each topic is a channel with message encoding ``cdr``, a schema with
encoding ``ros2msg`` holding the full message definition (``msgdefs.full_definition``) and the
channel metadata rosbag2 writes (``offered_qos_profiles``, ``topic_type_hash``). Chunks are
compressed with zstd or lz4 and go straight to the operating system when they are complete, so a
process killed with SIGKILL leaves every completed chunk on disk; ``flush`` closes the open chunk
early (the recorder calls it on a timer). ``metadata.yaml`` is rewritten atomically at every flush,
split and close, and ``reindex`` rebuilds it exactly. No ROS import.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from types import TracebackType
from typing import Sequence

from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter

from . import msgdefs
from .errors import BagError, BagExistsError, OptionError
from .metadata import BagInfo, FileInfo, TopicInfo, write_metadata
from .qos import QosRecord, dump_profiles

LIBRARY = 'smarticle_bags'


class Compression(Enum):
    """Chunk compression of the .mcap files."""

    NONE = 'none'
    LZ4 = 'lz4'
    ZSTD = 'zstd'

    @property
    def mcap_type(self) -> CompressionType:
        """The mcap library's compression constant."""
        return {Compression.NONE: CompressionType.NONE, Compression.LZ4: CompressionType.LZ4,
                Compression.ZSTD: CompressionType.ZSTD}[self]


@dataclass(frozen=True)
class WriterOptions:
    """How a bag is written: chunk compression and size, and when to split into a new file."""

    compression: Compression = Compression.ZSTD
    chunk_size: int = 1024 * 1024
    max_bag_size: int = 0
    max_bag_duration: int = 0

    def __post_init__(self) -> None:
        """Reject nonsense with a message naming the option."""
        if self.chunk_size < 1:
            raise OptionError(f'chunk size must be at least 1 byte, got {self.chunk_size}')
        if self.max_bag_size < 0:
            raise OptionError(f'max bag size must be >= 0 bytes (0 = no splitting), got {self.max_bag_size}')
        if self.max_bag_duration < 0:
            raise OptionError(
                f'max bag duration must be >= 0 (0 = no splitting), got {self.max_bag_duration}')


#: ``--storage-preset-profile`` names (as in rosbag2's mcap plugin) and what they mean here.
STORAGE_PRESETS: dict[str, tuple[Compression, int]] = {
    'none': (Compression.ZSTD, 1024 * 1024),
    'fastwrite': (Compression.NONE, 1024 * 1024),
    'zstd_fast': (Compression.ZSTD, 1024 * 1024),
    'zstd_small': (Compression.ZSTD, 4 * 1024 * 1024),
    'lz4': (Compression.LZ4, 1024 * 1024),
}


def file_name(folder: Path, index: int) -> str:
    """Return the rosbag2 name of storage file ``index`` of ``folder``: ``<folder name>_<index>.mcap``."""
    return f'{folder.name}_{index}.mcap'


class _DirectFile:
    """A binary file whose writes go straight to the operating system (no user-space buffer)."""

    def __init__(self, path: Path) -> None:
        self._raw = open(path, 'xb', buffering=0)

    def write(self, data: bytes) -> int:
        """Write all of ``data``."""
        view = memoryview(data)
        while view:
            written = self._raw.write(view)
            view = view[written or 0:]
        return len(data)

    def tell(self) -> int:
        """Return the current size of the file."""
        return self._raw.tell()

    def flush(self) -> None:
        """Nothing is buffered here."""

    def close(self) -> None:
        """Close the file."""
        self._raw.close()


@dataclass
class _StorageFile:
    """The .mcap file being written: its mcap writer, ids and the FileInfo that goes to metadata."""

    stream: _DirectFile
    mcap: McapWriter
    info: FileInfo
    channels: dict[str, int] = field(default_factory=dict)
    schemas: dict[str, int] = field(default_factory=dict)
    end_time: int = 0


class BagWriter:
    """Writes a bag folder; use as a context manager or call ``close``."""

    def __init__(self, folder: Path | str, options: WriterOptions | None = None,
                 custom_data: dict[str, str] | None = None) -> None:
        self.folder = Path(folder)
        self.options = options or WriterOptions()
        if self.folder.exists() and (not self.folder.is_dir() or any(self.folder.iterdir())):
            raise BagExistsError(
                f'output {self.folder} exists already; choose another -o/--output or remove it')
        self.folder.mkdir(parents=True, exist_ok=True)
        self.info = BagInfo(custom_data=custom_data)
        self._topics: dict[str, tuple[TopicInfo, str]] = {}
        self._file: _StorageFile | None = self._open_file()
        write_metadata(self.folder, self.info)

    # -- topics and messages ------------------------------------------------------------------

    def add_topic(self, name: str, type_name: str, offered_qos: Sequence[QosRecord] = (),
                  definition: str | None = None, type_hash: str | None = None) -> TopicInfo:
        """Declare a topic (once); its definition is read from the installed .msg files if not given."""
        if name in self._topics:
            return self._topics[name][0]
        type_name = msgdefs.normalize_type(type_name)
        text = definition if definition is not None else msgdefs.full_definition(type_name)
        digest = type_hash if type_hash is not None else msgdefs.type_hash(type_name)
        topic = TopicInfo(name=name, type=type_name, offered_qos_profiles=list(offered_qos),
                          type_description_hash=digest)
        self._topics[name] = (topic, text)
        self.info.topics.append(topic)
        self._register(self._current(), topic, text)
        write_metadata(self.folder, self.info)
        return topic

    def write(self, topic: str, data: bytes, log_time: int, publish_time: int | None = None) -> None:
        """Append one CDR-serialized message of ``topic`` received at ``log_time`` (ns since epoch)."""
        entry = self._topics.get(topic)
        if entry is None:
            raise BagError(f'topic {topic!r} was not added to {self.folder} (call add_topic first)')
        current = self._current()
        limit = self.options.max_bag_duration
        if limit and current.info.message_count and log_time - current.info.starting_time >= limit:
            current = self._split()
        channel = current.channels[topic]
        current.mcap.add_message(channel_id=channel, log_time=log_time, data=data,
                                 publish_time=publish_time if publish_time is not None else log_time)
        file_info = current.info
        if file_info.message_count == 0:
            file_info.starting_time = current.end_time = log_time
        file_info.starting_time = min(file_info.starting_time, log_time)
        current.end_time = max(current.end_time, log_time)
        file_info.duration = current.end_time - file_info.starting_time
        file_info.message_count += 1
        entry[0].message_count += 1
        if self.options.max_bag_size and current.stream.tell() >= self.options.max_bag_size:
            self._split()

    def flush(self) -> None:
        """Close the open chunk so that it is on disk, and rewrite metadata.yaml."""
        if self._file is not None:
            self._file.mcap.flush()
            write_metadata(self.folder, self.info)

    def close(self) -> BagInfo:
        """Finish the open file (summary and footer) and write the final metadata.yaml."""
        if self._file is not None:
            self._finish(self._file)
            self._file = None
            write_metadata(self.folder, self.info)
        return self.info

    def __enter__(self) -> BagWriter:
        """Context manager support."""
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        """Close the bag, also after an error (what was written stays readable)."""
        self.close()

    @property
    def closed(self) -> bool:
        """True once ``close`` ran."""
        return self._file is None

    # -- storage files ------------------------------------------------------------------------

    def _current(self) -> _StorageFile:
        """Return the open storage file or raise if the bag is closed."""
        if self._file is None:
            raise BagError(f'bag {self.folder} is closed')
        return self._file

    def _open_file(self) -> _StorageFile:
        """Create the next storage file and register every known topic in it."""
        name = file_name(self.folder, len(self.info.files))
        stream = _DirectFile(self.folder / name)
        mcap = McapWriter(stream, chunk_size=self.options.chunk_size,  # type: ignore[arg-type]
                          compression=self.options.compression.mcap_type, enable_data_crcs=True)
        mcap.start(profile='ros2', library=LIBRARY)
        storage = _StorageFile(stream=stream, mcap=mcap, info=FileInfo(path=name))
        self.info.files.append(storage.info)
        for topic, text in self._topics.values():
            self._register(storage, topic, text)
        return storage

    def _register(self, storage: _StorageFile, topic: TopicInfo, text: str) -> None:
        """Write the schema (once per type) and the channel of ``topic`` into ``storage``."""
        schema = storage.schemas.get(topic.type)
        if schema is None:
            schema = storage.mcap.register_schema(topic.type, 'ros2msg' if text else '', text.encode())
            storage.schemas[topic.type] = schema
        metadata = {'offered_qos_profiles': dump_profiles(topic.offered_qos_profiles),
                    'topic_type_hash': topic.type_description_hash}
        storage.channels[topic.name] = storage.mcap.register_channel(
            topic=topic.name, message_encoding=topic.serialization_format, schema_id=schema,
            metadata=metadata)

    def _finish(self, storage: _StorageFile) -> None:
        """Write the summary and footer of ``storage`` and close it."""
        storage.mcap.finish()
        storage.stream.close()

    def _split(self) -> _StorageFile:
        """Finish the current file and continue in a new one."""
        self._finish(self._current())
        self._file = self._open_file()
        write_metadata(self.folder, self.info)
        return self._file
