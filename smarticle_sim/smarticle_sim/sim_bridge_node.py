"""ROS node `sim_bridge`: the PyBullet world behind the hardware's topics.

For every robot k it subscribes to ``/smarticle_<k>/joint_commands`` and publishes
``/smarticle_<k>/joint_states``, ``/smarticle_<k>/fsr`` (only while someone subscribes) and
``/smarticle_<k>/pose`` (likewise) and latches ``/smarticle_<k>/robot_description``; arena-wide it
publishes ``/smarticles/poses``, ``/tf`` (where tf2_msgs is installed), ``/clock`` and ``/diagnostics``,
and optionally ``/smarticles/start``. Run the gait nodes with ``use_sim_time:=true``
(and ``lockstep:=true`` in lock-step mode). See docs/sim_bridge.md.
"""

from __future__ import annotations

import array
import functools
import re
import time
from typing import Any

import rclpy
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.time import Time
from smarticle_common import topics
from smarticle_common.launching import summary_line
from smarticle_common.messages import pose_message, stamp_msg, stamp_ns
from smarticle_common.node import DiagnosticsPublisher, read_config, run_node
from smarticle_common.robot_tf import RobotModelPublisher
from smarticle_common.params import ParameterError

from .bridge import NODE_NAME, PARAMS, BridgeSettings, SimBridgeCore
from .errors import SimError, SimTrouble

_COMMAND_TOPIC = re.compile(r'^/smarticle_(\d+)/joint_commands$')


def _msg(key: str) -> Any:
    """Message class of contract entry ``key``."""
    return topics.message_class(topics.spec_of(key).type)


#: Wall seconds the bridge waits after the awaited subscribers have matched (their side of the match).
SUBSCRIBER_SETTLE = 0.5
#: Lock-step: wall seconds between two looks, while waiting for commands, at who publishes them.
COMMANDER_CHECK = 0.5
#: Wall seconds between two looks at who listens to the optional per-robot outputs (joint states, poses).
LISTENER_LOOK = 0.05
#: Lock-step: the longest the executor goes without a turn (wall s) when every command is already in at a
#: tick (a composing host hands them over in-process): timers and messages from outside still get their turn
#: (a turn of the executor costs about half a millisecond, so not every tick gets one).
EXECUTOR_LOOK = 0.05


class Lateness:
    """Free mode at a real-time factor: the distribution of how late ticks are published after their due time
    (each tick is computed, then its messages go out at its due time: the lateness is how late their publication
    begins, the wake-up's delay after the wait; the publishing itself, the feedback nodes' callbacks in a
    composing host included, comes after it).

    A histogram of 0.1 ms bins up to 10 s (constant memory however long the run), the maximum, and the ticks
    published more than one tick period late (the next tick was already due: a skipped tick in real time).
    """

    BIN = 1e-4

    def __init__(self, period: float) -> None:
        self.period = period   # wall seconds per tick
        self.bins = [0] * 100_001
        self.ticks = self.behind = 0
        self.worst = 0.0

    def add(self, late: float) -> None:
        """Count one tick published ``late`` wall seconds after its due time (negative: early, counted as 0)."""
        late = max(late, 0.0)
        self.ticks += 1
        self.worst = max(self.worst, late)
        self.behind += late > self.period
        self.bins[min(int(late / self.BIN), len(self.bins) - 1)] += 1

    def quantile(self, q: float) -> float:
        """The ``q`` quantile of the lateness (s), to the bin's upper edge (at most the maximum)."""
        need, seen = q * self.ticks, 0
        for i, n in enumerate(self.bins):
            seen += n
            if seen >= need and n:
                return min((i + 1) * self.BIN, self.worst)
        return self.worst

    def line(self) -> str:
        """The one-line summary the bridge logs at the end of a real-time run."""
        return (f'tick lateness over {self.ticks} ticks: p50 {self.quantile(0.5) * 1e3:.1f} ms, p99 '
                f'{self.quantile(0.99) * 1e3:.1f} ms, max {self.worst * 1e3:.1f} ms; {self.behind} tick(s) more '
                f'than a tick period ({self.period * 1e3:g} ms) late')


