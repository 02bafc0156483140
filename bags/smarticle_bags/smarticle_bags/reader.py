"""Read a bag folder (``metadata.yaml`` + .mcap files) or a single .mcap without ROS: raw CDR or decoded.

Decoding uses ``mcap_ros2``'s decoder on the ``ros2msg`` schemas stored in the file, so bags made by
rosbag2 and by this package read the same way, with no rclpy or message packages needed. Damaged
files are salvaged (every intact chunk is read, every chunk's CRC checked as it is read) with a warning,
or rejected with ``strict=True`` (which checks every chunk when the bag is opened).
"""

from __future__ import annotations

import heapq
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from mcap.records import Channel
from mcap_ros2.decoder import DecoderFactory

from . import mcapfile
from .errors import BagError, BagNotFoundError, CorruptBagError, MetadataError, TopicSelectionError
from .metadata import BagInfo, FileInfo, TopicInfo, read_metadata
from .qos import load_profiles

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class RawMessage:
    """One stored message: topic, type, log and publish time (ns since epoch) and its CDR bytes."""

    topic: str
    type: str
    log_time: int
    publish_time: int
    data: bytes


def info_from_scans(scans: list[mcapfile.McapScan], base: Path | None = None,
                    custom_data: dict[str, str] | None = None) -> BagInfo:
    """Build the metadata of a bag from what its .mcap files actually hold."""
    topics: dict[str, TopicInfo] = {}
    files = []
    for result in scans:
        for channel_id, channel in sorted(result.channels.items()):
            topic = topics.get(channel.topic)
            if topic is None:
                topic = TopicInfo(
                    name=channel.topic, type=result.topic_type(channel),
                    serialization_format=channel.message_encoding or 'cdr',
                    offered_qos_profiles=load_profiles(channel.metadata.get('offered_qos_profiles')),
                    type_description_hash=channel.metadata.get('topic_type_hash', ''))
                topics[channel.topic] = topic
            topic.message_count += result.channel_counts.get(channel_id, 0)
        name = str(result.path.relative_to(base)) if base is not None else result.path.name
        count = result.message_count
        files.append(FileInfo(path=name, starting_time=result.start_time if count else 0,
                              duration=max(0, result.end_time - result.start_time) if count else 0,
                              message_count=count))
    return BagInfo(topics=list(topics.values()), files=files, custom_data=custom_data)


def check_topics(requested: Iterable[str], available: Iterable[str], where: str) -> None:
    """Raise TopicSelectionError if a requested topic is not among ``available``, listing those."""
    known = sorted(set(available))
    missing = [name for name in requested if name not in known]
    if missing:
        raise TopicSelectionError(
            f'{", ".join(missing)}: no such topic in {where}; it has {", ".join(known) or "no topics"}')


