"""sim.launch.xml through smarticle-launch: poses of every robot, the same trajectory composed or separate,
and the live view's scene over a real WebSocket."""

from __future__ import annotations

import json
import math
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


def foxglove_messages(port: int, schemas: dict[str, str], count: int, timeout: float) -> dict[str, list[bytes]]:
    """Connect to the Foxglove WebSocket server, subscribe to the channels ``schemas`` names (topic -> schema
    name, checked), return their payloads once the first channel has ``count`` (or the time is up)."""
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
    names = list(schemas)
    payloads: dict[str, list[bytes]] = {name: [] for name in names}
    subscribed: set[str] = set()
    with ws:
        while len(payloads[names[0]]) < count and time.monotonic() < deadline:
            message = ws.recv(timeout=max(deadline - time.monotonic(), 0.1))
            if isinstance(message, str):
                data = json.loads(message)
                if data['op'] == 'advertise':
                    wanted = [c for c in data['channels'] if c['topic'] in schemas and c['topic'] not in subscribed]
                    for channel in wanted:
                        assert channel['schemaName'] == schemas[channel['topic']], channel
                        subscribed.add(channel['topic'])
                    ws.send(json.dumps({'op': 'subscribe', 'subscriptions': [
                        {'id': names.index(c['topic']) + 1, 'channelId': c['id']} for c in wanted]}))
            else:
                opcode, subscription, _stamp = message[0], *struct.unpack_from('<IQ', message, 1)
                assert opcode == 1 and 1 <= subscription <= len(names)
                payloads[names[subscription - 1]].append(bytes(message[13:]))
    return payloads


def protobuf_fields(data: bytes) -> list[tuple[int, Any]]:
    """(field number, value) of a protobuf message: varints as int, fixed64 as float, length-delimited as bytes."""
    out: list[tuple[int, Any]] = []
    i = 0

    def varint() -> int:
        nonlocal i
        value, shift = 0, 0
        while True:
            byte = data[i]
            i += 1
            value |= (byte & 0x7F) << shift
            shift += 7
            if byte < 0x80:
                return value
    while i < len(data):
        key = varint()
        number, wire = key >> 3, key & 7
        if wire == 0:
            out.append((number, varint()))
        elif wire == 1:
            out.append((number, struct.unpack_from('<d', data, i)[0]))
            i += 8
        elif wire == 2:
            size = varint()
            out.append((number, data[i:i + size]))
            i += size
        elif wire == 5:
            out.append((number, struct.unpack_from('<f', data, i)[0]))
            i += 4
        else:
            raise ValueError(f'protobuf wire type {wire} not expected')
    return out


def frame_transforms(payload: bytes) -> dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]]:
    """A foxglove.FrameTransforms payload as child frame -> (parent, translation xyz, rotation xyzw)."""
    out = {}
    for _, transform in protobuf_fields(payload):          # field 1: repeated FrameTransform
        fields = dict(protobuf_fields(transform))
        vector = dict(protobuf_fields(fields.get(4, b'')))
        quaternion = dict(protobuf_fields(fields.get(5, b'')))
        out[fields[3].decode()] = (fields[2].decode(), tuple(vector.get(n, 0.0) for n in (1, 2, 3)),
                                   tuple(quaternion.get(n, 0.0) for n in (1, 2, 3, 4)))
    return out


