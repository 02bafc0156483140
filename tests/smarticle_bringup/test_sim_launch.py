"""sim.launch.xml through smarticle-launch: poses of every robot, the same trajectory composed or separate,
and the live view's scene over a real WebSocket."""

from __future__ import annotations

import json
import signal
import socket
import struct
import subprocess
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from smarticle_common import topics
from tests.helpers.ros import executable, spin_until

PERIODS = 3
DURATION = 0.5 + PERIODS * 1.6          # start_at of stack.yaml + whole periods


def launch(tmp_path: Path, name: str, *arguments: str) -> subprocess.Popen[str]:
    """Start ``smarticle-launch smarticle_bringup sim.launch.xml ARGS`` (its nodes log under tmp_path/name)."""
    return subprocess.Popen([executable('smarticle-launch'), 'smarticle_bringup', 'sim.launch.xml', *arguments,
                             '--log-dir', str(tmp_path / name)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)


def logs(tmp_path: Path, name: str) -> str:
    return '\n'.join(p.read_text(errors='replace')[-1500:] for p in sorted((tmp_path / name).glob('*.log')))


def test_composed_and_separate_runs_give_every_robot_the_same_trajectory(ros_node: Any, tmp_path: Path) -> None:
    """With the feedback nodes (each gait waits for its feedback node's decision on every FSR sample) the
    lock-step path is deterministic: one seed, one trajectory, composed or as separate processes."""
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from smarticle_common.messages import planar_poses

    node = ros_node('sim_launch_probe')
    got: dict[int, np.ndarray] = {}
    node.create_subscription(PoseArray, topics.topic('poses'),
                             lambda m: got.__setitem__(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec,
                                                       planar_poses(m)),
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT))
    runs: dict[str, dict[int, np.ndarray]] = {}
    for composed in ('true', 'false'):
        got.clear()
        proc = launch(tmp_path, composed, 'robots:=2', 'feedback:=true', f'composed:={composed}',
                      f'duration:={DURATION!r}', 'wait_for_subscribers:=2', 'seed:=3')
        finished = spin_until(node, lambda proc=proc: proc.poll() is not None, 90.0)
        out = proc.communicate(timeout=30)[0] if finished else ''
        assert finished and proc.returncode == 0, out + logs(tmp_path, composed)
        spin_until(node, lambda: False, 0.2)
        runs[composed] = dict(got)
        expected = DURATION / 0.05                    # the sim publishes every 0.05 s of sim time
        assert len(got) >= 0.8 * expected, (len(got), out)
        last = got[max(got)]
        assert last.shape == (2, 3) and np.all(np.isfinite(last)), last   # both robots seen
        moved = np.linalg.norm(last[:, :2] - got[min(got)][:, :2], axis=1)
        assert np.all(moved > 0.0)
    assert 'smarticle-compose' in ' '.join(p.name for p in (tmp_path / 'true').iterdir())
    assert len(list((tmp_path / 'false').glob('gait-*.log'))) == 2
    common = sorted(set(runs['true']) & set(runs['false']))
    assert len(common) >= 0.6 * DURATION / 0.05
    composed = np.array([runs['true'][s] for s in common])
    separate = np.array([runs['false'][s] for s in common])
    np.testing.assert_array_equal(composed, separate)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return int(sock.getsockname()[1])


def scene_updates(port: int, count: int, timeout: float) -> list[bytes]:
    """Connect to the Foxglove WebSocket server, subscribe to /smarticles/scene, return ``count`` payloads."""
    from websockets.sync.client import connect

    deadline = time.monotonic() + timeout
    while True:
        try:
            ws = connect(f'ws://127.0.0.1:{port}', subprotocols=['foxglove.sdk.v1', 'foxglove.websocket.v1'],
                         open_timeout=2.0)
            break
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
    payloads: list[bytes] = []
    with ws:
        while len(payloads) < count and time.monotonic() < deadline:
            message = ws.recv(timeout=max(deadline - time.monotonic(), 0.1))
            if isinstance(message, str):
                data = json.loads(message)
                if data['op'] == 'advertise':
                    channels = [c for c in data['channels'] if c['topic'] == '/smarticles/scene']
                    assert channels and channels[0]['schemaName'] == 'foxglove.SceneUpdate', data
                    ws.send(json.dumps({'op': 'subscribe',
                                        'subscriptions': [{'id': 1, 'channelId': channels[0]['id']}]}))
            else:
                opcode, subscription, _stamp = message[0], *struct.unpack_from('<IQ', message, 1)
                assert opcode == 1 and subscription == 1
                payloads.append(bytes(message[13:]))
    return payloads


@pytest.mark.integration
def test_the_live_view_sends_scene_updates_for_every_robot(tmp_path: Path) -> None:
    port = free_port()
    proc = launch(tmp_path, 'view', 'robots:=2', 'view:=true', f'view_port:={port}', 'wait_for_subscribers:=2')
    try:
        payloads = scene_updates(port, 60, 40.0)
        full = [p for p in payloads if all(f'robot_{k}'.encode() in p for k in range(2))]
        assert len(full) >= 10, (len(payloads), logs(tmp_path, 'view'))
        last = full[-1]                   # bodies and arms as cubes, trails, the robots' ids as labels
        assert b'trail_0' in last and b'trail_1' in last and b'arena' in last
    finally:
        proc.send_signal(signal.SIGINT)
        out = proc.communicate(timeout=30)[0]
    assert proc.returncode == 0, out
    assert 'serving the live view on ws://127.0.0.1' in logs(tmp_path, 'view')


def test_the_controller_argument_runs_the_example_controller_in_place_of_the_gait(ros_node: Any,
                                                                                  tmp_path: Path) -> None:
    """controller:=smarticle_example_controller/square_stop: the lock-step runs to its end on the example's
    commands (its own amplitude, 60 deg, not the gait's 90), composed with the user's nodes beside the host."""
    import math

    from sensor_msgs.msg import JointState
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from geometry_msgs.msg import PoseArray

    node = ros_node('controller_probe')
    targets: list[tuple[float, ...]] = []
    commands = node.create_subscription(JointState, topics.topic('joint_commands', 1),
                                        lambda m: targets.append(tuple(m.position)),
                                        QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    # the sim waits for this probe's poses subscription (and the glider monitor's); the probe for the controller
    node.create_subscription(PoseArray, topics.topic('poses'), lambda m: None,
                             QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
    proc = launch(tmp_path, 'example', 'robots:=2', 'scene:=pair', 'feedback:=none', 'duration:=2.5',
                  'controller:=smarticle_example_controller/square_stop', 'wait_for_subscribers:=2')
    assert spin_until(node, lambda: commands.get_publisher_count() > 0, 60.0), logs(tmp_path, 'example')
    finished = spin_until(node, lambda: proc.poll() is not None, 90.0)
    out = proc.communicate(timeout=30)[0] if finished else ''
    assert finished and proc.returncode == 0, out + logs(tmp_path, 'example')
    spin_until(node, lambda: False, 0.2)
    assert len(list((tmp_path / 'example').glob('square_stop-*.log'))) == 2
    assert not list((tmp_path / 'example').glob('gait-*.log'))
    corners = {round(math.degrees(abs(a))) for t in targets for a in t}
    assert len(targets) >= 10 and corners == {60}, corners     # the example's amplitude, every command
