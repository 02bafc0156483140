"""ROS node `square_stop`: an example of a user's own controller for one smarticle.

A square gait in the (alpha1, alpha2) shape space with its own amplitude, that stops moving to new corners
for good once any FSR face of its robot reads more than ``stop_force`` newtons.

It follows the stack's two contracts and nothing else:

* the topic contract (``smarticle_common.topics``): it publishes ``/smarticle_<k>/joint_commands``
  (sensor_msgs/JointState: position = arm targets in rad, velocity = speed limit in rad/s) and reads
  ``/smarticle_<k>/fsr`` (effort = force of each face in N) and ``/clock``;
* the lock-step contract of the simulation (``lockstep:=true``, docs/own_controller.md): for every
  ``/clock`` time t it publishes exactly one command stamped t, computed from what it knew at t (here the
  FSR sample stamped t, which the sim bridge publishes right after the clock), and answers a repeated
  ``/clock`` message again with the same command.

Without ``lockstep`` (a robot board) it publishes at ``rate`` Hz on its node clock with the newest sample.
"""

from __future__ import annotations

import math
import sys
from typing import Any

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.time import Time
from smarticle_common import topics
from smarticle_common.cli import version_of
from smarticle_common.facts import GAIT_PERIOD, SERVO_SPEED
from smarticle_common.launching import summary_line

NODE_NAME = 'square_stop'


def square_corner(t: float, start_at: float, period: float, amplitude: float) -> tuple[float, float]:
    """The arm targets (rad) of the square gait at time ``t`` (s): one arm moves each quarter period."""
    corners = ((amplitude, amplitude), (-amplitude, amplitude), (-amplitude, -amplitude), (amplitude, -amplitude))
    if t < start_at:
        return corners[0]
    quarter = math.floor(4.0 * (t - start_at) / period)
    return corners[(quarter + 1) % 4]


#: The node's parameters: name -> (default, meaning with units).
PARAMETERS: dict[str, tuple[Any, str]] = {
    'robot_id': (0, 'the robot this node drives (its topics /smarticle_<robot_id>/...)'),
    'amplitude_deg': (60.0, 'square gait amplitude alpha_max in degrees, in (0, 120]'),
    'period': (GAIT_PERIOD, 'gait period in seconds'),
    'start_at': (0.5, 'sim or wall time in seconds at which the gait starts'),
    'stop_force': (0.5, 'FSR force in newtons above which the gait stops moving to new corners (in the sim a '
                        'collision of two small robots peaks at 0.9 to 1.2 N on the hardest face)'),
    'speed': (SERVO_SPEED, 'commanded servo speed in rad/s'),
    'lockstep': (False, "answer each /clock time t with one command stamped t (the sim's lock-step)"),
}


def usage() -> str:
    """``--help``: what the node does and its parameters with their defaults."""
    lines = [f'usage: {NODE_NAME} [--help] [--version] [--ros-args -p name:=value ...]', '',
             'A square gait that stops on contact (the example controller of the smarticle stack).', '',
             'parameters:']
    lines += [f'  {name} (default {default!r}): {meaning}' for name, (default, meaning) in PARAMETERS.items()]
    return '\n'.join(lines)


