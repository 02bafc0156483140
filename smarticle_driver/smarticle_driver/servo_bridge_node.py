"""ROS node `servo_bridge`: joint commands to a Pololu Maestro, joint states and FSR forces back.

A lifecycle (managed) node: configure opens the port and seeds the joint models from the board, activate
drives the servos, deactivate holds the arms, cleanup closes the port; ``autostart`` (default true) takes
it to active by itself (``ros2 lifecycle set /smarticle_<k>/servo_bridge ...`` for manual control).

Subscribes ``/smarticle_<k>/joint_commands``; publishes ``/smarticle_<k>/joint_states`` (servo slew
model: the Maestro reports commanded, not measured, pulses), ``/smarticle_<k>/fsr`` (newtons) at
``fsr_rate_hz`` and ``/diagnostics``. All the work is in ``servo_bridge_core.ServoBridgeCore``; see
docs/servo_bridge.md.

Threads: the FSR step runs in its own thread (``fsr-step``) on a fixed 1/fsr_rate_hz grid; joint commands
and diagnostics run in the executor's thread. A command therefore goes to the board while a step is in
progress, waiting (on the core's lock) for at most the one board transaction under way. An exception in
the step thread is re-raised in the executor's thread, so it ends ``rclpy.spin`` as a timer's would.
"""

from __future__ import annotations

import math
import re
import sys
import threading
import time
from typing import Any

from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn

from smarticle_common import topics
from smarticle_driver.errors import DriverError
from smarticle_common.node import WARN as WARN_LEVEL
from smarticle_common.node import DiagnosticsPublisher, read_config, resolve_robot_id, run_node
from smarticle_common.params import ParameterError
from smarticle_driver.servo_bridge_core import (NODE_NAME, PARAMS, BridgeConfig, ServoBridgeCore, StepResult,
                                                load_calibration)

#: Seconds between two log lines of the same kind of warning.
WARN_THROTTLE = 2.0
_NUMBERS = re.compile(r'[-+]?(\d+(\.\d*)?|nan|inf)')


