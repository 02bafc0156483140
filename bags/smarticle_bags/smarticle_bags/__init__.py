"""Record, replay and analyse rosbag2-compatible mcap bags of smarticle runs.

Pure cores (no rclpy): ``writer`` (bag folders), ``mcapfile`` (crash-tolerant .mcap scanning),
``reader`` (raw and decoded messages), ``arrays`` (NumPy per topic), ``reindex``, ``playback``
(timing), ``selection`` (topic choice and remapping), ``csv_import`` (other trackers' CSV tracks).
ROS shells: ``recorder_node``, ``player_node``.
"""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'BagReader': 'reader',
    'BagWriter': 'writer', 'WriterOptions': 'writer',
    'start_recording': 'recording',
    'BagError': 'errors', 'BagNotFoundError': 'errors', 'MetadataError': 'errors', 'CorruptBagError': 'errors',
    'BagExistsError': 'errors', 'MessageDefinitionError': 'errors', 'TopicSelectionError': 'errors',
    'OptionError': 'errors', 'CsvImportError': 'errors',
    'ImportSpec': 'csv_import', 'read_tracks': 'csv_import', 'write_bag': 'csv_import',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
