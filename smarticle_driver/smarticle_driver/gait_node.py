"""ROS node `gait`: runs the square gait of one robot and publishes its joint commands.

Publishes ``/smarticle_<k>/joint_commands`` when the targets change and at a heartbeat;
subscribes to ``/smarticles/start`` (synchronised start at ``header.stamp``; a zero stamp means now)
and ``/smarticle_<k>/halt``. All timing uses the node's clock, so ``use_sim_time`` works.
"""

from __future__ import annotations

import math
from typing import Any

from rclpy.node import Node
from rclpy.time import Time

from smarticle_common import topics
from smarticle_common.facts import GAIT_PERIOD, SERVO_SPEED
from smarticle_common.gait import (GaitCommand, GaitConfig, GaitError, SquareGait, TIME_EPS, board_time,
                                   check_start_time)
from smarticle_common.launching import summary_line
from smarticle_common.messages import stamp_msg, stamp_ns
from smarticle_common.node import accept_runtime_changes, read_config, resolve_robot_id, run_node
from smarticle_common.params import ROBOT_ID_PARAM, ParameterError, ParamSpec

NODE_NAME = 'gait'
#: Latest ``start_at`` (s): wall-clock times up to the year 2286.
START_AT_MAX = 1e10

PARAMS: tuple[ParamSpec, ...] = (
    ROBOT_ID_PARAM,
    ParamSpec('alpha_max_deg', 90.0, 'square-gait amplitude alpha_max in degrees (5 to 120); a change at run '
              'time takes effect at the next gait period', 5.0, 120.0, runtime=True),
    ParamSpec('period', GAIT_PERIOD, 'gait period T in seconds', 0.05, 60.0),
    ParamSpec('servo_speed', SERVO_SPEED, 'servo speed limit in rad/s', 0.1, 100.0),
    ParamSpec('phase', 0.0, 'phase offset as a fraction of a period, in [0, 1)', 0.0, 0.999999),
    ParamSpec('tick_rate', 100.0, 'how often the gait is evaluated, Hz', 1.0, 1000.0),
    ParamSpec('heartbeat', 0.2, 'republish the unchanged command after this many seconds', 0.005, 10.0),
    ParamSpec('autostart', False, 'start at the first tick without waiting for /smarticles/start'),
    ParamSpec('start_at', -1.0, "start the gait at this time (s) on the node's clock without waiting for "
              '/smarticles/start: on a board the wall clock in seconds since 1970 (e.g. $(date +%s) + 5), with '
              'use_sim_time the sim time, in lock-step the /clock time; a start more than one period in the past '
              'is refused; a start message with this stamp changes nothing (negative = wait for '
              '/smarticles/start). Lock-step runs set it so that the start cannot race the first /clock messages',
              -1.0, START_AT_MAX),
    ParamSpec('clock_rate_offset', 0.0, "relative error of this gait's clock rate: the gait sees t0 + (t - t0) * "
              '(1 + offset) from its start t0. 0 on a real board (its own clock drifts); in the simulation '
              "a seeded draw models the board's resonator (docs/sim_core.md, \"Noise with a cause\")",
              -0.05, 0.05),
    ParamSpec('lockstep', False, 'publish one command stamped with every /clock message (for the '
              "simulation's lock-step mode) instead of on change plus heartbeat"),
    ParamSpec('wait_for_feedback', False, 'lock-step only: answer each /clock message only once the feedback '
              'node has decided on the FSR sample of that time (/smarticle_<k>/feedback_decision), and take '
              'halts from those decisions, so a halt is part of the tick of its sample and a run is the same '
              'bit for bit; for robots that run a feedback node with lockstep:=true'),
)


def config_from_params(values: dict[str, Any]) -> GaitConfig:
    """Build the gait config from checked parameter values (degrees at this edge only; GaitError if bad)."""
    return GaitConfig.from_degrees(values['alpha_max_deg'], values['period'], values['servo_speed'],
                                   values['phase'])