@pytest.mark.integration
def test_the_live_view_sends_scene_updates_and_frames_for_every_robot(tmp_path: Path) -> None:
    port = free_port()
    proc = launch(tmp_path, 'view', 'robots:=2', 'view:=true', f'view_port:={port}', 'wait_for_subscribers:=2')
    try:
        received = foxglove_messages(port, {'/smarticles/scene': 'foxglove.SceneUpdate',
                                            '/tf': 'foxglove.FrameTransforms'}, 60, 40.0)
        payloads = received['/smarticles/scene']
        full = [p for p in payloads if all(f'robot_{k}'.encode() in p for k in range(2))]
        assert len(full) >= 10, (len(payloads), logs(tmp_path, 'view'))
        last = full[-1]                   # bodies and arms as cubes, trails, the robots' ids as labels
        assert b'trail_0' in last and b'trail_1' in last and b'arena' in last
    finally:
        proc.send_signal(signal.SIGINT)
        out = proc.communicate(timeout=30)[0]
    assert proc.returncode == 0, out
    assert 'serving the live view on ws://127.0.0.1' in logs(tmp_path, 'view')
    frames = [frame_transforms(p) for p in received['/tf']]
    children = {f'smarticle_{k}/{link}' for k in range(2) for link in ('body', 'arm1_link', 'arm2_link')}
    complete = [f for f in frames if set(f) == children]
    assert len(complete) >= 10, (len(frames), [sorted(f) for f in frames[:3]])
    for frame in complete:
        for k in range(2):
            assert frame[f'smarticle_{k}/body'][0] == 'arena'
            assert frame[f'smarticle_{k}/arm1_link'][0] == frame[f'smarticle_{k}/arm2_link'][0] == f'smarticle_{k}/body'
            assert math.isclose(sum(v * v for v in frame[f'smarticle_{k}/body'][2]), 1.0, rel_tol=1e-9)
    # over the run the robots move (their body frames) and the gait turns the arms (the arm frames' rotation)
    first, last_frame = complete[0], complete[-1]
    for k in range(2):
        assert math.dist(first[f'smarticle_{k}/body'][1], last_frame[f'smarticle_{k}/body'][1]) > 1e-4
    arm_yaws = {2.0 * math.atan2(f['smarticle_0/arm2_link'][2][2], f['smarticle_0/arm2_link'][2][3]) for f in complete}
    assert max(arm_yaws) - min(arm_yaws) > math.radians(30.0)


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
    proc = launch(tmp_path, 'example', 'robots:=2', 'scene:=pair', 'feedback:=none', 'duration:=2.5',
                  'controller:=smarticle_example_controller/square_stop', 'wait_for_subscribers:=2')
    assert spin_until(node, lambda: commands.get_publisher_count() > 0, 60.0), logs(tmp_path, 'example')
    # the sim waits for this probe's poses subscription (and the glider monitor's), made only once the probe
    # has matched the controller: the run lasts about a second, shorter than discovery on a loaded machine
    node.create_subscription(PoseArray, topics.topic('poses'), lambda m: None,
                             QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
    finished = spin_until(node, lambda: proc.poll() is not None, 90.0)
    out = proc.communicate(timeout=30)[0] if finished else ''
    assert finished and proc.returncode == 0, out + logs(tmp_path, 'example')
    spin_until(node, lambda: False, 0.2)
    assert len(list((tmp_path / 'example').glob('square_stop-*.log'))) == 2
    assert not list((tmp_path / 'example').glob('gait-*.log'))
    corners = {round(math.degrees(abs(a))) for t in targets for a in t}
    assert len(targets) >= 10 and corners == {60}, corners     # the example's amplitude, every command


@pytest.mark.integration
def test_a_failed_bridge_shows_its_reason_on_the_terminal(tmp_path: Path) -> None:
    proc = launch(tmp_path, 'triangle', 'scene:=triangle')
    out = proc.communicate(timeout=120)[0]
    assert proc.returncode == 2, out
    lines = [line for line in out.splitlines() if line.startswith('[launch] /sim_stack ended with exit code 2: ')]
    assert len(lines) == 1 and "sim_bridge.scene must be one of dense, pair, random, got 'triangle'" in lines[0], out
    assert f'[launch]   its output: {tmp_path / "triangle"}/smarticle-compose-0.log' in out, out


@pytest.mark.integration
def test_a_launch_whose_controllers_have_all_failed_ends_at_once_with_their_reason(tmp_path: Path) -> None:
    """Not after the bridge's 120 s start timeout: the robots' own nodes have ended, nothing answers for them."""
    bad = tmp_path / 'bad_amplitude.yaml'
    bad.write_text('/**:\n  ros__parameters:\n    amplitude_deg: 500.0\n', encoding='utf-8')
    started = time.monotonic()
    proc = launch(tmp_path, 'failed', 'robots:=2', 'scene:=pair', 'feedback:=none', f'controller_params:={bad}',
                  'controller:=smarticle_example_controller/square_stop')
    out = proc.communicate(timeout=120)[0]
    assert time.monotonic() - started < 10.0 and proc.returncode != 0, out
    assert 'amplitude_deg must be in (0, 120]' in out and 'has ended (/smarticle_' in out, out
    assert 'Traceback' not in out


@pytest.mark.integration
def test_a_launch_ends_with_each_robots_summary_and_the_glider_report(tmp_path: Path) -> None:
    proc = launch(tmp_path, 'summary', 'robots:=2', 'scene:=pair', 'duration:=2.0', 'composed:=false')
    out = proc.communicate(timeout=120)[0]
    assert proc.returncode == 0, out + logs(tmp_path, 'summary')
    tail = out.splitlines()[-3:]
    for k in range(2):    # 2 s of sim time, a command per 0.05 s publication: about 41 commands
        words = tail[k].split()
        assert words[:3] == ['[launch]', 'robot', f'{k}:'] and 'halts' in words and 'contacts' in words, out
        assert int(words[words.index('commands') + 1].rstrip(',')) >= 40, out
    assert tail[2].startswith('[launch] glider report: '), out
