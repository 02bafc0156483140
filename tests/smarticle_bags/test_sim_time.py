"""Bags in the sim's time, over real DDS: a recorder with use_sim_time stamps log time with /clock.

A lock-step sim runs several times faster than real time; recorded with ``record:=true`` its bag lasts
the simulated time (and so plays in it at rate 1), read back with our reader and with ``rosbags``.
"""

from __future__ import annotations

import signal
import subprocess
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest
from rosbags.rosbag2 import Reader as RosbagsReader

from smarticle_bags import arrays
from smarticle_bags.reader import BagReader
from smarticle_bags.timebase import NS, TimeBase, time_base

from tests.helpers.bags import make_sim_bag
from tests.helpers.ros import NodeProcesses, executable, spin_until

pytestmark = pytest.mark.integration

DURATION = 20.0
TICK = 0.05          # the sim bridge's publish period


def test_a_recorded_lockstep_launch_lasts_its_sim_time(tmp_path: Path) -> None:
    bag = tmp_path / 'bag'
    proc = subprocess.run([executable('smarticle-launch'), 'smarticle_bringup', 'sim.launch.xml', 'robots:=2',
                           'scene:=pair', 'feedback:=false', f'duration:={DURATION!r}', 'record:=true',
                           f'bag:={bag}', '--log-dir', str(tmp_path / 'logs')],
                          capture_output=True, text=True, timeout=240)
    logs = '\n'.join(p.read_text(errors='replace')[-1500:] for p in sorted((tmp_path / 'logs').glob('*.log')))
    assert proc.returncode == 0, proc.stdout + proc.stderr + logs
    reader = BagReader(bag, strict=True)
    assert time_base(reader.info) == (TimeBase.SIM, True)
    # the bag spans the simulated run from its first tick, whatever the sim's speed against the wall clock
    assert reader.info.starting_time <= 2 * TICK * NS, reader.info.starting_time
    assert reader.info.duration / NS == pytest.approx(DURATION, abs=2 * TICK), logs
    with RosbagsReader(bag) as other:
        assert other.start_time == reader.info.starting_time
        assert (other.duration - 1) / NS == pytest.approx(DURATION, abs=2 * TICK)   # rosbags: end - start + 1
    # every pose is logged at the sim time it carries (its header stamp), within a few ticks
    poses = arrays.read_poses(reader)
    lag = poses.log_time - poses.stamp          # both in s
    assert len(lag) >= 0.9 * DURATION / TICK
    assert np.median(np.abs(lag)) <= TICK and np.all(np.abs(lag) <= 5 * TICK), lag


def test_record_use_sim_time_holds_messages_until_the_first_clock(
        nodes: NodeProcesses, ros_node: Callable[[str], Any], tmp_path: Path) -> None:
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Header

    out = tmp_path / 'bag'
    proc = nodes.start('smarticle-bag', 'record', '/smarticles/start', '/smarticle_7/joint_states', '-o', str(out),
                       '--use-sim-time', '--polling-interval', '0.1', '--flush-interval', '0.2')
    node = ros_node('sim_time_test')
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    start = node.create_publisher(Header, '/smarticles/start', latched)
    start.publish(Header(frame_id='go'))            # before any /clock: held, then logged at the first one
    joints = node.create_publisher(JointState, '/smarticle_7/joint_states',
                                   QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    clock = node.create_publisher(Clock, '/clock', QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    assert spin_until(node, lambda: joints.get_subscription_count() > 0 and start.get_subscription_count() > 0
                      and clock.get_subscription_count() > 0, 20.0), nodes.output(proc)
    spin_until(node, lambda: False, 0.5)           # the latched start reaches the recorder, which holds it
    for i, sim in enumerate((5.0, 5.5, 6.0)):
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = int(sim), round((sim % 1) * 1e9)
        clock.publish(msg)
        spin_until(node, lambda: False, 0.3)
        joints.publish(JointState(name=['arm1'], position=[0.1 * i]))
        spin_until(node, lambda: False, 0.3)
    proc.send_signal(signal.SIGINT)                 # the bag is closed with a footer
    assert proc.wait(timeout=20) == 0, nodes.output(proc)
    got = [(raw.topic, raw.log_time) for raw in BagReader(out, strict=True).messages()]
    assert got == [('/smarticles/start', 5 * NS), ('/smarticle_7/joint_states', 5 * NS),
                   ('/smarticle_7/joint_states', 5 * NS + NS // 2), ('/smarticle_7/joint_states', 6 * NS)], got
    assert 'log time: sim time from /clock' in nodes.output(proc)


def test_play_of_a_sim_bag_lasts_its_sim_time(nodes: NodeProcesses, ros_node: Callable[[str], Any],
                                              tmp_path: Path) -> None:
    """Log times from sim time 0 pace the replay: at rate 1, 2 s of sim take 2 s."""
    import time

    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Bool

    count = make_sim_bag(tmp_path / 'sim', 2.0, step=0.1)
    node = ros_node('sim_play_test')
    reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    arrivals: list[float] = []
    node.create_subscription(PoseArray, '/smarticles/poses', lambda _msg: arrivals.append(time.monotonic()), reliable)
    proc = nodes.start('smarticle-bag', 'play', str(tmp_path / 'sim'), '-r', '1', '--start-paused')
    pause = node.create_publisher(Bool, '/player/pause', reliable)
    assert spin_until(node, lambda: pause.get_subscription_count() > 0
                      and node.count_publishers('/smarticles/poses') > 0, 20.0), nodes.output(proc)
    spin_until(node, lambda: False, 0.5)           # both directions matched before the first message
    pause.publish(Bool(data=False))
    assert spin_until(node, lambda: len(arrivals) == count, 20.0), nodes.output(proc)
    assert proc.wait(timeout=15) == 0
    assert arrivals[-1] - arrivals[0] == pytest.approx(2.0, abs=0.3)
    assert '2.000 s of sim time in 2.000 s' in nodes.output(proc)