class BagReader:
    """A bag opened for reading; ``info`` is its metadata, ``messages`` and ``decoded`` its content."""

    def __init__(self, path: Path | str, strict: bool = False, verify: bool | None = None) -> None:
        self.path = Path(path)
        check = strict if verify is None else verify
        #: Decompressed chunks kept between passes of the columnar reader (``arrays.read_*``).
        self.chunk_cache = mcapfile.ChunkCache()
        #: Files of the bag that are not readable at all (skipped unless strict).
        self.unreadable: list[str] = []
        if not self.path.exists():
            raise BagNotFoundError(f'bag {self.path} does not exist')
        if self.path.is_dir():
            self.info = read_metadata(self.path)
            if self.info.storage_identifier != 'mcap':
                raise MetadataError(f'{self.path}: storage {self.info.storage_identifier!r} is not supported '
                                    f'(only mcap; convert sqlite3 bags with "ros2 bag convert")')
            paths = [self.path / f.path for f in self.info.files]
            missing = [str(p) for p in paths if not p.is_file()]
            if missing:
                raise MetadataError(f'{self.path}: metadata.yaml lists files that do not exist: '
                                    f'{", ".join(missing)}; run "smarticle-bag reindex {self.path}"')
            if not paths:
                raise MetadataError(f'{self.path}: metadata.yaml lists no storage files')
            self.scans = []
            for file_path in paths:
                try:
                    self.scans.append(mcapfile.scan(file_path, check))
                except CorruptBagError as err:
                    if strict or len(paths) == 1:
                        raise
                    self.unreadable.append(str(err))
                    _LOG.warning('%s; the file is skipped', err)
            if not self.scans:
                raise CorruptBagError(f'{self.path}: no readable storage file: {"; ".join(self.unreadable)}')
        elif self.path.suffix == '.mcap':
            self.scans = [mcapfile.scan(self.path, check)]
            self.info = info_from_scans(self.scans)
        else:
            raise BagError(f'{self.path} is neither a bag folder nor an .mcap file')
        for result in self.scans:
            mcapfile.require_ros2(result)
            if result.profile not in ('ros2', ''):
                _LOG.warning('%s: mcap profile is %r, not ros2', result.path, result.profile)
        if self.problems:
            text = '; '.join(r.describe_problems() for r in self.scans if r.problems)
            if strict:
                raise CorruptBagError(f'{text}. Run "smarticle-bag reindex" on the bag folder to repair it')
            _LOG.warning('damaged bag, reading what is complete: %s', text)

    @property
    def problems(self) -> list[str]:
        """What is wrong with the files (empty for a healthy bag)."""
        return [f'{r.path.name}: {p}' for r in self.scans for p in r.problems] + self.unreadable

    @property
    def topics(self) -> dict[str, TopicInfo]:
        """The topics of the bag by name."""
        return {t.name: t for t in self.info.topics}

    def check_topics(self, names: Iterable[str]) -> None:
        """Raise TopicSelectionError naming any of ``names`` the bag does not have."""
        check_topics(names, self.topics, f'bag {self.path}')

    def messages(self, topics: Iterable[str] | None = None, start: int | None = None,
                 end: int | None = None) -> Iterator[RawMessage]:
        """Yield the messages of ``topics`` (all if None) with start <= log_time <= end, in time order."""
        wanted = set(topics) if topics is not None else None
        if wanted is not None:
            self.check_topics(wanted)
        streams = [self._file_messages(index, wanted, start, end) for index in range(len(self.scans))]
        yield from heapq.merge(*streams, key=lambda m: m.log_time)

    def _file_messages(self, index: int, wanted: set[str] | None, start: int | None,
                       end: int | None) -> Iterator[RawMessage]:
        """Yield the wanted messages of one file in time order."""
        result = self.scans[index]
        ids = None if wanted is None else {c.id for c in result.channels.values() if c.topic in wanted}
        for channel, message in mcapfile.iter_messages(result, ids, start, end):
            if wanted is not None and channel.topic not in wanted:
                continue  # a channel learnt only while reading a chunk
            yield RawMessage(channel.topic, self._type_of(result, channel), message.log_time,
                             message.publish_time, message.data)

    def _type_of(self, result: mcapfile.McapScan, channel: Channel) -> str:
        """Return the message type of a channel from its schema, else from metadata.yaml."""
        name = result.topic_type(channel)
        if name:
            return name
        topic = self.topics.get(channel.topic)
        return topic.type if topic is not None else ''

    def decoded(self, topics: Iterable[str] | None = None, start: int | None = None,
                end: int | None = None) -> Iterator[tuple[RawMessage, Any]]:
        """Yield (raw, decoded) pairs; messages that cannot be decoded are skipped with a warning."""
        decoders: dict[str, Callable[[bytes], Any] | None] = {}
        factory = DecoderFactory()
        schemas = {s.name: s for result in self.scans for s in result.schemas.values()}
        for raw in self.messages(topics, start, end):
            if raw.type not in decoders:
                decoders[raw.type] = self._decoder(factory, schemas.get(raw.type), raw)
            decoder = decoders[raw.type]
            if decoder is None:
                continue
            try:
                value = decoder(raw.data)
            except Exception as err: # a generated decoder over bytes from disk
                _LOG.warning('%s at t=%d: cannot decode %s message (%s); skipped', raw.topic, raw.log_time,
                             raw.type, err)
                continue
            yield raw, value

    @staticmethod
    def _decoder(factory: DecoderFactory, schema: Any, raw: RawMessage) -> Callable[[bytes], Any] | None:
        """Return a decoder for the schema of ``raw`` or None (with a warning) when there is none."""
        if schema is None or not schema.data:
            _LOG.warning('%s: type %s has no message definition in the bag; its messages are skipped',
                         raw.topic, raw.type or '(unknown)')
            return None
        try:
            return factory.decoder_for('cdr', schema)
        except Exception as err: # mcap_ros2's parser of a definition read from disk
            _LOG.warning('%s: cannot parse the definition of %s (%s); its messages are skipped',
                         raw.topic, raw.type, err)
            return None
