"""ROS node `recorder`: records chosen topics as raw CDR into a rosbag2-compatible mcap bag.

Topics are found with ``get_topic_names_and_types`` every ``topic_polling_interval`` seconds, so
topics that appear later are recorded too. Subscriptions use ``raw=True``: the CDR bytes go to the
bag untouched. The open chunk is flushed every ``flush_interval`` seconds, so a recorder killed with
SIGKILL loses at most that much; SIGINT/SIGTERM close the bag properly.

Log time is the receive time on the wall clock, or with ``use_sim_time`` the latest ``/clock``
(``smarticle_bags.timebase``); the timers run on the steady clock either way, so a recorder waiting for a
sim's first ``/clock`` still finds and subscribes to its topics.
"""

from __future__ import annotations

import functools

import time
from typing import Any

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time

from smarticle_common import topics as contract
from smarticle_common.node import declare_and_read, run_node
from smarticle_common.params import ParameterError

from . import qos
from .errors import BagError
from .parameters import RECORDER_NODE, RECORDER_PARAMS, recorder_config
from .timebase import SimLogClock, TimeBase, custom_data
from .writer import BagWriter


class RecorderNode(Node):
    """Thin ROS shell around smarticle_bags.writer.BagWriter."""

    def __init__(self, overrides: dict[str, Any] | None = None) -> None:
        super().__init__(RECORDER_NODE, parameter_overrides=[
            Parameter(name, value=value) for name, value in (overrides or {}).items()])
        self.config = recorder_config(declare_and_read(self, RECORDER_PARAMS))
        self.sim_clock = SimLogClock() if self.get_parameter('use_sim_time').value else None
        base = TimeBase.WALL if self.sim_clock is None else TimeBase.SIM
        self.writer = BagWriter(self.config.output, self.config.writer, custom_data=custom_data(base))
        self.recording: dict[str, Any] = {}
        self.skipped: set[str] = set()
        self._created = time.monotonic()
        self._warned_missing = False
        self._warned_clock = False
        self._clock_sub: Any = None
        if self.sim_clock is not None:
            # created first, so that a tick's /clock is taken before its messages; as deep as the recorded
            # topics' queues (not keep-last 1), so that a burst of ticks keeps every time, the first one too
            clock_spec = contract.spec_of('clock')
            self._clock_sub = self.create_subscription(contract.message_class(clock_spec.type), clock_spec.name,
                                                       self.on_clock, qos.subscription_profile([]))
        steady = Clock(clock_type=ClockType.STEADY_TIME)   # not sim time: it does not run before the sim
        self.create_timer(self.config.polling_interval, self.on_scan, clock=steady)
        self.create_timer(self.config.flush_interval, self.on_flush, clock=steady)
        self.get_logger().info(
            f'recording to {self.config.output} ({self.config.writer.compression.value} chunks, log time: '
            f'{"sim time from /clock" if self.sim_clock is not None else "wall time"})')

    def on_scan(self) -> None:
        """Subscribe to chosen topics that appeared since the last scan; warn about missing named ones."""
        chosen = self.config.filter.choose(self.get_topic_names_and_types())
        if self._clock_sub is not None and self._clock_sub.get_publisher_count() == 0:
            # use_sim_time: no topic before /clock has matched its publisher, so that a sim waiting for this
            # recorder's subscription (sim.launch.xml) starts only once the recorder takes its first /clock;
            # else the ticks before the match would be written at a later tick's time
            chosen = {}
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
        clock = self.sim_clock
        if clock is not None and not clock.started and not self._warned_clock and waited >= self.config.wait_warning:
            self._warned_clock = True
            self.get_logger().warning(
                f'use_sim_time is set but no /clock has arrived after {waited:.0f} s: holding '
                f'{len(clock.held)} messages until it does (is a sim running?)')

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
        """Write one received message at its log time: now on the wall clock, or the latest /clock."""
        if self.sim_clock is None:
            self.writer.write(topic, data, self.get_clock().now().nanoseconds)
            return
        for item in self.sim_clock.stamp(topic, data):
            self.writer.write(*item)

    def on_clock(self, msg: Any) -> None:
        """use_sim_time: take the sim's time; at the first /clock, write the messages held until then."""
        if self.sim_clock is None:
            return
        for item in self.sim_clock.on_clock(Time.from_msg(msg.clock).nanoseconds):
            self.writer.write(*item)

    def on_flush(self) -> None:
        """Put the open chunk on disk and refresh metadata.yaml."""
        self.writer.flush()

    def destroy_node(self) -> None:
        """Close the bag (footer and final metadata.yaml), then the node."""
        if not self.writer.closed:
            info = self.writer.close()
            self.get_logger().info(f'closed {self.config.output}: {info.message_count} messages')
        clock = self.sim_clock
        if clock is not None and (clock.held or clock.dropped):
            self.get_logger().warning(
                f'{len(clock.held) + clock.dropped} messages not recorded: '
                + ('no /clock arrived (use_sim_time)' if not clock.started else
                   f'more than {clock.max_held_bytes} bytes arrived before the first /clock'))
        super().destroy_node()


def run(overrides: dict[str, Any] | None = None, args: list[str] | None = None) -> int:
    """Run the recorder until SIGINT/SIGTERM; return the process exit code (2: bad settings or bag)."""
    return run_node(lambda: RecorderNode(overrides), RECORDER_NODE, args, startup_errors=(ParameterError, BagError))


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_bags recorder` (settings as ROS parameters)."""
    raise SystemExit(run(args=args))