class ServoBridgeNode(LifecycleNode):
    """Thin ROS shell around ServoBridgeCore, as a managed (lifecycle) node.

    unconfigured -> configure: open the port and seed the joint models from the board's pulses (fails,
    staying unconfigured, when the port cannot be opened) -> inactive -> activate: joint commands drive the
    servos, the step thread samples the FSRs and publishes -> active -> deactivate: the step thread stops
    and the arms hold where they are; commands are ignored -> inactive -> cleanup: close the port ->
    unconfigured. Shutdown from any state closes the port. With ``autostart`` (default) the node takes
    itself to active, retrying configure every ``reconnect_max`` seconds until the port opens.
    """

    def __init__(self, **node_options: Any) -> None:
        """Read and check the parameters and calibration files; open nothing (that is configure's job)."""
        super().__init__(NODE_NAME, **node_options)
        self.config = read_config(self, PARAMS, lambda v: BridgeConfig.from_values(
            {**v, 'robot_id': resolve_robot_id(self, v['robot_id'])}))
        self.calibration = load_calibration(self.config)      # a bad file stops start-up (exit code 2)
        self.core: ServoBridgeCore | None = None
        self.active = False
        self.ignored_commands = 0
        self._warned: dict[str, tuple[float, int]] = {}
        self._warned_lock = threading.Lock()
        k = self.config.robot_id
        self._joint_state = topics.message_class('sensor_msgs/msg/JointState')
        self.diagnostics = DiagnosticsPublisher(self, f'smarticle_{k}/{NODE_NAME}', self.config.port)
        self.diag_timer = self.create_timer(self.config.diagnostics_period, self.on_diagnostics)
        self._step_error: BaseException | None = None
        self._step_failed = self.create_guard_condition(self._raise_step_error)
        self._stop = threading.Event()
        self._stepper: threading.Thread | None = None
        self.joint_pub: Any = None
        self.fsr_pub: Any = None
        self.command_sub: Any = None
        self._autostart_timer = (self.create_timer(0.0, self._autostart) if self.config.autostart else None)
        self.get_logger().info(
            f'robot {k}: {self.config.board} board on {self.config.port}, servos on channels '
            f'{self.config.servo_channels}, FSRs on {self.config.fsr_channels} at '
            f'{self.config.fsr_rate_hz:g} Hz; '
            f'calibration {self.config.servo_calibration_path()} and {self.config.fsr_calibration_path()}; '
            + ('autostart' if self.config.autostart else 'waiting for lifecycle transitions'))

    # ------------------------------------------------------------------ lifecycle
    def _autostart(self) -> None:
        """configure, then activate; a port that does not open is tried again every reconnect_max s."""
        timer = self._autostart_timer
        assert timer is not None
        if self.trigger_configure() != TransitionCallbackReturn.SUCCESS:
            timer.timer_period_ns = round(self.config.reconnect_max * 1e9)      # try again later
            return
        timer.cancel()
        self.trigger_activate()

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Open the port and seed the board's joint models; FAILURE (nothing kept) if it does not open."""
        core = ServoBridgeCore.from_config(self.config, self.calibration)
        opened, warnings = core.open(time.monotonic())
        if not opened:
            core.close()
            self.get_logger().error(f'configure: cannot open the board: {"; ".join(warnings)}',
                                    throttle_duration_sec=10.0)
            return TransitionCallbackReturn.FAILURE
        self._warn(warnings)
        self.core = core
        k = self.config.robot_id
        states, fsr, commands = (topics.spec_of(key) for key in ('joint_states', 'fsr', 'joint_commands'))
        self.joint_pub = self.create_lifecycle_publisher(self._joint_state, states.resolve(k),
                                                         topics.qos_profile(states.qos))
        self.fsr_pub = self.create_lifecycle_publisher(self._joint_state, fsr.resolve(k), topics.qos_profile(fsr.qos))
        self.command_sub = self.create_subscription(self._joint_state, commands.resolve(k), self.on_command,
                                                    topics.qos_profile(commands.qos))
        self.get_logger().info(f'configured: port {self.config.port} opened, joint models seeded from the board')
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start the step thread; joint commands drive the servos from now on."""
        self._stop.clear()
        self._stepper = threading.Thread(target=self._step_loop, name='fsr-step', daemon=True)
        self.active = True
        result = super().on_activate(state)       # activates the lifecycle publishers
        self._stepper.start()
        self.get_logger().info('active: following joint commands')
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop the step thread and hold the arms where they are; commands are ignored until activate."""
        self.active = False
        self._stop_stepper()
        if self.core is not None:
            self._warn(self.core.hold(time.monotonic()))
        self.get_logger().info('inactive: arms held, joint commands ignored')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the port and drop the publishers and the command subscription."""
        self._release()
        self.get_logger().info(f'unconfigured: port {self.config.port} closed')
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop stepping and close the port, from any state."""
        self.active = False
        self._stop_stepper()
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """An error in a transition: stop and close everything, back to unconfigured."""
        return self.on_shutdown(state)

    def _release(self) -> None:
        if self.core is not None:
            self.core.close()
            self.core = None
        for pub in (self.joint_pub, self.fsr_pub):
            if pub is not None:
                self.destroy_lifecycle_publisher(pub)
        if self.command_sub is not None:
            self.destroy_subscription(self.command_sub)
        self.joint_pub = self.fsr_pub = self.command_sub = None

    def _stop_stepper(self) -> None:
        self._stop.set()
        if (self._stepper is not None and self._stepper.is_alive()
                and self._stepper is not threading.current_thread()):
            self._stepper.join()
        self._stepper = None

    def on_command(self, msg: Any) -> None:
        """Pass a joint command to the core and log what was wrong with it (ignored unless active)."""
        if not self.active or self.core is None:
            self.ignored_commands += 1
            return
        warnings = self.core.handle_command(list(msg.name), list(msg.position), list(msg.velocity),
                                            time.monotonic())
        self._warn(warnings)

    def _step_loop(self) -> None:
        """Body of the step thread: ``on_step`` every 1/fsr_rate_hz s on a fixed grid (late ticks skipped), and
        the core's ``service`` at its own deadlines in between (the watchdog fires at its timeout, not at the
        next step)."""
        period = 1.0 / self.config.fsr_rate_hz
        due = time.monotonic()
        try:
            while not self._stop.is_set():
                if time.monotonic() >= due:
                    self.on_step()
                    due += period
                    late = time.monotonic() - due
                    if late > 0.0:
                        due += math.ceil(late / period) * period
                else:
                    self.on_service()
                core = self.core
                deadline = core.next_deadline() if core is not None else None
                wake = due if deadline is None else min(due, deadline)
                self._stop.wait(max(wake - time.monotonic(), 0.0))
        except BaseException as err:     # a bug: end the node from the executor's thread, as a timer would
            self._step_error = err
            self._step_failed.trigger()

    def _raise_step_error(self) -> None:
        if self._step_error is not None:
            raise self._step_error

    def on_step(self) -> None:
        """Run one bridge step and publish joint states and FSR forces."""
        core = self.core
        if core is None:
            return
        result = core.step(time.monotonic())
        for event in result.events:
            self.get_logger().info(event)
        self._warn(result.warnings)
        self._publish(result)

    def on_service(self) -> None:
        """Run the core's watchdog and pending sends between two steps (at its deadline)."""
        core = self.core
        if core is None:
            return
        result = core.service(time.monotonic())
        for event in result.events:
            self.get_logger().info(event)
        self._warn(result.warnings)

    def on_diagnostics(self) -> None:
        """Poll the board's error flags and publish the bridge's status (and lifecycle state) on /diagnostics."""
        core = self.core
        if core is None:
            self.diagnostics.publish(WARN_LEVEL, f'unconfigured: port {self.config.port} closed',
                                     {'lifecycle': 'unconfigured', 'port': self.config.port})
            return
        self._warn(core.poll_board_errors())
        status = core.status(time.monotonic())
        values = {**status.values, 'lifecycle': 'active' if self.active else 'inactive',
                  'ignored_commands': str(self.ignored_commands)}
        message = status.message if self.active else f'inactive: {status.message}'
        self.diagnostics.publish(int(status.level), message, values)

    def destroy_node(self) -> None:
        """Stop the step thread, close the serial port, then destroy the node."""
        self.active = False
        self._stop_stepper()
        if self.core is not None:
            self.core.close()
        super().destroy_node()

    def _publish(self, result: StepResult) -> None:
        """Publish the FSR sample first (a press is on its way to the feedback node sooner), then joint states."""
        stamp = self.get_clock().now().to_msg()
        if result.fsr_newtons is not None:
            msg = self._joint_state()
            msg.header.stamp = stamp
            msg.name = list(topics.FSR_FACES)
            msg.effort = list(result.fsr_newtons)
            self._send(self.fsr_pub, msg)
        if result.joint_positions is not None and result.joint_velocities is not None:
            msg = self._joint_state()
            msg.header.stamp = stamp
            msg.name = list(topics.JOINT_NAMES)
            msg.position = list(result.joint_positions)
            msg.velocity = list(result.joint_velocities)
            self._send(self.joint_pub, msg)

    def _send(self, publisher: Any, msg: Any) -> None:
        """Publish, except while shutting down (Ctrl-C or SIGTERM can end the context during a step)."""
        try:
            publisher.publish(msg)
        except RuntimeError:        # rclpy's RCLError: "publisher's context is invalid"
            if self.context.ok():
                raise

    def _warn(self, warnings: list[str]) -> None:
        """Log warnings, each kind (the text without its numbers) at most once per WARN_THROTTLE."""
        now = time.monotonic()
        for text in warnings:
            kind = _NUMBERS.sub('#', text)
            with self._warned_lock:      # the step thread and the executor's thread both warn
                last, skipped = self._warned.get(kind, (-WARN_THROTTLE, 0))
                if now - last < WARN_THROTTLE:
                    self._warned[kind] = (last, skipped + 1)
                    continue
                self._warned[kind] = (now, 0)
            more = f' ({skipped} similar warnings not shown)' if skipped else ''
            self.get_logger().warning(text + more)


#: Seconds a Python thread may hold the GIL while another waits (Python's default is 0.005): the command
#: thread gets it from the step thread within this, so a hold is not kept waiting for a whole step.
GIL_SWITCH_INTERVAL = 0.0005


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_driver servo_bridge`."""
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    raise SystemExit(run_node(ServoBridgeNode, NODE_NAME, args, startup_errors=(ParameterError, DriverError)))

if __name__ == '__main__':
    main()
