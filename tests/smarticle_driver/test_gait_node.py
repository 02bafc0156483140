"""The `gait` node in its own process: synchronised start, the square gait on the wire, halt, bad params."""

from __future__ import annotations

import math
import subprocess
import time
from pathlib import Path

import pytest

from smarticle_common import topics
from smarticle_common.gait import GaitConfig, SquareGait, board_time
from tests.helpers.ros import executable, spin_until

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.integration
def test_gait_node_follows_start_and_halt(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Header

    nodes.start('gait', '--ros-args', '-p', 'robot_id:=2', '-p', 'alpha_max_deg:=60.0',
                '-p', 'period:=0.8', '-p', 'servo_speed:=10.5', '-p', 'heartbeat:=0.05')
    node = ros_node('gait_probe')
    got: list[tuple[float, tuple[float, ...]]] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 2),
                             lambda m: got.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                                                   tuple(m.position))),
                             topics.qos_profile(topics.Qos.COMMAND))
    start_pub = node.create_publisher(Header, topics.topic('start'), topics.qos_profile(topics.Qos.LATCHED))
    halt_pub = node.create_publisher(Header, topics.topic('halt', 2), topics.qos_profile(topics.Qos.COMMAND))
    assert spin_until(node, lambda: len(got) >= 2, 15.0), 'no commands before the start'
    a = math.radians(60.0)
    assert got[-1][1] == pytest.approx((a, a))  # start pose held before the start

    t0 = time.time() + 0.5
    msg = Header()
    msg.stamp.sec, msg.stamp.nanosec = int(t0), int((t0 % 1) * 1e9)
    start_pub.publish(msg)
    spin_until(node, lambda: time.time() > t0 + 1.7, 5.0)
    # every command carries the gait's targets at its stamp (the gait node's clock)
    reference = SquareGait(GaitConfig.from_degrees(60.0, period=0.8, servo_speed=10.5))
    reference.start(t0)
    started = [(t, pos) for t, pos in got if t >= t0]
    mismatched = [(t - t0, pos) for t, pos in started
                  if pos != pytest.approx(reference.command(t).targets, abs=1e-9)]
    assert len(started) > 20 and not mismatched
    seen = {tuple(round(v / a) for v in pos) for _, pos in started}
    assert seen == {(-1, 1), (-1, -1), (1, -1), (1, 1)}

    halt_pub.publish(Header())
    spin_until(node, lambda: False, 0.3)
    held = got[-1][1]
    count = len(got)
    spin_until(node, lambda: False, 0.25)
    assert len(got) > count and all(pos == held for _, pos in got[count:]), 'arms must hold after a halt'
    # within one period the next gait period begins and the targets move on from the held pose
    spin_until(node, lambda: got[-1][1] != held, 1.0)
    assert got[-1][1] != held, 'the gait must resume at the next period'


@pytest.mark.integration
def test_gait_node_clock_rate_offset_runs_its_gait_clock_fast(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    """clock_rate_offset 0.05: the gait sees t0 + (t - t0) * 1.05, the same board_time as the batch path."""
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Header

    nodes.start('gait', '--ros-args', '-p', 'robot_id:=1', '-p', 'alpha_max_deg:=60.0', '-p', 'period:=0.8',
                '-p', 'servo_speed:=10.5',
                '-p', 'heartbeat:=0.05', '-p', 'clock_rate_offset:=0.05')
    node = ros_node('gait_clock_probe')
    got: list[tuple[float, tuple[float, ...]]] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 1),
                             lambda m: got.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                                                   tuple(m.position))),
                             topics.qos_profile(topics.Qos.COMMAND))
    start_pub = node.create_publisher(Header, topics.topic('start'), topics.qos_profile(topics.Qos.LATCHED))
    assert spin_until(node, lambda: len(got) >= 2, 15.0), 'no commands before the start'
    t0 = time.time() + 0.5
    msg = Header()
    msg.stamp.sec, msg.stamp.nanosec = int(t0), int((t0 % 1) * 1e9)
    start_pub.publish(msg)
    spin_until(node, lambda: time.time() > t0 + 2.5, 6.0)
    reference = SquareGait(GaitConfig.from_degrees(60.0, period=0.8, servo_speed=10.5))
    reference.start(t0)
    started = [(t, pos) for t, pos in got if t >= t0]
    assert len(started) > 30
    assert all(pos == pytest.approx(reference.command(board_time(t, t0, 1.05)).targets, abs=1e-9)
               for t, pos in started)
    plain = SquareGait(GaitConfig.from_degrees(60.0, period=0.8, servo_speed=10.5))
    plain.start(t0)
    assert any(pos != pytest.approx(plain.command(t).targets, abs=1e-9) for t, pos in started)


