"""`smarticle-start`: start the robots' gaits by publishing /smarticles/start, without the ROS CLI.

The gait and feedback nodes that have no ``start_at`` wait for this latched message (``std_msgs/Header``);
its stamp is the shared start time on their clocks: seconds since 1970 on a board, sim time in a
simulation. A zero stamp (the default) means "now", each node's own clock when the message arrives;
``--in 2`` stamps this machine's wall clock plus 2 s (boards on one clock, e.g. NTP, then start their
periods together); ``--at T`` stamps T. The command waits until the nodes listen (``--wait`` matching
subscriptions, within ``--timeout`` seconds, then until no new one has come for a second), publishes, waits
until they have the message, then stays a second for nodes still being discovered. The same as
``ros2 topic pub --once /smarticles/start std_msgs/msg/Header "{}" --qos-durability transient_local``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from datetime import datetime

from smarticle_common import topics
from smarticle_common.cli import add_version

#: Largest stamp a Header carries (its seconds are a signed 32-bit integer).
STAMP_MAX = 2**31 - 1
#: Seconds the publisher stays after delivery, for nodes still being discovered (the message is latched).
KEEP_ALIVE = 1.0
#: What the ROS graph calls a node it has not named yet.
UNKNOWN = '_UNKNOWN_'
#: Once ``--wait`` subscriptions matched: the start goes out when no new one has come for SETTLE seconds, at
#: the latest SETTLE_MAX seconds after.
SETTLE, SETTLE_MAX = 1.0, 5.0


def _seconds(text: str, low: float, high: float, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{what}: expected a number of seconds, got {text!r}') from None
    if not (math.isfinite(value) and low <= value <= high):
        raise argparse.ArgumentTypeError(f'{what}: must be {low:g} to {high:g} s, got {text!r}')
    return value


def parse_args(argv: list[str]) -> argparse.Namespace:
    """The options of ``smarticle-start`` (everything from ``--ros-args`` on goes to rclpy)."""
    parser = argparse.ArgumentParser(
        prog='smarticle-start', description=(__doc__ or '').split('\n\n')[1].replace('\n', ' ').replace('``', ''),
        epilog='ROS arguments (remappings, a log level) follow --ros-args.')
    when = parser.add_mutually_exclusive_group()
    when.add_argument('--in', dest='delay', metavar='SECONDS', default=None,
                      type=lambda s: _seconds(s, 0.0, 86400.0, 'the delay'),
                      help="start this many seconds from now on this machine's wall clock")
    when.add_argument('--at', metavar='SECONDS', default=None,
                      type=lambda s: _seconds(s, 1e-9, float(STAMP_MAX), 'the start time'),
                      help="start at this time on the nodes' clocks (seconds since 1970 on a board, sim time "
                           'in a simulation)')
    parser.add_argument('--wait', metavar='N', type=int, default=1,
                        help='matching subscriptions to wait for before publishing (default 1)')
    parser.add_argument('--timeout', metavar='SECONDS', default=10.0,
                        type=lambda s: _seconds(s, 0.0, 3600.0, 'the timeout'),
                        help='give up when fewer than --wait nodes listen after this long (default 10)')
    add_version(parser, 'smarticle_driver')
    args = parser.parse_args(argv)
    if args.wait < 0:
        parser.error(f'--wait: a number of subscriptions >= 0, got {args.wait}')
    return args


def start_stamp(delay: float | None, at: float | None, wall_now: float) -> float:
    """The stamp to publish (s): ``at``, or ``wall_now + delay``, or 0 ("now" at each node)."""
    if at is not None:
        return at
    return 0.0 if delay is None else wall_now + delay


def describe(stamp: float) -> str:
    """The start time in words, for the one line the command prints."""
    if stamp == 0.0:
        return "now (each node's clock when the message arrives)"
    if stamp > 1e8:     # seconds since 1970
        return f'at {stamp:.3f} s ({datetime.fromtimestamp(stamp).isoformat(sep=" ", timespec="milliseconds")})'
    return f'at t = {stamp:.3f} s'


def _full_name(namespace: str, name: str) -> str:
    return f'{namespace.rstrip("/")}/{name}'


def main(argv: list[str] | None = None) -> int:
    """Publish the start; return the exit code (1 when no node listens in time, 130 on Ctrl-C)."""
    from smarticle_common.node import SigintShutsDown

    argv = sys.argv[1:] if argv is None else argv
    cut = argv.index('--ros-args') if '--ros-args' in argv else len(argv)
    args = parse_args(argv[:cut])
    with SigintShutsDown():       # Ctrl-C shuts the context down, as in a node: no traceback from rclpy's code
        return publish_start(args, argv[cut:])


def publish_start(args: argparse.Namespace, ros_args: list[str]) -> int:
    """``main`` once its options are read: wait for listeners, publish, wait for delivery, stay a second."""
    import rclpy
    from rclpy.duration import Duration
    from rclpy.executors import ExternalShutdownException
    from smarticle_common.node import ended_by_signal

    rclpy.init(args=['smarticle-start', *ros_args])
    node = None
    try:
        node = rclpy.create_node('smarticle_start')
        spec = topics.spec_of('start')
        topic = node.resolve_topic_name(spec.resolve())
        header = topics.message_class(spec.type)
        publisher = node.create_publisher(header, topic, topics.qos_profile(spec.qos))
        deadline = time.monotonic() + args.timeout
        while publisher.get_subscription_count() < args.wait:
            if time.monotonic() >= deadline:
                print(f'smarticle-start: no start published: {publisher.get_subscription_count()} of {args.wait} '
                      f'nodes listen on {topic} after {args.timeout:g} s (is the launch running, with the same '
                      'ROS_DOMAIN_ID?)', file=sys.stderr)
                return 1
            rclpy.spin_once(node, timeout_sec=0.05)
        # nodes started together are discovered one by one: publish once no new listener has come for SETTLE s
        seen, changed = (-1, -1), time.monotonic()
        latest = changed + SETTLE_MAX
        while time.monotonic() < min(changed + SETTLE, latest):
            now = (publisher.get_subscription_count(), node.count_subscribers(topic))
            if now != seen:
                seen, changed = now, time.monotonic()
            rclpy.spin_once(node, timeout_sec=0.05)
        msg = header()
        stamp = start_stamp(args.delay, args.at, time.time())
        msg.stamp.sec, msg.stamp.nanosec = int(stamp), min(round((stamp % 1.0) * 1e9), 999_999_999)
        publisher.publish(msg)
        delivered = publisher.wait_for_all_acked(Duration(seconds=5.0))
        stay, named_by = time.monotonic() + KEEP_ALIVE, time.monotonic() + 3.0 * KEEP_ALIVE

        def listeners() -> list[str]:
            return sorted({_full_name(info.node_namespace, info.node_name)
                           for info in node.get_subscriptions_info_by_topic(topic)})

        # stay for nodes still being discovered, and until the graph names the listeners (at most 3 s)
        while time.monotonic() < stay or (any(UNKNOWN in name for name in listeners())
                                          and time.monotonic() < named_by):
            rclpy.spin_once(node, timeout_sec=0.05)
        names = [name if UNKNOWN not in name else 'a node not yet named' for name in listeners()]
        print(f'smarticle-start: start {describe(stamp)} published on {topic} to {len(names)} node(s): '
              + ', '.join(names) + ('' if delivered else ' (not every one confirmed it within 5 s)'),
              flush=True)
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):
        return 130
    except RuntimeError:      # rclpy's errors of a context that Ctrl-C just ended
        if not ended_by_signal():
            raise
        return 130
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()


def entry() -> None:
    """Console entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
