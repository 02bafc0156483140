"""ROS node `recorder`: records chosen topics as raw CDR into a rosbag2-compatible mcap bag.

Topics are found with ``get_topic_names_and_types`` every ``topic_polling_interval`` seconds, so
topics that appear later are recorded too. Subscriptions use ``raw=True``: the CDR bytes go to the
bag untouched. The open chunk is flushed every ``flush_interval`` seconds, so a recorder killed with
SIGKILL loses at most that much; SIGINT/SIGTERM close the bag properly.
"""

from __future__ import annotations

import functools

import time
from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter

from smarticle_common import topics as contract
from smarticle_common.node import declare_and_read, run_node
from smarticle_common.params import ParameterError

from . import qos
from .errors import BagError
from .parameters import RECORDER_NODE, RECORDER_PARAMS, recorder_config
from .writer import BagWriter


class RecorderNode(Node):
    """Thin ROS shell around smarticle_bags.writer.BagWriter."""

    def __init__(self, overrides: dict[str, Any] | None = None) -> None:
        super().__init__(RECORDER_NODE, parameter_overrides=[
            Parameter(name, value=value) for name, value in (overrides or {}).items()])
        self.config = recorder_config(declare_and_read(self, RECORDER_PARAMS))
        self.writer = BagWriter(self.config.output, self.config.writer)
        self.recording: dict[str, Any] = {}
        self.skipped: set[str] = set()
        self._created = time.monotonic()
        self._warned_missing = False
        self.create_timer(self.config.polling_interval, self.on_scan)
        self.create_timer(self.config.flush_interval, self.on_flush)
        self.get_logger().info(
            f'recording to {self.config.output} ({self.config.writer.compression.value} chunks)')

    def on_scan(self) -> None:
        """Subscribe to chosen topics that appeared since the last scan; warn about missing named ones."""
        chosen = self.config.filter.choose(self.get_topic_names_and_types())
        for name, type_name in chosen.items():
            # a topic seen only through its subscribers waits for a publisher: its QoS (latched,
            # reliable) is not known before, and a latched message would be missed
            if name not in self.recording and name not in self.skipped and self.count_publishers(name):
                self.subscribe(name, type_name)
        missing = [t for t in self.config.filter.topics if t not in self.recording and t not in self.skipped]
        waited = time.monotonic() - self._created
        if missing and not self._warned_missing and waited >= self.config.wait_warning:
            self._warned_missing = True
            self.get_logger().warning(
                f'no publisher seen after {waited:.0f} s for: {", ".join(missing)}; still waiting '
                f'(check the names: nothing is recorded for a topic that matches no publisher)')

    def subscribe(self, name: str, type_name: str) -> None:
        """Start recording topic ``name``; skip it with a warning if its type is not installed."""
        try:
            msg_class = contract.message_class(type_name)
            offered = [qos.from_rclpy(info.qos_profile) for info in self.get_publishers_info_by_topic(name)]
            self.writer.add_topic(name, type_name, offered)
        except (ImportError, AttributeError, ValueError, BagError) as err:
            self.skipped.add(name)
            self.get_logger().warning(f'not recording {name}: unknown message type {type_name} ({err})')
            return
        self.recording[name] = self.create_subscription(
            msg_class, name, functools.partial(self.on_message, name),
            qos.subscription_profile(offered), raw=True)
        self.get_logger().info(f'subscribed to {name} ({type_name})')

    def on_message(self, topic: str, data: bytes) -> None:
        """Write one received message with the node clock's time."""
        self.writer.write(topic, data, self.get_clock().now().nanoseconds)

    def on_flush(self) -> None:
        """Put the open chunk on disk and refresh metadata.yaml."""
        self.writer.flush()

    def destroy_node(self) -> None:
        """Close the bag (footer and final metadata.yaml), then the node."""
        if not self.writer.closed:
            info = self.writer.close()
            self.get_logger().info(f'closed {self.config.output}: {info.message_count} messages')
        super().destroy_node()


def run(overrides: dict[str, Any] | None = None, args: list[str] | None = None) -> int:
    """Run the recorder until SIGINT/SIGTERM; return the process exit code (2: bad settings or bag)."""
    return run_node(lambda: RecorderNode(overrides), RECORDER_NODE, args, startup_errors=(ParameterError, BagError))


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_bags recorder` (settings as ROS parameters)."""
    raise SystemExit(run(args=args))
