"""ROS node `player`: replays a bag's raw CDR messages with their recorded timing (times a rate).

Topics whose message type is not installed are skipped with a warning. ``/clock`` is published from
bag time when ``clock`` > 0 (the bag's own ``/clock`` is then not replayed). Pause and resume:
publish ``std_msgs/msg/Bool`` on ``/player/pause`` (true = pause, false = resume), or press the
space bar when the player runs in a terminal. The node exits when playback ends (unless ``loop``),
once reliable subscribers have acknowledged the last messages (or after ``ACK_WAIT`` seconds).
"""

from __future__ import annotations

import select
import sys
import time
from typing import Any

import rclpy
from rosgraph_msgs.msg import Clock
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from smarticle_common import topics as contract
from smarticle_common.node import declare_and_read, run_node
from smarticle_common.params import ParameterError

from . import qos
from .errors import BagError
from .playback import PlaybackClock, window
from .reader import BagReader, RawMessage
from .timebase import TimeBase, time_base
from .parameters import PLAYER_NODE, PLAYER_PARAMS, player_config

TICK = 0.001
#: Seconds the player waits, at the end, for reliable subscribers to acknowledge what it sent.
ACK_WAIT = 5.0


class Keyboard:
    """Space bar toggles pause when stdin is a terminal (cbreak mode, restored on close)."""

    def __init__(self) -> None:
        self._saved: Any = None
        if sys.stdin is not None and sys.stdin.isatty():
            import termios
            import tty
            self._saved = termios.tcgetattr(sys.stdin)
            tty.setcbreak(sys.stdin.fileno())

    @property
    def active(self) -> bool:
        """True when keys are read."""
        return self._saved is not None

    def pressed(self) -> str:
        """Return the keys pressed since the last call (never blocks)."""
        keys = ''
        while self.active and select.select([sys.stdin], [], [], 0.0)[0]:
            keys += sys.stdin.read(1)
        return keys

    def close(self) -> None:
        """Restore the terminal."""
        if self._saved is not None:
            import termios
            termios.tcsetattr(sys.stdin, termios.TCSADRAIN, self._saved)
            self._saved = None