class SimBridgeNode(Node):
    """Thin ROS shell around SimBridgeCore."""

    def __init__(self, **node_options: Any) -> None:
        """Build the node; ``node_options`` go to rclpy's Node (a composing host's ``cli_args``)."""
        super().__init__(NODE_NAME, **node_options)
        self.settings = read_config(self, PARAMS, BridgeSettings.from_values)
        try:
            self.core = SimBridgeCore(self.settings)
        except (SimError, ValueError) as err:
            raise ParameterError(f'node {NODE_NAME}: {err}') from err
        n = self.core.n_robots
        self.JointState, self.Clock = _msg('joint_states'), _msg('clock')
        self.PoseArray, self.PoseStamped = _msg('poses'), _msg('pose')
        qos = {key: topics.qos_profile(topics.spec_of(key).qos) for key in topics.BY_KEY}
        self.clock_pub = self.create_publisher(self.Clock, topics.topic('clock'), qos['clock'])
        self.poses_pub = self.create_publisher(self.PoseArray, topics.topic('poses'), qos['poses'])
        self.diagnostics = DiagnosticsPublisher(self, NODE_NAME, 'pybullet')
        self.robot_model = RobotModelPublisher(self, n, self.settings.sim.robot)   # descriptions and /tf
        # per-robot outputs without QoS-event handlers: each one would add two waitables to every
        # executor wait, which dominates the lock-step loop with many robots
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        self.joint_pubs = [self.create_publisher(self.JointState, topics.topic('joint_states', k),
                                                 qos['joint_states'], event_callbacks=quiet) for k in range(n)]
        self.fsr_pubs = [self.create_publisher(self.JointState, topics.topic('fsr', k), qos['fsr'],
                                               event_callbacks=quiet) for k in range(n)]
        #: The FSR messages published at the current time, by robot (resent while the lock-step waits).
        self.fsr_sent: dict[int, Any] = {}
        self.pose_pubs = [self.create_publisher(self.PoseStamped, topics.topic('pose', k), qos['pose'],
                                                event_callbacks=quiet) for k in range(n)]
        for k in range(n):
            self.create_subscription(self.JointState, topics.topic('joint_commands', k),
                                     functools.partial(self.on_command, k), qos['joint_commands'])
        # frames are published reliable (the contract's image QoS; it also serves best-effort subscribers):
        # a 2 MB frame is ~30 UDP fragments, and over best effort one lost fragment loses it (docs/tracking.md)
        self.image_pub = self.create_publisher(_msg('image_raw'), topics.topic('image_raw'), qos['image_raw'])
        self.info_pub = self.create_publisher(_msg('camera_info'), topics.topic('camera_info'), qos['camera_info'])
        self.start_pub = None
        if self.settings.start_at >= 0.0:
            header = _msg('start')
            self.start_pub = self.create_publisher(header, topics.topic('start'), qos['start'])
            start = header()
            start.stamp = Time(nanoseconds=round(self.settings.start_at * 1e9)).to_msg()
            self.start_pub.publish(start)
        self.counts: dict[str, int] = {}
        self.commands_received = 0
        self.published = [0, 0]   # /clock and /smarticles/poses messages published (the run's last log line)
        self.spun = 0.0   # wall time (monotonic) of the executor's last turn in the lock-step wait
        #: Wall time of the next look at the optional outputs' listeners, and the robots each one has.
        self.listeners_due = 0.0
        self.joint_listened: list[int] = []
        self.pose_listened: list[int] = []
        self.reported: set[tuple[str, int]] = set()   # (cause, robot) of bad inputs already logged
        self.warned_ids: set[int] = set()
        #: Robots whose joint commands topic has had a publisher (a commander that may since have exited).
        self.commanded: set[int] = set()
        #: hold:=true: the sim time (ns) up to which a test lets the lock-step run (None: not yet given).
        self.run_until_ns: int | None = None
        if self.settings.hold:
            run_until = topics.spec_of('run_until')
            self.create_subscription(topics.message_class(run_until.type), run_until.resolve(), self.on_run_until,
                                     topics.qos_profile(run_until.qos))
        self.create_timer(2.0, self.scan_for_unknown_robots, clock=rclpy.clock.Clock())
        self.get_logger().info(
            f'{n} robots, scene {self.settings.scene_kind}, '
            f'mode {"lockstep" if self.settings.lockstep else "free"}, '
            f'time step {self.settings.sim.physics.time_step:.6g} s, publishing every '
            f'{self.settings.publish_period:g} s')

    # ------------------------------------------------------------------ callbacks
    def on_command(self, robot: int, msg: Any) -> None:
        """Hand a joint command to the core; report what it dropped or changed."""
        self.commands_received += 1
        stamp = stamp_ns(msg.header.stamp)
        checked = self.core.apply_command(robot, list(msg.name), list(msg.position), list(msg.velocity),
                                          stamp)
        for counter, count in checked.counts.items():
            self.counts[counter] = self.counts.get(counter, 0) + count
        for counter in checked.counts:
            self.report_once(counter, robot, topics.topic('joint_commands', robot), '; '.join(checked.warnings))

    # ------------------------------------------------------------------ bad input
    def publishers_of(self, topic: str) -> str:
        """The nodes publishing ``topic``, by full name (who sent a bad or a missing message)."""
        names = sorted({f'{i.node_namespace.rstrip("/")}/{i.node_name}'
                        for i in self.get_publishers_info_by_topic(topic)})
        return ', '.join(names) if names else f'no node publishes {topic}'

    def report_once(self, cause: str, robot: int, topic: str, problem: str) -> None:
        """Log a bad input once per cause and robot, naming the node that sent it (counted on /diagnostics)."""
        if (cause, robot) in self.reported:
            return
        self.reported.add((cause, robot))
        self.get_logger().warning(f'{self.publishers_of(topic)} (robot {robot}): {problem} [{cause}: counted on '
                                  '/diagnostics, logged once]')

    def scan_for_unknown_robots(self) -> None:
        """Warn (once per id) about joint commands published for robots the scene does not have."""
        for name, _ in self.get_topic_names_and_types():
            match = _COMMAND_TOPIC.match(name)
            if match is None:
                continue
            k = int(match.group(1))
            if k >= self.core.n_robots and k not in self.warned_ids and self.count_publishers(name) > 0:
                self.warned_ids.add(k)
                self.counts['unknown_robot_ids'] = self.counts.get('unknown_robot_ids', 0) + 1
                self.report_once('unknown_robot_ids', k, name, f'commands on {name} dropped: the scene has robots '
                                 f'0..{self.core.n_robots - 1} only')

    def on_run_until(self, msg: Any) -> None:
        """hold:=true: a test lets the sim run up to ``msg.stamp``."""
        self.run_until_ns = Time.from_msg(msg.stamp).nanoseconds

    def held(self) -> bool:
        """hold:=true: the current time is not before the time a test allowed (or none is given yet)."""
        return self.settings.hold and (self.run_until_ns is None or self.core.time_ns >= self.run_until_ns)

    # ------------------------------------------------------------------ outputs
    def publish_outputs(self) -> None:
        """Publish /clock and poses, and joint states, FSR and per-robot poses of robots someone listens to."""
        now = stamp_msg(self.core.time_ns)
        clock = self.Clock()
        clock.clock = now
        self.clock_pub.publish(clock)
        self.published[0] += 1
        physics = self.core.physics
        poses = self.core.poses()   # the bases alone: arms and velocities only for their listeners below
        wall = time.monotonic()
        if wall >= self.listeners_due:   # nobody listens: no message (a new subscriber gets one from the next look)
            self.listeners_due = wall + LISTENER_LOOK
            self.joint_listened = [k for k, pub in enumerate(self.joint_pubs) if pub.get_subscription_count()]
            self.pose_listened = [k for k, pub in enumerate(self.pose_pubs) if pub.get_subscription_count()]
        if self.joint_listened:
            state = physics.state()
            for k in self.joint_listened:
                pub = self.joint_pubs[k]
                msg = self.JointState()
                msg.header.stamp = now
                msg.name = list(topics.JOINT_NAMES)
                msg.position = state.arm_angles[k].tolist()
                msg.velocity = state.arm_velocities[k].tolist()
                pub.publish(msg)
        listened = [k for k, pub in enumerate(self.fsr_pubs) if pub.get_subscription_count() > 0]
        forces = self.core.fsr_sample(listened)   # peaks since the last publication; [] stops the tracking
        self.fsr_sent = {}
        for row, k in enumerate(listened):
            self.publish_fsr(k, now, forces[row])
        array = self.PoseArray()
        array.header.stamp = now
        array.header.frame_id = topics.ARENA_FRAME
        array.poses = [pose_message(p) for p in poses]
        self.poses_pub.publish(array)
        self.published[1] += 1
        tf_pub = self.robot_model.tf_pub
        if tf_pub is not None and tf_pub.get_subscription_count() > 0:
            self.robot_model.publish(now, poses, physics.arm_angles())
        for k in self.pose_listened:
            msg = self.PoseStamped()
            msg.header = array.header
            msg.pose = array.poses[k]
            self.pose_pubs[k].publish(msg)
        if self.core.frame_due():
            if self.image_pub.get_subscription_count() > 0:
                self.publish_frame(now)
            else:
                self.core.skip_frame()   # nobody watches: no rendering at all

    def publish_fsr(self, robot: int, now: Any, forces: Any) -> None:
        """Publish one FSR sample of ``robot`` stamped ``now`` (kept for a resend at the same time)."""
        msg = self.JointState()
        msg.header.stamp = now
        msg.name = list(topics.FSR_FACES)
        msg.effort = forces.tolist()   # the floats of the row, without a Python loop
        self.fsr_sent[robot] = msg
        self.fsr_pubs[robot].publish(msg)

    def resend_fsr(self) -> None:
        """Lock-step, while waiting: publish the current time's FSR samples again (best effort may lose one).

        A robot whose FSR topic found its first subscriber since the publication gets a sample now: the
        force at this instant, which is also the whole sample at the start of a run (no step before it).
        """
        listened = [k for k, pub in enumerate(self.fsr_pubs) if pub.get_subscription_count() > 0]
        new = [k for k in listened if k not in self.fsr_sent]
        for k in listened:
            if k in self.fsr_sent:
                self.fsr_pubs[k].publish(self.fsr_sent[k])
        if new:
            now = Time(nanoseconds=self.core.time_ns).to_msg()
            forces = self.core.fsr_sample(listened)   # no step since the sample: each face's force now
            for row, k in enumerate(listened):
                if k in new:
                    self.publish_fsr(k, now, forces[row])

    def publish_frame(self, now: Any) -> None:
        """Render the overhead frame and publish it (mono8) with its camera_info."""
        frame = self.core.render_frame()
        info = self.core.camera.camera_info()
        image = _msg('image_raw')()
        image.header.stamp = now
        image.header.frame_id = topics.spec_of('image_raw').frame
        image.height, image.width = frame.shape
        image.encoding = 'mono8'
        image.step = frame.shape[1]
        image.data = array.array('B', frame.tobytes())
        self.image_pub.publish(image)
        camera_info = _msg('camera_info')(header=image.header, height=info.height, width=info.width,
                                          distortion_model=info.distortion_model, d=info.d, k=info.k,
                                          r=info.r, p=info.p)
        self.info_pub.publish(camera_info)

    def publish_diagnostics(self, level: int, message: str, rtf: float) -> None:
        """Publish the bridge's status and counters on /diagnostics."""
        self.diagnostics.publish(level, message, {'sim_time': f'{self.core.time:.3f}',
                                                  'real_time_factor': f'{rtf:.2f}', **self.counts,
                                                  **self.robot_model.status()})

    def destroy_node(self) -> None:
        """Log each robot's summary line (for the launcher), release the physics client, then the node."""
        for k in range(self.core.n_robots):
            self.get_logger().info(summary_line(k, self.core.summary(k)))
        self.core.close()
        super().destroy_node()

    # ------------------------------------------------------------------ loop
    def run(self, executor: SingleThreadedExecutor) -> int:
        """Step the physics until the duration is reached or ROS shuts down; return an exit code."""
        settings = self.settings
        end_ns = round(settings.duration * 1e9) if settings.duration > 0 else None
        wall0, sim0 = time.monotonic(), self.core.time
        last_diag = wall0
        self.wait_for_subscribers(executor)
        wall0 = time.monotonic()
        self.publish_outputs()
        first = True
        physics_wall = 0.0   # wall seconds inside the physics (advance), against the time in messages and nodes
        cpu0 = time.process_time()   # CPU seconds of this process (every thread): steadier than wall when shared
        # free mode at a real-time factor: how late each tick's publication came after its wall-clock due time
        lateness = Lateness(settings.publish_period / max(settings.real_time_factor, 1e-9))
        while rclpy.ok():
            if settings.lockstep:
                missed = self.wait_for_commands(executor, first)
                if missed is not None:
                    self.get_logger().error(missed)
                    self.publish_diagnostics(2, missed, 0.0)
                    return 4
                if first:  # the real-time factor counts from the moment every gait node has answered
                    wall0, cpu0, first, physics_wall = time.monotonic(), time.process_time(), False, 0.0
            else:
                for _ in range(self.core.n_robots + 4):
                    executor.spin_once(timeout_sec=0.0)
            if end_ns is not None and self.core.time_ns >= end_ns:
                break
            try:
                stepping = time.monotonic()
                self.core.advance()
                physics_wall += time.monotonic() - stepping
            except SimTrouble as trouble:
                self.get_logger().error(str(trouble))
                self.publish_diagnostics(2, str(trouble), 0.0)
                return 3
            if settings.real_time_factor > 0.0 and not settings.lockstep:
                # the tick's messages go out at its wall-clock due time, not as soon as it is computed
                due = (self.core.time - sim0) / settings.real_time_factor
                ahead = due - (time.monotonic() - wall0)
                if ahead > 0:
                    time.sleep(ahead)
                lateness.add(time.monotonic() - wall0 - due)   # when the tick's publication begins
            self.publish_outputs()
            wall = time.monotonic()
            if wall - last_diag >= 1.0:
                rtf = (self.core.time - sim0) / max(wall - wall0, 1e-9)
                self.publish_diagnostics(0, 'running', rtf)
                last_diag = wall
        wall = max(time.monotonic() - wall0, 1e-9)
        rtf = (self.core.time - sim0) / wall
        per_cpu = (self.core.time - sim0) / max(time.process_time() - cpu0, 1e-9)
        self.get_logger().info(f'done at sim time {self.core.time:.2f} s, real-time factor {rtf:.2f} ({per_cpu:.2f} '
                               f'per CPU second of this process; physics steps and FSR: '
                               f'{min(physics_wall / wall, 1.0):.0%} of the wall time)')
        if lateness.ticks:
            self.get_logger().info(lateness.line())
        self.get_logger().info(f'final poses: sha256 {self.core.poses_digest()}; published: '
                               f'/clock {self.published[0]}, /smarticles/poses {self.published[1]}')
        self.publish_diagnostics(0, 'finished', rtf)
        return 0

    def wait_for_subscribers(self, executor: SingleThreadedExecutor) -> None:
        """Hold the start until /smarticles/poses has the configured number of subscribers.

        The count is the publisher's side of the match; a best-effort subscriber drops what arrives before
        its own side has matched, so once the count is reached the bridge waits SUBSCRIBER_SETTLE more
        seconds (wall time) before the first publication.
        """
        started = time.monotonic()
        while rclpy.ok() and (
                self.poses_pub.get_subscription_count() < self.settings.wait_for_subscribers
                or self.image_pub.get_subscription_count() < self.settings.wait_for_camera_subscribers):
            executor.spin_once(timeout_sec=0.05)
            if time.monotonic() - started > 5.0:
                self.get_logger().warning('waiting for subscribers of /smarticles/poses and '
                                          '/overhead_camera/image_raw', throttle_duration_sec=5.0)
        if self.settings.wait_for_subscribers or self.settings.wait_for_camera_subscribers:
            settle = time.monotonic() + SUBSCRIBER_SETTLE
            while rclpy.ok() and time.monotonic() < settle:
                executor.spin_once(timeout_sec=0.05)

    def wait_for_commands(self, executor: SingleThreadedExecutor, first: bool = False) -> str | None:
        """Lock-step barrier: spin until every robot's command for the current time has arrived (and, with
        hold:=true, a test allows the step); None, or the line saying which node missed the tick.

        A robot whose command has not come within ``tick_timeout`` wall seconds (``start_timeout`` for the
        first tick, which also waits for the nodes to start) ends the wait with that line.
        """
        timeout = self.settings.start_timeout if first else self.settings.tick_timeout
        started = last = time.monotonic()
        # wall time of the last look at the ROS graph for commanders that have gone
        looked = started
        told = 0.0   # wall time of the last 'held' diagnostics
        seen = -1    # commands received when ``missing`` was last computed (only a command can shorten it)
        while rclpy.ok():
            if seen != self.commands_received:
                seen, missing = self.commands_received, self.core.waiting_for()
            held = self.held()
            if not missing and not held:
                if started - self.spun >= EXECUTOR_LOOK:   # commands came in-process: timers and others still run
                    executor.spin_once(timeout_sec=0.0)
                    self.spun = time.monotonic()
                return None
            now = time.monotonic()
            if held and now - told >= 1.0:   # tell the test where the sim stands (its counters too), each second
                told = now
                self.publish_diagnostics(0, 'held', 0.0)
            executor.spin_once(timeout_sec=0.005)
            now = self.spun = time.monotonic()
            if missing and timeout > 0.0 and now - started > timeout:
                return self.missed_tick(missing, timeout)
            if missing and now - looked >= COMMANDER_CHECK:
                looked = now
                gone = self.gone_commanders(missing)
                if gone:
                    return gone
            if now - last > 0.5:  # a gait node that joined late missed the (best-effort) clock: resend
                clock = self.Clock()
                clock.clock = Time(nanoseconds=self.core.time_ns).to_msg()
                self.clock_pub.publish(clock)
                self.published[0] += 1
                self.resend_fsr()   # and a feedback node the sample its gait node waits on
                last = now
                if now - started > 5.0:
                    self.get_logger().warning(f'lock-step: waiting for joint commands of robots {missing} '
                                              f'at sim time {self.core.time:.3f} s', throttle_duration_sec=5.0)
        return None

    def gone_commanders(self, missing: list[int]) -> str | None:
        """The line of robots whose commands nobody publishes any more (a publisher was seen, now none is),
        or None: the node that answered for the robot has exited, so the lock-step would wait in vain."""
        gone = []
        for k in missing:
            if self.count_publishers(topics.topic('joint_commands', k)) > 0:
                self.commanded.add(k)
            elif k in self.commanded or self.core.command_stamp_ns[k] >= 0:   # it sent commands: it was there
                gone.append(k)
        if not gone:
            return None
        return ('lock-step: ' + '; '.join(f'the node publishing {topics.topic("joint_commands", k)} (robot {k}) has '
                                          'exited' for k in gone) + f' at sim time {self.core.time:.3f} s: stopping')

    def missed_tick(self, missing: list[int], timeout: float) -> str:
        """The one line of a missed tick: which node (robot) did not answer which tick, how long it was given."""
        period_ns = round(self.settings.publish_period * 1e9)
        who = '; '.join(f'{self.publishers_of(topics.topic("joint_commands", k))} (robot {k})' for k in missing)
        return (f'lock-step: {who} sent no joint command for the tick at sim time {self.core.time:.3f} s '
                f'(tick {self.core.time_ns // period_ns}) within {timeout:g} s: stopping')


def main(args: list[str] | None = None) -> None:
    """Entry point of `ros2 run smarticle_sim sim_bridge`: the lock-step loop on rclpy's EventsExecutor, whose
    turn for one message costs a fraction of the SingleThreadedExecutor's (the commands of every robot come
    one by one from other processes), as in the composing host."""
    from rclpy.experimental import EventsExecutor

    raise SystemExit(run_node(SimBridgeNode, NODE_NAME, args, executor_factory=EventsExecutor))


if __name__ == '__main__':
    main()
