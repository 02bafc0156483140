"""Bag benchmarks: recorder throughput and CPU on the full 7-robot stack, offline decode rate, replay timing.

Three parts, run one after the other (or pick with --part); each prints a Markdown table and writes a
CSV (and the replay part a PNG) under out/benchmarks/:

  record  sim_bridge in free mode at real_time_factor 1.0, publishing every 0.01 s, 7 gait nodes, and
          ``smarticle-bag record`` subscribed to /clock, /smarticles/poses and every robot's fsr and
          joint_states (so the bridge publishes all of them: 16 topics x 100 Hz). Counts what the
          bridge published (one message per topic per publish period, from the first step to the
          last) against what the bag holds, with the recorder's CPU use (from /proc).
  decode  reads the recorded bag (or a sample bag) offline: our reader raw and decoded, our NumPy
          arrays, and the generic decoders: mcap_ros2 (mcap reader + DecoderFactory) and rosbags
          (rosbag2 Reader + deserialize_cdr). Messages per second, best of --repeats.
  replay  ``smarticle-bag play`` of that bag into a subscriber in this process (raw, best effort,
          deep queue); lateness of each message = its arrival minus its bag time, relative to the
          earliest message: median, 99th percentile and maximum, and the share received.

Usage: python tests/benchmarks/bench_bags.py [--quick] [--part record decode replay] [--seconds 60]
--quick: 15 s of sim, 2 decode repeats (under 2 min). Run alone: it starts 10 processes.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import ROOT, figure, markdown_table, out_path, write_csv

from smarticle_bags import arrays
from smarticle_bags.reader import BagReader
from smarticle_bags.recording import start_recording

ROBOTS = 7
PERIOD_S = 0.01
TIME_STEP = 0.005  # 0.01 s must be a whole number of control ticks: 2 physics steps per tick
WORK = ROOT / 'out' / 'benchmarks' / 'bags_work'


def _cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` (Linux /proc)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _topics() -> list[str]:
    """The recorded topics: /clock, poses, and fsr + joint_states of every robot."""
    return ['/clock', '/smarticles/poses'] + [f'/smarticle_{k}/{leaf}' for k in range(ROBOTS)
                                               for leaf in ('fsr', 'joint_states')]


def _stamp_ns(msg: Any) -> int:
    """Header stamp (or /clock time) of a decoded message in ns."""
    stamp = msg.clock if hasattr(msg, 'clock') else msg.header.stamp
    return int(stamp.sec) * 10**9 + int(stamp.nanosec)


def bench_record(seconds: float, bag: Path, log_dir: Path) -> list[dict[str, Any]]:
    """Run the 7-robot free-mode stack with the recorder; return one row per topic group + totals."""
    import rclpy
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from smarticle_common.launching import ProcessGroup

    shutil.rmtree(bag, ignore_errors=True)
    rclpy.init()
    gate = rclpy.create_node('bench_bag_gate')
    try:
        with ProcessGroup(log_dir) as group:
            for k in range(ROBOTS):
                group.start('gait', '--ros-args', '-p', f'robot_id:={k}', '-p', 'use_sim_time:=true')
            rec = start_recording(group, bag, _topics())
            bridge = group.start('sim_bridge', '--ros-args', '-p', f'robots:={ROBOTS}', '-p', 'mode:=free',
                                 '-p', 'real_time_factor:=1.0', '-p', f'publish_period:={PERIOD_S}',
                                 '-p', f'control_tick:={PERIOD_S}', '-p', f'time_step:={TIME_STEP}',
                                 '-p', f'duration:={seconds}', '-p', 'wait_for_subscribers:=2')
            if not rec.wait_subscribed(timeout=60.0):
                raise RuntimeError('recorder did not subscribe:\n' + group.output(rec.proc)[-2000:])
            time.sleep(2.0)  # discovery: the bridge matches every recorder subscription
            cpu0, wall0 = _cpu_seconds(rec.proc.pid), time.monotonic()
            gate.create_subscription(PoseArray, '/smarticles/poses', lambda _m: None,
                                     QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
            while bridge.poll() is None:
                rclpy.spin_once(gate, timeout_sec=0.1)
            time.sleep(0.5)
            cpu1, wall1 = _cpu_seconds(rec.proc.pid), time.monotonic()
            log = group.output(bridge)
            if bridge.returncode != 0:
                raise RuntimeError(f'sim bridge exited with {bridge.returncode}:\n{log[-2000:]}')
            rec.stop()
    finally:
        gate.destroy_node()
        rclpy.try_shutdown()
    rtf = float(log.rsplit('real-time factor', 1)[1].split()[0])
    reader = BagReader(bag, strict=True)
    published_each = round(seconds / PERIOD_S) + 1  # stamps 0, period, ..., duration on every topic
    groups: dict[str, dict[str, Any]] = {}
    for topic in _topics():
        stamps = sorted(_stamp_ns(m) for _, m in reader.decoded([topic]))
        kind = topic.rsplit('/', 1)[1] if topic.startswith('/smarticle_') else topic
        row = groups.setdefault(kind, {'topics': kind, 'n topics': 0, 'published': 0, 'recorded': 0,
                                       'lost': 0, 'duplicates': 0})
        row['n topics'] += 1
        row['published'] += published_each
        row['recorded'] += len(stamps)
        row['lost'] += published_each - len(set(stamps))
        row['duplicates'] += len(stamps) - len(set(stamps))
    wall = wall1 - wall0
    size = sum(f.stat().st_size for f in bag.iterdir())
    total = {key: sum(r[key] for r in groups.values()) for key in ('n topics', 'published', 'recorded', 'lost',
                                                                    'duplicates')}
    rows = list(groups.values()) + [{'topics': 'all', **total}]
    for row in rows:
        row['per s'] = row['recorded'] / wall
    rows[-1].update({'sim s': seconds, 'wall s': wall, 'bridge RTF': rtf,
                     'recorder CPU %': 100.0 * (cpu1 - cpu0) / wall, 'bag MiB': size / 2**20,
                     'bag KiB/s': size / 1024 / wall})
    return rows


def _best(fn: Callable[[], int], repeats: int) -> tuple[int, float]:
    """(count, best wall seconds) of ``repeats`` calls of ``fn``."""
    best, count = float('inf'), 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        count = fn()
        best = min(best, time.perf_counter() - t0)
    return count, best


def bench_decode(bag: Path, repeats: int) -> list[dict[str, Any]]:
    """Offline read and decode rates of every message of ``bag`` with our reader and generic ones."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.rosbag2 import Reader as RosbagsReader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    files = sorted(bag.glob('*.mcap')) if bag.is_dir() else [bag]

    def ours_raw() -> int:
        return sum(1 for _ in BagReader(bag).messages())

    def ours_decoded() -> int:
        return sum(1 for _ in BagReader(bag).decoded())

    def ours_arrays() -> int:
        reader = BagReader(bag)
        poses = arrays.read_poses(reader)
        joints = arrays.read_robot_topic(reader, 'joint_states')
        fsr = arrays.read_fsr(reader)
        return len(poses.stamp) + sum(len(s.log_time) for s in [*joints.values(), *fsr.values()])

    def generic_mcap_ros2() -> int:
        count = 0
        for path in files:
            with path.open('rb') as handle:
                for _ in make_reader(handle, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
                    count += 1
        return count

    def generic_rosbags() -> int:
        count = 0
        with RosbagsReader(bag) as reader:
            for connection, _, data in reader.messages():
                store.deserialize_cdr(data, connection.msgtype)
                count += 1
        return count

    rows = []
    for name, fn, what in (('ours: raw CDR (BagReader.messages)', ours_raw, 'read only'),
                           ('ours: decoded (BagReader.decoded)', ours_decoded, 'all topics'),
                           ('ours: NumPy arrays (read_poses/read_robot_topic/read_fsr)', ours_arrays,
                            'poses, joints, FSR'),
                           ('generic: mcap + mcap_ros2 DecoderFactory', generic_mcap_ros2, 'all topics'),
                           ('generic: rosbags Reader + deserialize_cdr', generic_rosbags, 'all topics')):
        count, wall = _best(fn, repeats)
        rows.append({'reader': name, 'what': what, 'messages': count, 'best s': wall,
                     'msgs/s': count / wall})
    return rows


def bench_replay(bag: Path, rate: float, log_dir: Path) -> tuple[list[dict[str, Any]], np.ndarray]:
    """Play ``bag`` into a raw subscriber; return a summary row per topic group and all lateness (ms)."""
    import rclpy
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from smarticle_common import topics as contract
    from smarticle_common.launching import ProcessGroup

    reader = BagReader(bag)
    names = [t for t in sorted(reader.topics) if t != '/smarticles/start']
    expected: dict[tuple[str, bytes], int] = {}
    for raw in reader.messages(names):
        expected[(raw.topic, raw.data)] = raw.log_time
    arrivals: list[tuple[str, int, int]] = []  # topic, arrival ns, bag log time
    rclpy.init()
    node = rclpy.create_node('bench_bag_replay')
    deep = QoSProfile(depth=10000, reliability=ReliabilityPolicy.BEST_EFFORT)
    for name in names:
        def on_raw(data: bytes, topic: str = name) -> None:
            now = time.monotonic_ns()
            arrivals.append((topic, now, expected.get((topic, bytes(data)), -1)))
        node.create_subscription(contract.message_class(reader.topics[name].type), name, on_raw, deep, raw=True)
    try:
        with ProcessGroup(log_dir) as group:
            player = group.start('smarticle-bag', 'play', str(bag), '--topics', *names, '-r', f'{rate:g}',
                                 '-d', '3.0')
            deadline = time.monotonic() + 3.0 + reader.info.duration / 1e9 / rate + 60.0
            while player.poll() is None and time.monotonic() < deadline:
                rclpy.spin_once(node, timeout_sec=0.01)
            end = time.monotonic() + 1.0
            while time.monotonic() < end:
                rclpy.spin_once(node, timeout_sec=0.01)
            if player.returncode != 0:
                raise RuntimeError('player failed:\n' + group.output(player)[-2000:])
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    got = [(topic, t, b) for topic, t, b in arrivals if b >= 0]
    offsets = np.array([t - b / rate for _, t, b in got], dtype=np.float64)
    late = (offsets - offsets.min()) / 1e6
    rows = []
    by_kind: dict[str, list[float]] = {}
    sent_by_kind: dict[str, int] = {}
    for (topic, _, _), value in zip(got, late, strict=True):
        kind = topic.rsplit('/', 1)[1] if topic.startswith('/smarticle_') else topic
        by_kind.setdefault(kind, []).append(value)
    for raw_topic in names:
        kind = raw_topic.rsplit('/', 1)[1] if raw_topic.startswith('/smarticle_') else raw_topic
        sent_by_kind[kind] = sent_by_kind.get(kind, 0) + reader.topics[raw_topic].message_count
    for kind, values in [*sorted(by_kind.items()), ('all', list(late))]:
        v = np.array(values)
        sent = sum(sent_by_kind.values()) if kind == 'all' else sent_by_kind[kind]
        rows.append({'topics': kind, 'in bag': sent, 'received': len(v), 'received %': 100.0 * len(v) / sent,
                     'median ms': float(np.median(v)), 'p99 ms': float(np.percentile(v, 99)),
                     'max ms': float(v.max()), 'rate': rate,
                     'bag msgs/s': sum(sent_by_kind.values()) / (reader.info.duration / 1e9) * rate})
    return rows, late


def main(argv: list[str] | None = None) -> int:
    """Run the chosen parts and print their tables."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--part', nargs='+', choices=('record', 'decode', 'replay'),
                        default=['record', 'decode', 'replay'])
    parser.add_argument('--seconds', type=float, default=60.0, help='sim seconds recorded (default 60)')
    parser.add_argument('--repeats', type=int, default=5, help='decode repeats (best of; default 5)')
    parser.add_argument('--rate', type=float, default=1.0, help='replay rate (default 1.0)')
    parser.add_argument('--bag', type=Path, default=None,
                        help='bag for decode/replay (default: the one the record part writes, else '
                             'bags/samples/dense7)')
    parser.add_argument('--quick', action='store_true', help='15 s of sim and 2 decode repeats')
    args = parser.parse_args(argv)
    if args.quick:
        args.seconds, args.repeats = min(args.seconds, 15.0), min(args.repeats, 2)
    from smarticle_common.launching import DomainReservation, isolated_ros_env

    reservation = DomainReservation()
    os.environ.update(isolated_ros_env(reservation.domain_id))
    recorded = WORK / 'stack7'
    print(f'# bag benchmarks ({os.cpu_count()} cpus, load {os.getloadavg()[0]:.1f})\n', flush=True)
    try:
        if 'record' in args.part:
            rows = bench_record(args.seconds, recorded, WORK / 'logs_record')
            print(f'## recorder: 7-robot free-mode stack, {args.seconds:g} s at RTF 1.0, every {PERIOD_S} s\n')
            print(markdown_table(rows, [('topics', 'topics', ''), ('n topics', 'n', 'd'),
                                        ('published', 'published', 'd'), ('recorded', 'recorded', 'd'),
                                        ('lost', 'lost', 'd'), ('duplicates', 'dup', 'd'),
                                        ('per s', 'msgs/s', '.0f')]))
            last = rows[-1]
            print(f'\nwall {last["wall s"]:.1f} s, bridge real-time factor {last["bridge RTF"]:.2f}, recorder CPU '
                  f'{last["recorder CPU %"]:.0f} % of one core, bag {last["bag MiB"]:.2f} MiB '
                  f'({last["bag KiB/s"]:.0f} KiB/s)\n', flush=True)
            write_csv(out_path('bags_record.csv'), rows)
        bag = args.bag or (recorded if (recorded / 'metadata.yaml').exists() else ROOT / 'bags/samples/dense7')
        if 'decode' in args.part:
            rows = bench_decode(bag, args.repeats)
            print(f'## offline decode of {bag.relative_to(ROOT) if bag.is_relative_to(ROOT) else bag}\n')
            print(markdown_table(rows, [('reader', 'reader', ''), ('what', 'what', ''),
                                        ('messages', 'messages', 'd'), ('best s', 'best s', '.3f'),
                                        ('msgs/s', 'msgs/s', ',.0f')]) + '\n', flush=True)
            write_csv(out_path('bags_decode.csv'), rows)
        if 'replay' in args.part:
            rows, late = bench_replay(bag, args.rate, WORK / 'logs_replay')
            print(f'## replay timing of {bag.name} at rate {args.rate:g} (lateness vs bag time)\n')
            print(markdown_table(rows, [('topics', 'topics', ''), ('in bag', 'in bag', 'd'),
                                        ('received', 'received', 'd'), ('received %', 'recv %', '.1f'),
                                        ('median ms', 'median ms', '.2f'), ('p99 ms', 'p99 ms', '.2f'),
                                        ('max ms', 'max ms', '.1f')]) + '\n', flush=True)
            write_csv(out_path('bags_replay.csv'), rows)
            fig = figure(6.0, 4.0)
            ax = fig.add_subplot(1, 1, 1)
            ax.hist(late, bins=100, log=True)
            ax.set_xlabel('lateness against bag time (ms)')
            ax.set_ylabel('messages')
            ax.set_title(f'replay of {bag.name} at rate {args.rate:g}: median {np.median(late):.2f} ms, '
                         f'p99 {np.percentile(late, 99):.2f} ms', fontsize=9)
            fig.savefig(out_path('bags_replay.png'))
    finally:
        reservation.close()
    print(f'wrote CSV/PNG under {out_path("x").parent}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
