"""A lock-step controller with faults to order, for the sim_world fixture's tests (run as a script).

It answers every /clock time t with a command stamped t holding the arms straight, except that with
``stall_at`` >= 0 it stops answering from that sim time on (it stays alive: a node that misses ticks), with
``exit_at`` >= 0 it exits at that sim time without answering it (a node that has gone), and
at ``bad_at`` >= 0 it also sends one command with a NaN target, one stamped a second in the future and one
for robot ``foreign_robot`` (a robot the scene does not have).
"""

from __future__ import annotations

import math
import sys
from typing import Any

from rclpy.node import Node
from rclpy.time import Time
from smarticle_common import topics
from smarticle_common.node import run_node


class FaultyController(Node):
    """Answers /clock like a lock-step controller, with the faults of its parameters."""

    def __init__(self) -> None:
        super().__init__('faulty_controller')
        self.robot_id = int(self.declare_parameter('robot_id', 0).value)
        self.stall_at = float(self.declare_parameter('stall_at', -1.0).value)
        self.bad_at = float(self.declare_parameter('bad_at', -1.0).value)
        self.exit_at = float(self.declare_parameter('exit_at', -1.0).value)
        foreign = int(self.declare_parameter('foreign_robot', 7).value)
        self.JointState = topics.message_class('sensor_msgs/msg/JointState')
        qos = topics.qos_profile(topics.spec_of('joint_commands').qos)
        self.pub = self.create_publisher(self.JointState, topics.topic('joint_commands', self.robot_id), qos)
        self.foreign = self.create_publisher(self.JointState, topics.topic('joint_commands', foreign), qos)
        self.bad_sent = False
        clock = topics.spec_of('clock')
        self.create_subscription(topics.message_class(clock.type), clock.resolve(), self.on_clock,
                                 topics.qos_profile(clock.qos))

    def command(self, t_ns: int, target: float) -> Any:
        msg = self.JointState()
        msg.header.stamp = Time(nanoseconds=t_ns).to_msg()
        msg.name = list(topics.JOINT_NAMES)
        msg.position = [target, 0.0]
        msg.velocity = [5.0, 5.0]
        return msg

    def on_clock(self, msg: Any) -> None:
        t_ns = Time.from_msg(msg.clock).nanoseconds
        if 0.0 <= self.stall_at <= t_ns * 1e-9:
            return
        if 0.0 <= self.exit_at <= t_ns * 1e-9:
            self.context.try_shutdown()     # the process ends as after Ctrl-C (exit code 0)
            return
        if 0.0 <= self.bad_at <= t_ns * 1e-9 and not self.bad_sent:
            self.bad_sent = True
            self.pub.publish(self.command(t_ns, math.nan))
            self.pub.publish(self.command(t_ns + 10**9, 0.0))
            self.foreign.publish(self.command(t_ns, 0.0))
        self.pub.publish(self.command(t_ns, 0.0))


def main() -> None:
    raise SystemExit(run_node(FaultyController, 'faulty_controller', sys.argv))


if __name__ == '__main__':
    main()
