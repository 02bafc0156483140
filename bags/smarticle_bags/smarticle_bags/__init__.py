"""Record, replay and analyse rosbag2-compatible mcap bags of smarticle runs.

Pure cores (no rclpy): ``writer`` (bag folders), ``mcapfile`` (crash-tolerant .mcap scanning),
``reader`` (raw and decoded messages), ``arrays`` (NumPy per topic), ``reindex``, ``playback``
(timing), ``selection`` (topic choice and remapping). ROS shells: ``recorder_node``, ``player_node``.
"""
