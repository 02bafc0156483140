"""The composing host's in-process delivery: hosted nodes on sim time share one /clock subscription."""

from __future__ import annotations

from typing import Any

from smarticle_bringup.local_delivery import connect, share_clock


def clock_subscriptions(nodes: list[Any]) -> int:
    """The /clock subscriptions of ``nodes``."""
    return sum(sub.topic_name == '/clock' for node in nodes for sub in node.subscriptions)


def test_hosted_sim_time_nodes_share_one_clock_subscription_and_read_the_same_time(ros_node: Any) -> None:
    import rclpy
    from builtin_interfaces.msg import Time as TimeMsg
    from rclpy.parameter import Parameter
    from rosgraph_msgs.msg import Clock

    ros_node('local_delivery_test')   # rclpy is initialised (and shut down) by the fixture
    sim = [rclpy.create_node(f'sim_{k}', parameter_overrides=[Parameter('use_sim_time', value=True)])
           for k in range(3)]
    wall = rclpy.create_node('wall')
    nodes = [*sim, wall]
    try:
        assert clock_subscriptions(nodes) == 3
        publisher = wall.create_publisher(Clock, '/clock', 1)
        assert share_clock(nodes) == 2
        assert clock_subscriptions(nodes) == 1
        delivery = connect(nodes)
        assert len(delivery.topics['/clock']) == 1
        publisher.publish(Clock(clock=TimeMsg(sec=5, nanosec=7)))
        assert delivery.counts.local == 1
        assert [node.get_clock().now().nanoseconds for node in sim] == [5_000_000_007] * 3
        assert wall.get_clock().now().nanoseconds > 1_000_000_000_000_000_000   # the wall clock, untouched
    finally:
        for node in nodes:
            node.destroy_node()
