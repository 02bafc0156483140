"""Offline decode speed of a 500,000-message bag: our columnar and per-message decoders, rosbags, mcap_ros2.

The bag is generated once (``out/benchmarks/work/decode500k``, reused): 7 robots publishing
``joint_states``, ``joint_commands`` and ``fsr`` (sensor_msgs/JointState) plus ``/smarticles/poses``
(PoseArray) and ``/clock``, 23 messages per 10 ms period, serialised with rosbags, written by
``BagWriter`` (zstd chunks of 1 MiB). Every reader decodes every message into values:

* ours, columnar: ``arrays.read_poses``, ``read_robot_topic`` x 3, ``read_clock`` (the default);
* ours, per message: the same calls with ``columnar=False`` (``mcap_ros2`` decoder per message);
* rosbags: ``Reader.messages`` + ``typestore.deserialize_cdr``; rosbags raw: records only;
* mcap_ros2: ``make_reader(...).iter_decoded_messages()``.

Prints a Markdown table (messages/s, best of ``--repeats``; process CPU time and wall time) and writes
``out/benchmarks/bag_decode.csv``. Times are never asserted. Run alone on a quiet machine if you can.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import OUT_DIR, markdown_table, out_path, write_csv

ROBOTS = 7
PERIOD_NS = 10_000_000
T0 = 1_700_000_000_000_000_000
PER_PERIOD = 3 * ROBOTS + 2


def make_bag(folder: Path, messages: int) -> Path:
    """Write the benchmark bag (about ``messages`` messages) unless it exists; return its folder."""
    from rosbags.typesys import Stores, get_typestore

    from smarticle_bags.writer import BagWriter, WriterOptions

    done = folder.with_name(folder.name + '.complete')
    if done.is_file() and (folder / 'metadata.yaml').is_file():
        return folder
    if folder.exists():
        import shutil
        shutil.rmtree(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    periods = math.ceil(messages / PER_PERIOD)

    def header(i: int, frame: str) -> Any:
        sec, nsec = divmod(i * PERIOD_NS, 1_000_000_000)
        return types['std_msgs/msg/Header'](stamp=types['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec),
                                            frame_id=frame)

    def joint_state(i: int, robot: int, names: list[str], kind: int) -> bytes:
        phase = i * 0.01 + robot
        values = np.array([math.sin(phase + k + kind) for k in range(len(names))])
        msg = types['sensor_msgs/msg/JointState'](
            header=header(i, f'smarticle_{robot}'), name=names, position=values,
            velocity=values * 0.5 if kind == 0 else np.array([], dtype=np.float64),
            effort=values * 2.0 if kind == 2 else np.array([], dtype=np.float64))
        return bytes(store.serialize_cdr(msg, 'sensor_msgs/msg/JointState'))

    def poses(i: int) -> bytes:
        items = []
        for k in range(ROBOTS):
            heading = 0.3 * k + i * 1e-4
            items.append(types['geometry_msgs/msg/Pose'](
                position=types['geometry_msgs/msg/Point'](x=0.01 * k + i * 1e-5, y=-0.02 * k, z=0.0),
                orientation=types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(heading / 2),
                                                                  w=math.cos(heading / 2))))
        msg = types['geometry_msgs/msg/PoseArray'](header=header(i, 'arena'), poses=items)
        return bytes(store.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray'))

    def clock(i: int) -> bytes:
        sec, nsec = divmod(i * PERIOD_NS, 1_000_000_000)
        msg = types['rosgraph_msgs/msg/Clock'](clock=types['builtin_interfaces/msg/Time'](sec=sec, nanosec=nsec))
        return bytes(store.serialize_cdr(msg, 'rosgraph_msgs/msg/Clock'))

    joints, faces = ['arm1', 'arm2'], ['front', 'back', 'left', 'right']
    with BagWriter(folder, WriterOptions()) as writer:
        writer.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for robot in range(ROBOTS):
            for key in ('joint_states', 'joint_commands', 'fsr'):
                writer.add_topic(f'/smarticle_{robot}/{key}', 'sensor_msgs/msg/JointState')
        for i in range(periods):
            t = T0 + i * PERIOD_NS
            writer.write('/clock', clock(i), t)
            writer.write('/smarticles/poses', poses(i), t + 1000)
            for robot in range(ROBOTS):
                writer.write(f'/smarticle_{robot}/joint_states', joint_state(i, robot, joints, 0), t + 2000 + robot)
                writer.write(f'/smarticle_{robot}/joint_commands', joint_state(i, robot, joints, 1),
                             t + 3000 + robot)
                writer.write(f'/smarticle_{robot}/fsr', joint_state(i, robot, faces, 2), t + 4000 + robot)
    done.write_text(f'{periods * PER_PERIOD} messages\n')
    return folder


def _best(fn: Callable[[], int], repeats: int) -> tuple[int, float, float]:
    """Run ``fn`` ``repeats`` times; return (its count, best CPU seconds, best wall seconds)."""
    best_cpu, best_wall, count = math.inf, math.inf, 0
    for _ in range(repeats):
        cpu0, wall0 = time.process_time(), time.perf_counter()
        count = fn()
        best_cpu = min(best_cpu, time.process_time() - cpu0)
        best_wall = min(best_wall, time.perf_counter() - wall0)
    return count, best_cpu, best_wall


def readers(bag: Path) -> list[tuple[str, Callable[[], int], bool]]:
    """Return (name, function returning the number of messages decoded, slow) of every reader timed."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.rosbag2 import Reader as RosbagsReader
    from rosbags.typesys import Stores, get_typestore

    from smarticle_bags import arrays
    from smarticle_bags.reader import BagReader

    store = get_typestore(Stores.ROS2_JAZZY)
    files = sorted(bag.glob('*.mcap'))

    def ours(columnar: bool) -> Callable[[], int]:
        def run() -> int:
            reader = BagReader(bag)
            poses = arrays.read_poses(reader, columnar=columnar)
            total = len(poses.stamp)
            for key in ('joint_states', 'joint_commands', 'fsr'):
                total += sum(len(s.stamp) for s in arrays.read_robot_topic(reader, key, columnar).values())
            if columnar:
                total += len(arrays.read_clock(reader).clock)
            else:
                total += sum(1 for _ in reader.decoded(['/clock']))
            return total
        return run

    def rosbags_decoded() -> int:
        count = 0
        with RosbagsReader(bag) as reader:
            for connection, _, data in reader.messages():
                store.deserialize_cdr(data, connection.msgtype)
                count += 1
        return count

    def rosbags_raw() -> int:
        with RosbagsReader(bag) as reader:
            return sum(1 for _ in reader.messages())

    def mcap_ros2() -> int:
        count = 0
        for path in files:
            with path.open('rb') as handle:
                for _ in make_reader(handle, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
                    count += 1
        return count

    return [('ours: columnar (arrays.read_*)', ours(True), False),
            ('ours: per message (arrays.read_*, columnar=False)', ours(False), True),
            ('rosbags: Reader + deserialize_cdr', rosbags_decoded, False),
            ('rosbags: Reader, raw records only', rosbags_raw, False),
            ('mcap_ros2: iter_decoded_messages', mcap_ros2, True)]


def main(argv: list[str] | None = None) -> int:
    """Generate the bag if needed, time every reader, print the table and write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--messages', type=int, default=500_000, help='bag size in messages (default 500,000)')
    parser.add_argument('--repeats', type=int, default=3, help='best of this many runs (slow readers: 1)')
    parser.add_argument('--only', nargs='+', default=None, help='time only readers whose name has these words')
    args = parser.parse_args(argv)
    bag = make_bag(OUT_DIR / 'work' / f'decode{args.messages // 1000}k', args.messages)
    size = sum(p.stat().st_size for p in bag.glob('*.mcap'))
    print(f'# bag decode benchmark: {bag.name}, {size / 2**20:.1f} MiB ({os.cpu_count()} cpus, '
          f'load {os.getloadavg()[0]:.1f})\n', flush=True)
    rows: list[dict[str, Any]] = []
    for name, fn, slow in readers(bag):
        if args.only and not any(word in name for word in args.only):
            continue
        count, cpu, wall = _best(fn, 1 if slow else args.repeats)
        rows.append({'reader': name, 'messages': count, 'cpu s': cpu, 'wall s': wall,
                     'msgs/s (cpu)': count / cpu, 'msgs/s (wall)': count / wall})
        print(f'  {name}: {count} messages, {cpu:.2f} s CPU, {wall:.2f} s wall', file=sys.stderr, flush=True)
    base = next((r for r in rows if r['reader'].startswith('rosbags: Reader + deserialize')), None)
    for row in rows:
        row['vs rosbags'] = row['msgs/s (cpu)'] / base['msgs/s (cpu)'] if base else math.nan
    print(markdown_table(rows, [('reader', 'reader', ''), ('messages', 'messages', 'd'),
                                ('cpu s', 'CPU s', '.2f'), ('wall s', 'wall s', '.2f'),
                                ('msgs/s (cpu)', 'msgs/s (CPU)', ',.0f'),
                                ('msgs/s (wall)', 'msgs/s (wall)', ',.0f'), ('vs rosbags', 'x rosbags', '.2f')]))
    print(f'\nwrote {write_csv(out_path("bag_decode.csv"), rows)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