class PlayerNode(Node):
    """Thin ROS shell around smarticle_bags.reader.BagReader and smarticle_bags.playback."""

    def __init__(self, overrides: dict[str, Any] | None = None) -> None:
        super().__init__(PLAYER_NODE, parameter_overrides=[
            Parameter(name, value=value) for name, value in (overrides or {}).items()])
        self.config = player_config(declare_and_read(self, PLAYER_PARAMS))
        options = self.config.options
        self.reader = BagReader(self.config.bag)
        self.reader.check_topics(self.config.topics)
        self.reader.check_topics(self.config.remaps)
        self.first, self.last = window(self.reader.info.starting_time, self.reader.info.end_time, options)
        wanted = self.config.topics or tuple(sorted(self.reader.topics))
        clock_topic = contract.topic('clock')
        if options.clock > 0.0 and clock_topic in wanted:
            self.get_logger().info(f'not replaying the bag\'s {clock_topic}: publishing it from bag time')
            wanted = tuple(t for t in wanted if t != clock_topic)
        self.publishers_by_topic: dict[str, Any] = {}
        for name in wanted:
            self.advertise(name)
        self.clock = PlaybackClock(options.rate)
        self.messages: Any = None
        self.pending: RawMessage | None = None
        self.published = 0
        self.finished = False
        self._start_at = time.monotonic_ns() + round(options.delay * 1e9)
        self._paused_at_start = options.start_paused
        bool_type = contract.message_class('std_msgs/msg/Bool')
        self.create_subscription(bool_type, '~/pause', self.on_pause,
                                 contract.qos_profile(contract.Qos.COMMAND))
        self.clock_publisher = None
        if options.clock > 0.0:
            clock_spec = contract.spec_of('clock')
            self.clock_publisher = self.create_publisher(
                contract.message_class(clock_spec.type), clock_topic, contract.qos_profile(clock_spec.qos))
            self.create_timer(1.0 / options.clock, self.on_clock)
        self.keyboard = Keyboard()
        if self.keyboard.active:
            self.create_timer(0.05, self.on_keys)
        self.create_timer(TICK, self.on_tick)
        base = {TimeBase.SIM: 'sim time', TimeBase.TRACKER: 'tracker time'}.get(time_base(self.reader.info)[0],
                                                                                'wall time')
        span = (self.last - self.first) / 1e9
        self.get_logger().info(
            f'playing {self.config.bag}: {len(self.publishers_by_topic)} topics at rate {options.rate:g}, '
            f'{span:.3f} s of {base} in {span / options.rate:.3f} s'
            + (' (paused: publish false on ~/pause or press space)' if options.start_paused else ''))

    def advertise(self, name: str) -> None:
        """Create the publisher of a bag topic (remapped), or skip it if its type is not installed."""
        info = self.reader.topics[name]
        try:
            msg_class = contract.message_class(info.type)
        except (ImportError, AttributeError, ValueError) as err:
            self.get_logger().warning(f'skipping {name}: unknown message type {info.type} ({err})')
            return
        target = self.config.remaps.get(name, name)
        self.publishers_by_topic[name] = self.create_publisher(
            msg_class, target, qos.playback_profile(info.offered_qos_profiles))

    def restart(self, wall: int) -> None:
        """Start (or loop) playback at the beginning of the window."""
        self.messages = self.reader.messages(list(self.publishers_by_topic), self.first, self.last)
        self.pending = next(self.messages, None)
        self.clock.start(wall, self.first, paused=self._paused_at_start)
        self._paused_at_start = False

    def on_tick(self) -> None:
        """Publish every message whose (rate-scaled) time has come."""
        wall = time.monotonic_ns()
        if self.finished or wall < self._start_at:
            return
        if self.messages is None:
            self.restart(wall)
        if self.clock.paused:
            return
        now = self.clock.now(wall)
        while self.pending is not None and self.pending.log_time <= now:
            self.publishers_by_topic[self.pending.topic].publish(self.pending.data)
            self.published += 1
            self.pending = next(self.messages, None)
        if self.pending is None:
            if self.config.options.loop and self.publishers_by_topic:
                self.restart(wall)
            else:
                self.finished = True
                self.get_logger().info(f'playback finished: {self.published} messages published')

    def on_clock(self) -> None:
        """Publish the current bag time on /clock."""
        if self.clock_publisher is None or self.messages is None:
            return
        now = self.clock.now(time.monotonic_ns())
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = divmod(now, 1_000_000_000)
        self.clock_publisher.publish(msg)

    def set_paused(self, paused: bool) -> None:
        """Pause or resume playback."""
        wall = time.monotonic_ns()
        if self.messages is None:
            self._paused_at_start = paused
            return
        if paused and not self.clock.paused:
            self.clock.pause(wall)
            self.get_logger().info('paused')
        elif not paused and self.clock.paused:
            self.clock.resume(wall)
            self.get_logger().info('resumed')

    def on_pause(self, msg: Any) -> None:
        """``~/pause``: true pauses, false resumes."""
        self.set_paused(bool(msg.data))

    def on_keys(self) -> None:
        """Space toggles pause."""
        if ' ' in self.keyboard.pressed():
            self.set_paused(not self.clock.paused)

    def run(self, executor: SingleThreadedExecutor) -> int:
        """Spin until the bag has been played (or ROS shuts down); return the exit code."""
        while rclpy.ok() and not self.finished:
            executor.spin_once(timeout_sec=0.1)
        self.wait_for_acks()
        return 0

    def wait_for_acks(self) -> None:
        """Before exiting, let reliable subscribers acknowledge the last messages (at most ACK_WAIT s).

        A process that exits right after its last publish takes unacknowledged samples with it.
        """
        deadline = time.monotonic() + ACK_WAIT
        for name, publisher in self.publishers_by_topic.items():
            left = max(0.0, deadline - time.monotonic())
            if not publisher.wait_for_all_acked(Duration(seconds=left)):
                self.get_logger().warning(f'{name}: not every subscriber acknowledged the last messages')

    def destroy_node(self) -> None:
        """Restore the terminal, then destroy the node."""
        self.keyboard.close()
        super().destroy_node()


def run(overrides: dict[str, Any] | None = None, args: list[str] | None = None) -> int:
    """Play a bag until it ends (or SIGINT); return the process exit code (2: bad settings or bag)."""
    return run_node(lambda: PlayerNode(overrides), PLAYER_NODE, args, startup_errors=(ParameterError, BagError))


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_bags player` (settings as ROS parameters)."""
    raise SystemExit(run(args=args))