class SquareStopNode(Node):
    """A square gait that stops on contact, answering the simulation's clock in lock-step."""

    def __init__(self, **node_options: Any) -> None:
        """Declare the parameters, the publisher and the subscriptions."""
        super().__init__(NODE_NAME, **node_options)
        value = {name: self.declare_parameter(name, default).value for name, (default, _) in PARAMETERS.items()}
        self.robot_id = int(value['robot_id'])
        self.amplitude = math.radians(float(value['amplitude_deg']))
        self.period = float(value['period'])
        self.start_at = float(value['start_at'])
        self.stop_force = float(value['stop_force'])
        self.speed = float(value['speed'])
        self.lockstep = bool(value['lockstep'])
        if not (0.0 < self.amplitude <= math.radians(120.0) and self.period > 0.0 and self.speed > 0.0):
            raise ValueError('square_stop: amplitude_deg must be in (0, 120], period and speed positive')
        self.JointState = topics.message_class(topics.spec_of('joint_commands').type)
        self.commands = self.create_publisher(self.JointState, topics.topic('joint_commands', self.robot_id),
                                              topics.qos_profile(topics.spec_of('joint_commands').qos))
        fsr = topics.spec_of('fsr')
        self.create_subscription(topics.message_class(fsr.type), fsr.resolve(self.robot_id), self.on_fsr,
                                 topics.qos_profile(fsr.qos))
        self.stopped_at: tuple[float, float] | None = None   # the corner the gait stopped at
        self.sent = 0                                        # joint commands published
        self.samples: dict[int, float] = {}                  # FSR stamp (ns) -> largest face force (N)
        self.clock_ns: int | None = None                     # the /clock time still to answer
        if self.lockstep:
            clock = topics.spec_of('clock')
            self.create_subscription(topics.message_class(clock.type), clock.resolve(), self.on_clock,
                                     topics.qos_profile(clock.qos))
        else:
            self.create_timer(1.0 / float(self.declare_parameter('rate', 50.0).value), self.on_timer)
        self.get_logger().info(f'robot {self.robot_id}: square gait of {math.degrees(self.amplitude):g} deg, '
                               f'stops above {self.stop_force:g} N; {"lock-step" if self.lockstep else "free"}')

    def on_clock(self, msg: Any) -> None:
        """Lock-step: remember the time to answer; answer once its FSR sample is here."""
        self.clock_ns = Time.from_msg(msg.clock).nanoseconds
        self.answer()

    def on_fsr(self, msg: Any) -> None:
        """Keep the largest finite face force of the sample, by its stamp."""
        forces = [f for f in msg.effort if math.isfinite(f)]
        self.samples[Time.from_msg(msg.header.stamp).nanoseconds] = max(forces, default=0.0)
        if self.lockstep:
            self.answer()

    def answer(self) -> None:
        """Publish the command of the unanswered /clock time once the sample of that time has arrived."""
        t_ns = self.clock_ns
        if t_ns is None or t_ns not in self.samples:
            return
        self.publish_command(t_ns, self.samples[t_ns])
        for old in [s for s in self.samples if s < t_ns]:
            del self.samples[old]

    def on_timer(self) -> None:
        """Free mode (a board): command for the node clock's time with the newest sample."""
        now = self.get_clock().now().nanoseconds
        newest = self.samples[max(self.samples)] if self.samples else 0.0
        self.publish_command(now, newest)

    def publish_command(self, t_ns: int, force: float) -> None:
        """Decide (stop on a force above the threshold) and publish the command stamped ``t_ns``."""
        targets = square_corner(t_ns * 1e-9, self.start_at, self.period, self.amplitude)
        if self.stopped_at is None and force > self.stop_force:
            self.stopped_at = targets
            self.get_logger().info(f'stopped at t = {t_ns * 1e-9:.3f} s: an FSR face read {force:.2f} N')
        msg = self.JointState()
        msg.header.stamp = Time(nanoseconds=t_ns).to_msg()
        msg.name = list(topics.JOINT_NAMES)
        msg.position = list(self.stopped_at or targets)
        msg.velocity = [self.speed, self.speed]
        self.commands.publish(msg)
        self.sent += 1


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_example_controller square_stop`."""
    argv = sys.argv[1:] if args is None else args
    words = argv[:argv.index('--ros-args')] if '--ros-args' in argv else argv
    if '--version' in words:
        print(f'{NODE_NAME} {version_of("smarticle_example_controller")}')
        return
    if '-h' in words or '--help' in words:
        print(usage())
        return
    rclpy.init(args=args)
    node = None
    try:
        node = SquareStopNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:   # the line smarticle-launch gathers into its summary of the run
            node.get_logger().info(summary_line(node.robot_id, {'commands': node.sent,
                                                                'stops': int(node.stopped_at is not None)}))
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