class GaitNode(Node):
    """Thin ROS shell around smarticle_common.gait.SquareGait."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node; ``node_options`` go to rclpy's Node (a composing host's ``cli_args``)."""
        super().__init__(NODE_NAME, **node_options)
        config, values = read_config(self, PARAMS, lambda v: (config_from_params(v), v))
        self.robot_id = resolve_robot_id(self, values['robot_id'])
        self.gait = SquareGait(config)
        self.clock_rate = 1.0 + values['clock_rate_offset']
        self.heartbeat = Time(seconds=values['heartbeat']).nanoseconds
        self.autostart: bool = values['autostart']
        self.start_at: float = values['start_at']
        self.lockstep: bool = values['lockstep']
        if self.start_at >= 0.0:
            self.check_start_at(config.period)
            self.gait.start(self.start_at)
        self._last_targets: tuple[float, float] | None = None
        self.sent = self.halts = 0      # joint commands published, halts taken: the exit summary
        self._last_sent_ns = 0
        self._latest_ns = 0
        self._joint_state_type = topics.message_class('sensor_msgs/msg/JointState')
        spec = topics.spec_of('joint_commands')
        self.publisher = self.create_publisher(
            self._joint_state_type, spec.resolve(self.robot_id), topics.qos_profile(spec.qos))
        header_type = topics.message_class('std_msgs/msg/Header')
        start = topics.spec_of('start')
        self.create_subscription(header_type, start.resolve(), self.on_start, topics.qos_profile(start.qos))
        self.wait_for_feedback: bool = self.lockstep and values['wait_for_feedback']
        if values['wait_for_feedback'] and not self.lockstep:
            self.get_logger().warning('wait_for_feedback needs lockstep:=true: ignored')
        #: Lock-step with feedback: the /clock time still to answer, and the decisions received (stamp ns ->
        #: halting face or '') for times not answered yet.
        self._unanswered_ns: int | None = None
        self._decisions: dict[int, str] = {}
        halt = topics.spec_of('halt')
        if self.wait_for_feedback:   # halts come with the decisions, at the time of their sample
            decision = topics.spec_of('decision')
            self.create_subscription(header_type, decision.resolve(self.robot_id), self.on_decision,
                                     topics.qos_profile(decision.qos))
        else:
            self.create_subscription(header_type, halt.resolve(self.robot_id), self.on_halt,
                                     topics.qos_profile(halt.qos))
        if self.lockstep:
            clock = topics.spec_of('clock')
            self.create_subscription(topics.message_class(clock.type), clock.resolve(), self.on_clock,
                                     topics.qos_profile(clock.qos))
        else:
            self.timer = self.create_timer(1.0 / values['tick_rate'], self.on_tick)
        accept_runtime_changes(self, PARAMS, self.on_parameters)
        waiting = ('starting at once' if self.autostart else f'starting at t = {self.start_at:.3f} s'
                   if self.start_at >= 0.0 else f'waiting for {start.resolve()} (smarticle-start sends it)')
        self.get_logger().info(
            f'robot {self.robot_id}: alpha_max {values["alpha_max_deg"]:g} deg, '
            f'period {values["period"]:g} s, phase {values["phase"]:g}; {waiting}')

    def check_start_at(self, period: float) -> None:
        """Refuse a ``start_at`` more than one period before the node's clock (ParameterError, one line).

        In lock-step the gait's clock is /clock, unknown at start-up, and with use_sim_time before the first
        /clock message the node's clock reads zero: the check needs a clock and is skipped without one.
        """
        now = self.get_clock().now().nanoseconds * 1e-9
        if self.lockstep or now <= 0.0:
            return
        try:
            check_start_time(self.start_at, now, period)
        except GaitError as err:
            raise ParameterError(f'node {self.get_name()} parameter start_at: {err}; give a wall-clock time '
                                 '(seconds since 1970, e.g. $(date +%s) + 5) or -1 to wait for '
                                 f'{topics.spec_of("start").resolve()}') from None

    def on_parameters(self, changes: dict[str, Any]) -> None:
        """Apply a run-time change: the new amplitude from the next gait period on (GaitError if unusable)."""
        if 'alpha_max_deg' in changes:
            self.gait.set_alpha_max(math.radians(changes['alpha_max_deg']))

    def now(self) -> Time:
        """Return the node clock's time, never earlier than a time already handed to the gait.

        In lock-step mode the gait's time is exactly that of the last /clock message (so a halt takes
        effect at the tick it belongs to, and the node needs no use_sim_time).
        """
        if self.lockstep:
            return Time(nanoseconds=self._latest_ns)
        now = self.get_clock().now()
        if now.nanoseconds < self._latest_ns:
            return Time(nanoseconds=self._latest_ns, clock_type=now.clock_type)
        self._latest_ns = now.nanoseconds
        return now

    def now_seconds(self) -> float:
        """Return ``now()`` in seconds."""
        return self.now().nanoseconds * 1e-9

    def gait_clock(self, t: float) -> float:
        """The gait's own clock at node time ``t`` (s): runs at ``clock_rate_offset`` from the start."""
        return board_time(t, self.gait.start_time, self.clock_rate)

    def on_start(self, msg: Any) -> None:
        """Start (or restart) the gait at the stamped time."""
        stamp = msg.stamp.sec + msg.stamp.nanosec * 1e-9
        if self.start_at >= 0.0 and abs(stamp - self.start_at) < 1e-9:
            return  # the start this node was given already (a restart would forget a halt)
        now = self.now_seconds()
        if 0.0 < stamp < now - self.gait.config.period:
            self.get_logger().warning(f'the start stamp {stamp:.3f} s is {now - stamp:.3f} s before now on this '
                                      "node's clock: the gait joins that start mid-run")
        self.gait.start(stamp if stamp > 0.0 else now)
        self.get_logger().info(f'gait start at t = {self.gait.start_time:.3f} s')
        self.on_tick()

    def on_halt(self, msg: Any) -> None:
        """Hold the arms now and send the hold command at once.

        Now is the instant ``on_tick`` evaluates (plus ``TIME_EPS``): on sim time a halt often comes at the time
        of the last tick (the clock moves once per /clock message), and the gait has been evaluated there.
        """
        if self.gait.halt(self.gait_clock(self.now_seconds()) + TIME_EPS):
            self.halts += 1
            self.on_tick()

    def on_clock(self, msg: Any) -> None:
        """Lock-step mode: publish the command for exactly the time of this clock message.

        With ``wait_for_feedback`` the command waits for the feedback node's decision on the FSR sample of
        the same time (``on_decision``); a repeated clock message (the bridge resends it while it waits)
        is answered again.
        """
        now_ns = stamp_ns(msg.clock)
        if now_ns < self._latest_ns:
            self.get_logger().warning('clock went backwards: ignored')
            return
        self._latest_ns = now_ns
        if self.autostart and self.gait.start_time is None:
            self.gait.start(now_ns * 1e-9)
        if self.wait_for_feedback:
            self._unanswered_ns = now_ns
            self.answer_clock()
            return
        self.publish_command(now_ns)

    def on_decision(self, msg: Any) -> None:
        """Lock-step with feedback: keep the decision on the sample of ``msg.header.stamp``; answer if due."""
        stamp = stamp_ns(msg.stamp)
        if stamp < self._latest_ns:
            return   # a repeat of a decision on a time already answered
        self._decisions[stamp] = msg.frame_id
        self.answer_clock()

    def answer_clock(self) -> None:
        """Publish the command of the unanswered /clock time once its decision is here (halting first)."""
        stamp = self._unanswered_ns
        if stamp is None or stamp not in self._decisions:
            return
        if self._decisions[stamp] and self.gait.halt(self.gait_clock(stamp * 1e-9)):
            self.halts += 1
            self.get_logger().info(f'halt at t = {stamp * 1e-9:.4f} s ({self._decisions[stamp]})')
        if len(self._decisions) > 1:
            for old in [s for s in self._decisions if s < stamp]:
                del self._decisions[old]
        self.publish_command(stamp)

    def publish_command(self, now_ns: int) -> None:
        """Lock-step: publish the gait's command for exactly ``now_ns`` (integer nanoseconds)."""
        t = self.gait_clock(now_ns * 1e-9)
        self.publisher.publish(self.to_message(self.gait.command(t + TIME_EPS), now_ns))
        self.sent += 1

    def on_tick(self) -> None:
        """Evaluate the gait and publish when the targets change or the heartbeat is due."""
        now = self.now()
        if now.nanoseconds == 0:
            return  # sim time not yet received
        if self.autostart and self.gait.start_time is None:
            self.gait.start(now.nanoseconds * 1e-9)
        command = self.gait.command(self.gait_clock(now.nanoseconds * 1e-9) + TIME_EPS)
        if command.targets != self._last_targets or now.nanoseconds - self._last_sent_ns >= self.heartbeat:
            self.publisher.publish(self.to_message(command, now.nanoseconds))
            self.sent += 1
            self._last_targets = command.targets
            self._last_sent_ns = now.nanoseconds

    def destroy_node(self) -> None:
        """Log the robot's summary line (for the launcher), then destroy the node."""
        self.get_logger().info(summary_line(self.robot_id, {'commands': self.sent, 'halts': self.halts}))
        super().destroy_node()

    def to_message(self, command: GaitCommand, now_ns: int) -> Any:
        """Convert a gait command stamped ``now_ns`` to a JointState (position = targets, velocity = speed
        limits)."""
        msg = self._joint_state_type()
        msg.header.stamp = stamp_msg(now_ns)
        msg.name = list(topics.JOINT_NAMES)
        msg.position = [float(a) for a in command.targets]
        msg.velocity = [command.speed, command.speed]
        return msg


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_driver gait`."""
    raise SystemExit(run_node(GaitNode, NODE_NAME, args, startup_errors=(ParameterError,)))

if __name__ == '__main__':
    main()
