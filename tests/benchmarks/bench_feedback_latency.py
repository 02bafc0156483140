"""Halt latency of the hardware path: FSR sample -> feedback -> gait -> servo bridge -> Set Target bytes.

Board emulator in this process; servo_bridge, gait and feedback as separate processes over DDS on
localhost. Every other gait period the emulator's arm1_front input is pressed (2 N, 30 ms) early in
quarter 0, while arm 1 strokes. Per halt it measures, from the stamp of the triggering FSR sample (the
halt message carries it):
  hold_cmd     the gait's hold command (its joint_commands stamp: when the gait node acted on the halt)
  set_target   the hold Set Target received by the emulator (the servo target actually changed)
Prints a table (median, 95th percentile, max in ms) and writes CSV under out/benchmarks/.
Usage: python tests/benchmarks/bench_feedback_latency.py [--halts 20] [--quick]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
from smarticle_driver.launching import DomainReservation, ProcessGroup, isolated_ros_env

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers
from tests.benchmarks._common import markdown_table, out_path, write_csv
from tests.smarticle_driver.fake_board_helpers import running_emulator
from tests.smarticle_feedback.hardware_rig import HardwareRig

PERIOD = 0.8


def spin_to(node: object, wall: float) -> None:
    """Spin ``node`` until time.time() reaches ``wall``."""
    while time.time() < wall:
        rclpy.spin_once(node, timeout_sec=min(0.01, max(wall - time.time(), 0.0)))


def measure(halts: int, workdir: Path) -> list[dict[str, float]]:
    """Run the rig and return one row of latencies (s) per halt."""
    import os

    domain = DomainReservation()
    env = isolated_ros_env(domain.domain_id)
    os.environ.update({k: env[k] for k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')})
    rclpy.init()
    probe = rclpy.create_node('feedback_latency_probe')
    rows: list[dict[str, float]] = []
    try:
        with running_emulator(workdir / 'maestro') as emulator, ProcessGroup(workdir / 'logs', env) as procs:
            rig = HardwareRig(procs, emulator, probe, period=PERIOD, alpha_max_deg=45.0)
            deadline = time.time() + 30.0
            while not rig.ready() and time.time() < deadline:
                rclpy.spin_once(probe, timeout_sec=0.05)
            if not rig.ready():
                raise RuntimeError('nodes did not connect; see ' + str(workdir / 'logs'))
            rig.start(1.0)
            for i in range(halts):
                n = 2 + 2 * i
                spin_to(probe, rig.period_start(n) + 0.03)
                before = len(rig.observed.halts)
                rig.pulse('arm1_front', 2.0)
                spin_to(probe, rig.period_start(n + 1) - 0.05)
                if len(rig.observed.halts) <= before:
                    continue
                stamp = rig.observed.halts[before][0]
                hold = [c for c in rig.observed.commands if c[0] >= stamp - 1e-6]
                targets = rig.targets_between(stamp, rig.period_start(n + 1) - 0.05)
                rows.append({'halt': i,
                             'hold_cmd': hold[0][0] - stamp if hold else float('nan'),
                             'set_target': rig.wall(targets[0]) - stamp if targets else float('nan')})
    finally:
        probe.destroy_node()
        rclpy.try_shutdown()
        domain.close()
    return rows


def main() -> None:
    """Measure, print the table, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--halts', type=int, default=20)
    parser.add_argument('--quick', action='store_true', help='5 halts')
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = measure(5 if args.quick else args.halts, Path(tmp))
    write_csv(out_path('feedback_latency.csv'), rows)
    summary = []
    for key, what in (('hold_cmd', 'FSR stamp -> gait hold command'),
                      ('set_target', 'FSR stamp -> hold Set Target at the board')):
        ms = np.array([r[key] for r in rows]) * 1e3
        ms = ms[np.isfinite(ms)]
        summary.append({'stage': what, 'n': int(ms.size), 'median': float(np.median(ms)) if ms.size else np.nan,
                        'p95': float(np.percentile(ms, 95)) if ms.size else np.nan,
                        'max': float(ms.max()) if ms.size else np.nan})
    write_csv(out_path('feedback_latency_summary.csv'), summary)
    print(markdown_table(summary, [('stage', 'stage', ''), ('n', 'halts', 'd'), ('median', 'median (ms)', '.2f'),
                                   ('p95', 'p95 (ms)', '.2f'), ('max', 'max (ms)', '.2f')]))
    print(f'CSV: {out_path("feedback_latency.csv")}')


if __name__ == '__main__':
    main()
