"""Writer core: bag folders that our reader and the independent rosbags library read back alike."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader

from smarticle_bags import msgdefs
from smarticle_bags.errors import BagExistsError, MessageDefinitionError, OptionError
from smarticle_bags.qos import QosRecord, load_profiles
from smarticle_bags.reader import BagReader
from smarticle_bags.writer import BagWriter, Compression, WriterOptions

from tests.helpers.bags import JOINTS, POSES, T0, make_bag, pose_array


def test_round_trip_our_reader(tmp_path: Path) -> None:
    written = make_bag(tmp_path / 'bag')
    reader = BagReader(tmp_path / 'bag', strict=True)
    got: dict[str, list[tuple[int, bytes]]] = {POSES: [], JOINTS: []}
    times = []
    for raw in reader.messages():
        got[raw.topic].append((raw.log_time, raw.data))
        times.append(raw.log_time)
    assert got == written
    assert times == sorted(times)
    decoded = [msg for _, msg in reader.decoded([POSES])]
    assert decoded[7].poses[2].position.x == pytest.approx(2.07)
    assert decoded[7].header.frame_id == 'arena'


def test_round_trip_rosbags(tmp_path: Path) -> None:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    written = make_bag(tmp_path / 'bag')
    typestore = get_typestore(Stores.ROS2_JAZZY)
    got: dict[str, list[tuple[int, bytes]]] = {POSES: [], JOINTS: []}
    with Reader(tmp_path / 'bag') as reader:
        assert reader.message_count == 100
        assert {c.topic: c.msgtype for c in reader.connections} == {
            POSES: 'geometry_msgs/msg/PoseArray', JOINTS: 'sensor_msgs/msg/JointState'}
        for connection, timestamp, data in reader.messages():
            got[connection.topic].append((timestamp, bytes(data)))
            msg = typestore.deserialize_cdr(data, connection.msgtype)
            if connection.topic == JOINTS:
                assert list(msg.name) == ['arm1', 'arm2']
    assert got == written


def test_metadata_fields(tmp_path: Path) -> None:
    qos = QosRecord(history='keep_last', depth=10, reliability='best_effort')
    with BagWriter(tmp_path / 'bag') as writer:
        writer.add_topic(POSES, 'geometry_msgs/PoseArray', [qos])
        writer.write(POSES, pose_array(0), T0)
        writer.write(POSES, pose_array(1), T0 + 500)
    info = yaml.safe_load((tmp_path / 'bag' / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap' and info['ros_distro'] == 'jazzy'
    assert info['duration'] == {'nanoseconds': 500}
    assert info['starting_time'] == {'nanoseconds_since_epoch': T0}
    assert info['relative_file_paths'] == ['bag_0.mcap']
    assert info['files'][0]['message_count'] == 2
    topic = info['topics_with_message_count'][0]
    assert topic['message_count'] == 2
    meta = topic['topic_metadata']
    assert meta['type'] == 'geometry_msgs/msg/PoseArray' and meta['serialization_format'] == 'cdr'
    assert meta['type_description_hash'].startswith('RIHS01_')
    assert meta['offered_qos_profiles'][0]['reliability'] == 'best_effort'
    assert meta['offered_qos_profiles'][0]['deadline'] == {'sec': 9223372036, 'nsec': 854775807}
    for key in ('compression_format', 'compression_mode', 'custom_data', 'message_count'):
        assert key in info


def test_mcap_schema_and_channel(tmp_path: Path) -> None:
    qos = QosRecord(history='keep_last', depth=5)
    with BagWriter(tmp_path / 'bag', WriterOptions(compression=Compression.LZ4)) as writer:
        writer.add_topic(POSES, 'geometry_msgs/msg/PoseArray', [qos])
        writer.write(POSES, pose_array(0), T0)
    with open(tmp_path / 'bag' / 'bag_0.mcap', 'rb') as handle:
        reader = make_reader(handle)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert summary is not None
        schema = next(iter(summary.schemas.values()))
        channel = next(iter(summary.channels.values()))
        assert [c.compression for c in summary.chunk_indexes] == ['lz4']
    text = schema.data.decode()
    assert schema.encoding == 'ros2msg' and schema.name == 'geometry_msgs/msg/PoseArray'
    assert '=' * 80 + '\nMSG: std_msgs/Header\n' in text
    assert 'MSG: builtin_interfaces/Time' in text and 'MSG: geometry_msgs/Quaternion' in text
    assert channel.message_encoding == 'cdr'
    assert load_profiles(channel.metadata['offered_qos_profiles']) == [qos]
    assert channel.metadata['topic_type_hash'] == msgdefs.type_hash('geometry_msgs/msg/PoseArray')


def test_split_by_size_and_duration(tmp_path: Path) -> None:
    make_bag(tmp_path / 'size', 60, WriterOptions(chunk_size=500, max_bag_size=3000))
    make_bag(tmp_path / 'time', 60, WriterOptions(max_bag_duration=200_000_000))
    for name in ('size', 'time'):
        reader = BagReader(tmp_path / name, strict=True)
        assert len(reader.info.files) > 1
        assert [f.path for f in reader.info.files][:2] == [f'{name}_0.mcap', f'{name}_1.mcap']
        assert reader.info.message_count == 120 == sum(1 for _ in reader.messages())
    durations = [f.duration for f in BagReader(tmp_path / 'time').info.files]
    assert max(durations) < 200_000_000


def test_refuses_existing_output_and_bad_options(tmp_path: Path) -> None:
    (tmp_path / 'bag').mkdir()
    (tmp_path / 'bag' / 'keep.txt').write_text('mine')
    with pytest.raises(BagExistsError, match='exists already'):
        BagWriter(tmp_path / 'bag')
    assert (tmp_path / 'bag' / 'keep.txt').read_text() == 'mine'
    with pytest.raises(OptionError, match='max bag size'):
        WriterOptions(max_bag_size=-1)


def test_message_definitions() -> None:
    text = msgdefs.full_definition('diagnostic_msgs/msg/DiagnosticArray')
    assert text.count('MSG: ') == 4  # Header, Time, DiagnosticStatus, KeyValue
    assert msgdefs.field_types('Pose[] poses\nuint8 OK=0\nstring<=5[<=3] s\nHeader h', 'geometry_msgs') == [
        'geometry_msgs/Pose', 'std_msgs/Header']
    with pytest.raises(MessageDefinitionError, match='not installed'):
        msgdefs.full_definition('no_such_msgs/msg/Thing')
    with pytest.raises(MessageDefinitionError, match='pkg/msg/Name'):
        msgdefs.full_definition('PoseArray')


def test_reads_bag_written_by_rosbags(tmp_path: Path) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Writer(tmp_path / 'other', version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection(POSES, 'geometry_msgs/msg/PoseArray', typestore=typestore)
        for i in range(5):
            writer.write(connection, T0 + i, pose_array(i))
    reader = BagReader(tmp_path / 'other', strict=True)
    assert reader.info.message_count == 5
    assert [msg.header.stamp.sec for _, msg in reader.decoded()] == [0, 1, 2, 3, 4]
