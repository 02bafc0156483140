"""Composed vs separate: the full demo stack through sim.launch.xml, x real time and CPU per robot.

Runs ``smarticle-launch smarticle_bringup sim.launch.xml`` with the demo's stack (sim bridge, a gait and a
feedback node per robot, glider monitor, bag recorder, plus this script listening to the poses like the
demo does) once per mode, alternating, and measures:

* **x real time**: sim seconds per wall second of the stepping (the sim bridge's own figure: from the
  moment every gait node has answered to the end) and of the whole launch (start-up included);
* **CPU per robot**: CPU seconds of every process of the launch (user + system, all of them reaped),
  per robot and per sim second.

Prints a Markdown table and writes ``out/benchmarks/bringup.csv``. Not a test: run it alone.
Usage: ``python tests/benchmarks/bench_bringup.py [--robots 7] [--periods 20] [--rounds 1]``.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.benchmarks._common import markdown_table, out_path, write_csv

START_AT, PERIOD = 0.5, 1.6


def children_cpu() -> float:
    """CPU seconds (user + system) of every reaped descendant so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run(mode: str, robots: int, periods: float, log_dir: Path) -> dict[str, Any]:
    """One launch of the demo stack in ``mode`` ('composed' or 'separate'); its figures."""
    import rclpy
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    duration = START_AT + periods * PERIOD
    node = rclpy.create_node(f'bench_listener_{mode}')
    stamps: list[int] = []
    node.create_subscription(PoseArray, '/smarticles/poses',
                             lambda m: stamps.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec),
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT))
    bag = log_dir / 'bag'
    cpu0, wall0 = children_cpu(), time.monotonic()
    proc = subprocess.Popen([sys.executable, '-m', 'smarticle_bringup.launcher', 'smarticle_bringup',
                             'sim.launch.xml', f'robots:={robots}', f'duration:={duration!r}',
                             f'composed:={str(mode == "composed").lower()}', 'record:=true', f'bag:={bag}',
                             'wait_for_subscribers:=2', '--log-dir', str(log_dir)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    while proc.poll() is None:
        rclpy.spin_once(node, timeout_sec=0.05)
    wall = time.monotonic() - wall0
    output = proc.communicate()[0]
    cpu = children_cpu() - cpu0
    node.destroy_node()
    if proc.returncode != 0:
        raise RuntimeError(f'{mode}: the launch ended with code {proc.returncode}:\n{output[-2000:]}')
    logs = ''.join(p.read_text(errors='replace') for p in log_dir.glob('*.log'))
    factors = re.findall(r'real-time factor ([0-9.]+)', logs)
    sim = max(stamps) * 1e-9 if stamps else duration
    return {'mode': mode, 'robots': robots, 'periods': periods, 'sim_s': sim,
            'processes': len(list(log_dir.glob('*.log'))), 'x_real_time': float(factors[-1]) if factors else 0.0,
            'x_real_time_with_startup': sim / wall, 'wall_s': wall, 'cpu_s': cpu,
            'cpu_per_robot_per_sim_s': cpu / robots / sim, 'poses_received': len(stamps)}


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print the table, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--periods', type=float, default=20.0)
    parser.add_argument('--rounds', type=int, default=1, help='runs per mode, alternating (default 1)')
    args = parser.parse_args(argv)
    import rclpy
    from smarticle_common.launching import DomainReservation

    reservation = DomainReservation()
    os.environ['ROS_DOMAIN_ID'] = str(reservation.domain_id)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    rclpy.init()
    rows = []
    try:
        with tempfile.TemporaryDirectory(prefix='bench-bringup-') as tmp:
            for i in range(args.rounds):
                for mode in ('separate', 'composed'):
                    row = run(mode, args.robots, args.periods, Path(tmp) / f'{mode}-{i}')
                    print(f'[bench] {mode}: {row["x_real_time"]:.2f}x real time, '
                          f'{row["cpu_per_robot_per_sim_s"]:.3f} CPU s per robot per sim s', flush=True)
                    rows.append(row)
    finally:
        rclpy.try_shutdown()
        reservation.close()
    print(f'\nfull demo stack, {args.robots} robots, {args.periods:g} periods, {os.cpu_count()} cores:\n')
    print(markdown_table(rows, [('mode', 'mode', ''), ('processes', 'processes', 'd'),
                                ('x_real_time', 'x real time (stepping)', '.2f'),
                                ('x_real_time_with_startup', 'x real time (with start-up)', '.2f'),
                                ('cpu_per_robot_per_sim_s', 'CPU s per robot per sim s', '.3f'),
                                ('cpu_s', 'CPU s total', '.1f'), ('poses_received', 'poses received', 'd')]))
    print(f'\nwrote {write_csv(out_path("bringup.csv"), rows)}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
