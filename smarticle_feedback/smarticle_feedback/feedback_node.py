"""ROS node `feedback`: the impact-threshold controller of one robot, on hardware and in simulation alike.

Subscribes ``/smarticle_<k>/fsr`` (sensor_msgs/JointState, effort = newtons) and ``/smarticles/start``;
publishes ``/smarticle_<k>/halt`` (std_msgs/Header, stamp = the stamp of the triggering FSR sample,
frame_id = the triggering face) and ``/diagnostics``; with ``lockstep`` (the simulation's lock-step mode)
also ``/smarticle_<k>/feedback_decision`` for every sample, which the lock-step gait node waits for.
The node never asks where it runs: the servo bridge and the sim bridge publish the same FSR topic. See docs/feedback.md.
"""

from __future__ import annotations

from typing import Any

import rclpy
from rclpy.node import Node
from rclpy.time import Time
from smarticle_common import topics
from smarticle_common.gait import board_time
from smarticle_common.launching import summary_line
from smarticle_common.messages import stamp_ns
from smarticle_common.node import (OK, WARN, DiagnosticsPublisher, accept_runtime_changes, read_config,
                                   resolve_robot_id, run_node)
from smarticle_common.params import ParameterError

from .controller import ImpactController, check_sample
from .errors import FsrSampleError
from .parameters import NODE_NAME, PARAMS, config_from_values


def _msg(key: str) -> Any:
    """Message class of contract entry ``key``."""
    return topics.message_class(topics.spec_of(key).type)


class FeedbackNode(Node):
    """Thin ROS shell around smarticle_feedback.controller.ImpactController."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node; ``node_options`` go to rclpy's Node (a composing host's ``cli_args``)."""
        super().__init__(NODE_NAME, **node_options)
        config, values = read_config(self, PARAMS, lambda v: (config_from_values(v), v))
        self.robot_id = resolve_robot_id(self, values['robot_id'])
        self.controller = ImpactController(config)
        self.start_at: float = values['start_at']
        self.clock_rate = 1.0 + values['clock_rate_offset']
        if self.start_at >= 0.0:
            self.controller.start(self.start_at)
        self.bad: dict[str, int] = {}
        self.last_problem = ''
        self.Header = _msg('halt')
        qos = {key: topics.qos_profile(topics.spec_of(key).qos) for key in ('fsr', 'halt', 'start')}
        self.halt_pub = self.create_publisher(self.Header, topics.topic('halt', self.robot_id), qos['halt'])
        self.diagnostics = DiagnosticsPublisher(self, f'smarticle_{self.robot_id}/{NODE_NAME}')
        self.lockstep: bool = values['lockstep']
        self.decision_pub: Any = None
        self._last_decision: Any = None
        if self.lockstep:
            self.decision_pub = self.create_publisher(self.Header, topics.topic('decision', self.robot_id),
                                                      topics.qos_profile(topics.spec_of('decision').qos))
        self.create_subscription(_msg('fsr'), topics.topic('fsr', self.robot_id), self.on_fsr, qos['fsr'])
        self.create_subscription(self.Header, topics.topic('start'), self.on_start, qos['start'])
        self.create_timer(values['diagnostics_period'], self.publish_diagnostics, clock=rclpy.clock.Clock())
        self.values = values
        accept_runtime_changes(self, PARAMS, self.on_parameters)
        cfg = self.controller.config
        self.get_logger().info(
            f'robot {self.robot_id}: faces {", ".join(cfg.enabled_faces) or "none"}; windows '
            + ', '.join(f'[{w.f_min:g}, {w.f_max:g}] N' for w in cfg.windows)
            + f'; debounce {cfg.debounce}; period {cfg.period:g} s')

    def on_parameters(self, changes: dict[str, Any]) -> None:
        """Apply new impact windows at once (ParameterError, nothing changed, if they contradict each other)."""
        values = {**self.values, **changes}
        self.controller.set_windows(config_from_values(values))
        self.values = values

    def on_start(self, msg: Any) -> None:
        """Take the gait start time (a zero stamp means now, as for the gait node)."""
        stamp = Time.from_msg(msg.stamp).nanoseconds * 1e-9
        if self.start_at >= 0.0 and abs(stamp - self.start_at) < 1e-9:
            return  # the start this node was given already (a restart would forget its halts)
        self.controller.start(stamp if stamp > 0.0 else self.get_clock().now().nanoseconds * 1e-9)

    def on_fsr(self, msg: Any) -> None:
        """Check the sample, update the controller, publish a halt stamped with the sample's stamp.

        In lock-step the decision on every sample is published too (a bad sample decides "no halt"), and a
        sample with the stamp of the one decided last (the bridge resends while it waits) is not taken
        again: its decision is resent.
        """
        last = self._last_decision
        sampled_ns = stamp_ns(msg.header.stamp)
        if self.lockstep and last is not None and sampled_ns <= stamp_ns(last.stamp):
            self.decision_pub.publish(last)
            return
        decided_face = ''   # the decision topic's frame_id: the halting face, '' for no halt
        try:
            sample = check_sample(list(msg.name), list(msg.effort))
            for warning in sample.warnings:
                self.report('bad_values', warning)
            # the robot's board clock, as its gait node reads it (with clock_rate_offset: its own periods)
            t = board_time(sampled_ns * 1e-9, self.controller.start_time, self.clock_rate)
            decision = self.controller.update(t, sample.forces)
            if decision.halt:
                halt = self.Header()
                halt.stamp = msg.header.stamp
                halt.frame_id = decision.face or ''
                self.halt_pub.publish(halt)
                decided_face = decision.face or 'halt'
        except FsrSampleError as err:
            self.report(err.kind, str(err))
        if self.decision_pub is not None:
            decided = self.Header()
            decided.stamp = msg.header.stamp
            decided.frame_id = decided_face
            self._last_decision = decided
            self.decision_pub.publish(decided)

    def destroy_node(self) -> None:
        """Log the robot's summary line (for the launcher: halts decided, FSR samples inside an impact window),
        then destroy the node."""
        c = self.controller.counters
        self.get_logger().info(summary_line(self.robot_id, {'halts': c.halts, 'impact samples': sum(c.in_window)}))
        super().destroy_node()

    def report(self, kind: str, problem: str) -> None:
        """Count a bad message and log it (throttled)."""
        self.bad[kind] = self.bad.get(kind, 0) + 1
        self.last_problem = problem
        self.get_logger().warning(f'robot {self.robot_id}: {problem}', throttle_duration_sec=2.0)

    def publish_diagnostics(self) -> None:
        """Counters and the last problem on /diagnostics (WARN while bad messages arrive)."""
        c = self.controller.counters
        values = {'samples': c.samples, 'halts': c.halts, 'suppressed_impacts': c.suppressed,
                  'before_start': c.before_start, 'bad_values': c.bad_values,
                  **{f'in_window_{face}': n for face, n in zip(topics.FSR_FACES, c.in_window, strict=False)},
                  **{k: v for k, v in self.bad.items() if k != 'bad_values'},
                  'start_time': 'unknown' if self.controller.start_time is None else
                  f'{self.controller.start_time:.3f}', 'last_problem': self.last_problem}
        self.diagnostics.publish(WARN if self.bad else OK, 'bad FSR messages' if self.bad else 'ok', values)
        self.bad = {}


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_feedback feedback`."""
    raise SystemExit(run_node(FeedbackNode, NODE_NAME, args, startup_errors=(ParameterError,)))

if __name__ == '__main__':
    main()