def test_invalid_parameter_stops_startup_with_a_clear_error() -> None:
    proc = subprocess.run([executable('gait'), '--ros-args', '-p', 'alpha_max_deg:=150.0'],
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode != 0
    assert 'alpha_max_deg' in proc.stdout + proc.stderr and 'maximum' in proc.stdout + proc.stderr


def test_the_namespace_names_the_robot_and_a_disagreeing_robot_id_is_refused(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    """`-r __ns:=/smarticle_3` makes the node /smarticle_3/gait serving robot 3; robot_id 2 there is refused."""
    from sensor_msgs.msg import JointState

    node = ros_node('namespace_probe')
    seen: list[str] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 3), lambda m: seen.append('3'),
                             topics.qos_profile(topics.spec_of('joint_commands').qos))
    nodes.start('gait', '--ros-args', '-r', '__ns:=/smarticle_3', '-p', 'autostart:=true')
    assert spin_until(node, lambda: bool(seen), 20.0), 'no commands on /smarticle_3/joint_commands'
    assert spin_until(node, lambda: ('gait', '/smarticle_3') in node.get_node_names_and_namespaces(), 20.0), \
        node.get_node_names_and_namespaces()     # the graph (node names) is discovered apart from topics
    proc = subprocess.run([executable('gait'), '--ros-args', '-r', '__ns:=/smarticle_3', '-p', 'robot_id:=2'],
                          capture_output=True, text=True, timeout=30)
    assert proc.returncode == 2
    assert 'disagrees with its namespace /smarticle_3' in proc.stdout + proc.stderr


@pytest.mark.integration
def test_alpha_max_changes_at_run_time_and_bad_changes_are_refused(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    from sensor_msgs.msg import JointState

    from tests.helpers.params import get_parameter, set_parameter

    proc = nodes.start('gait', '--ros-args', '-r', '__ns:=/smarticle_4', '-p', 'alpha_max_deg:=60.0',
                '-p', 'period:=0.8', '-p', 'servo_speed:=10.5', '-p', 'heartbeat:=0.05', '-p', 'autostart:=true')
    node = ros_node('gait_params_probe')
    got: list[tuple[float, ...]] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 4), lambda m: got.append(tuple(m.position)),
                             topics.qos_profile(topics.Qos.COMMAND))
    assert spin_until(node, lambda: len(got) >= 5, 15.0), nodes.output(proc)
    target = '/smarticle_4/gait'
    for name, value, reason in (('alpha_max_deg', 150.0, 'range'), ('alpha_max_deg', 'wide', 'type'),
                                ('period', 1.6, 'read-only'), ('phase', 0.5, 'read-only')):
        ok, why = set_parameter(node, target, name, value)
        assert not ok and why, (name, value)
        assert reason in why.lower() or (reason == 'range' and 'max' in why.lower()), why
    assert get_parameter(node, target, 'alpha_max_deg') == 60.0 and get_parameter(node, target, 'period') == 0.8
    assert set_parameter(node, target, 'alpha_max_deg', 30.0) == (True, '')
    assert get_parameter(node, target, 'alpha_max_deg') == 30.0
    count = len(got)
    spin_until(node, lambda: False, 2.0)                 # > 2 periods: the new square is in use
    amplitudes = [round(math.degrees(max(abs(v) for v in pos)), 6) for pos in got[count:]]
    assert amplitudes[0] == 60.0 and amplitudes[-10:] == [30.0] * 10     # the old square until its period ends
    assert sorted(set(amplitudes)) == [30.0, 60.0] and amplitudes == sorted(amplitudes, reverse=True)


def test_a_start_at_on_another_clock_is_refused_in_one_line_at_once() -> None:
    """start_at:=0.0 on a board's wall clock is 1970: refused with one line, not a spin through 56 years of
    quarter periods deaf to signals."""
    began = time.monotonic()
    proc = subprocess.run([executable('gait'), '--ros-args', '-p', 'start_at:=0.0'],
                          capture_output=True, text=True, timeout=30)
    took = time.monotonic() - began
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1, lines
    assert 'start_at' in lines[0] and 'more than one period (1.6 s) in the past' in lines[0], lines[0]
    assert took < 5.0, f'{took:.1f} s'     # about 0.5 s: the import of rclpy and one clock reading


@pytest.mark.integration
def test_a_wall_clock_start_at_starts_the_gait_there(nodes, ros_node) -> None:  # type: ignore[no-untyped-def]
    """start_at in seconds since 1970 (board.launch.xml's start_at:=...): the gait starts at that instant."""
    from sensor_msgs.msg import JointState

    t0 = round(time.time() + 4.0, 3)
    proc = nodes.start('gait', '--ros-args', '-p', 'robot_id:=6', '-p', 'alpha_max_deg:=60.0', '-p', 'period:=0.8',
                       '-p', 'servo_speed:=10.5', '-p', 'heartbeat:=0.05', '-p', f'start_at:={t0}')
    node = ros_node('gait_start_at_probe')
    got: list[tuple[float, tuple[float, ...]]] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 6),
                             lambda m: got.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                                                   tuple(m.position))),
                             topics.qos_profile(topics.Qos.COMMAND))
    assert spin_until(node, lambda: bool(got) and got[-1][0] > t0 + 1.7, 15.0), nodes.output(proc)
    reference = SquareGait(GaitConfig.from_degrees(60.0, period=0.8, servo_speed=10.5))
    reference.start(t0)
    a = math.radians(60.0)
    assert all(pos == pytest.approx((a, a)) for t, pos in got if t < t0)           # the start pose until t0
    started = [(t, pos) for t, pos in got if t >= t0]
    assert len(started) > 20
    assert all(pos == pytest.approx(reference.command(t).targets, abs=1e-9) for t, pos in started)
    assert f'starting at t = {t0:.3f} s' in nodes.output(proc)


@pytest.mark.integration
def test_a_halt_at_the_time_of_the_last_tick_holds_the_arms(ros_node) -> None:  # type: ignore[no-untyped-def]
    """On sim time the clock moves once per /clock message, so a halt (free-running mode) often comes at the
    very time of the gait's last tick: it holds the arms there (it used to stop the node, 'time went
    backwards')."""
    import rclpy
    from rclpy.parameter import Parameter
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Header

    from smarticle_driver.gait_node import GaitNode

    probe = ros_node('clock_probe')
    clock_pub = probe.create_publisher(Clock, '/clock', 10)
    node = GaitNode(parameter_overrides=[Parameter('use_sim_time', value=True), Parameter('autostart', value=True),
                                         Parameter('tick_rate', value=1.0)])
    try:
        stamp = Clock()
        stamp.clock.sec, stamp.clock.nanosec = 2, 337_500_000      # a time inside a gait quarter
        deadline = time.monotonic() + 10.0
        while node.get_clock().now().nanoseconds != 2_337_500_000 and time.monotonic() < deadline:
            clock_pub.publish(stamp)
            rclpy.spin_once(node, timeout_sec=0.05)
        assert node.get_clock().now().nanoseconds == 2_337_500_000, 'the node never took the sim time'
        node.on_tick()                                   # starts the gait and evaluates it at now
        moving = node._last_targets                      # the corner the tick's command sent the arms to
        node.on_halt(Header())                           # a halt at the same sim time
        assert node.halts == 1
        held = node.gait.command(node.gait_clock(node.now_seconds()) + 0.01)
        assert held.halted and held.targets == held.positions
        assert moving is not None and moving != held.targets   # on its way to a corner: now it holds
    finally:
        node.destroy_node()
