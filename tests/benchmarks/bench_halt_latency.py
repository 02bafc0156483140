"""Halt latency on the board path: from the first board reply that carries a press to the hold Set Target.

Board emulator in this process (its thread at a raised priority where allowed, as a board's own processor);
servo_bridge, gait and feedback as separate processes over DDS on localhost (tests/helpers/hardware_rig.py).
Every other gait period the emulator's arm1_front input is pressed (11 N, 80 ms) early in quarter 0, while
arm 1 strokes. Both ends are on the emulator's clock:
  reply -> Set Target   the first analog reply of the arm1_front channel at the pressed reading, to the
                        first Set Target after it (the hold of the moving arm)
and, from the same reply (probe receipt times, on the same clock):
  reply -> halt         the feedback node's halt, as received by a probe in this process
  reply -> hold cmd     the gait's hold command, as received by the probe
Prints the machine load (os.getloadavg before and after) and a table (median, 95th percentile, max in ms);
writes CSV under out/benchmarks/.
Usage: nice -n 10 python tests/benchmarks/bench_halt_latency.py [--presses 50]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
from smarticle_common.launching import DomainReservation, ProcessGroup, isolated_ros_env

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers
from tests.benchmarks._common import markdown_table, out_path, write_csv
from tests.helpers.fake_board import running_emulator
from tests.helpers.hardware_rig import FSR_CHANNEL, HardwareRig, volts_for

from smarticle_driver import maestro

PERIOD = 0.8
FACE = 'arm1_front'
NEWTONS = 11.0        # inside the shipped arm1_front window [7.37, 15.07] N
PRESS = 0.08          # s


def spin_to(node: object, wall: float) -> None:
    """Spin ``node`` until time.time() reaches ``wall``."""
    while time.time() < wall:
        rclpy.spin_once(node, timeout_sec=min(0.01, max(wall - time.time(), 0.0)))


def measure(presses: int, workdir: Path) -> list[dict[str, float]]:
    """Run the rig; one row of latencies (s) per press that halted the gait."""
    domain = DomainReservation()
    env = isolated_ros_env(domain.domain_id)
    os.environ.update({k: env[k] for k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')})
    rclpy.init()
    probe = rclpy.create_node('halt_latency_probe')
    rows: list[dict[str, float]] = []
    channel = FSR_CHANNEL[FACE]
    pressed = round(volts_for(FACE, NEWTONS) / maestro.ANALOG_VOLTS * maestro.ANALOG_FULL_SCALE)
    try:
        workdir.mkdir(parents=True, exist_ok=True)
        with running_emulator(workdir / 'maestro') as emulator, ProcessGroup(workdir / 'logs', env) as procs:
            emulator.raise_priority()
            rig = HardwareRig(procs, emulator, probe, period=PERIOD, alpha_max_deg=45.0)
            deadline = time.time() + 30.0
            while not rig.ready() and time.time() < deadline:
                rclpy.spin_once(probe, timeout_sec=0.05)
            if not rig.ready():
                raise RuntimeError('nodes did not connect; see ' + str(workdir / 'logs'))
            rig.start(1.0)
            for i in range(presses):
                n = 2 + 2 * i
                spin_to(probe, rig.period_start(n) + 0.03)
                halts_before = len(rig.observed.halts)
                pressed_at = time.monotonic()
                emulator.set_voltage(channel, volts_for(FACE, NEWTONS))
                spin_to(probe, time.time() + PRESS)
                emulator.set_voltage(channel, 0.0)
                spin_to(probe, rig.period_start(n + 1) - 0.05)
                if len(rig.observed.halts) <= halts_before:
                    print(f'press {i}: no halt', flush=True)
                    continue
                reply = next((r.time for r in emulator.analog_replies()
                              if r.channel == channel and r.time >= pressed_at and r.counts >= pressed), None)
                if reply is None:
                    continue
                hold = next((r.time for r in emulator.targets() if r.time > reply), float('nan'))
                to_mono = -rig.wall_offset     # probe receipts are time.time(); the emulator's time.monotonic()
                halt = rig.observed.halts[halts_before][1] + to_mono
                command = next((c[1] + to_mono for c in rig.observed.commands if c[1] + to_mono > reply), float('nan'))
                rows.append({'press': i, 'reply_to_halt': halt - reply, 'reply_to_hold_cmd': command - reply,
                             'reply_to_set_target': hold - reply})
    finally:
        probe.destroy_node()
        rclpy.try_shutdown()
        domain.close()
    return rows


def main() -> None:
    """Measure, print the load and the table, write the CSV."""
    parser = argparse.ArgumentParser(description=(__doc__ or '').split('\n')[0])
    parser.add_argument('--presses', type=int, default=50, help='presses (one halt each; default 50)')
    args = parser.parse_args()
    # the emulator's thread shares this process with the probe's spinning: hand the GIL over every 0.5 ms
    # (not Python's 5 ms) so that the board's time stamps are not held up by the probe
    sys.setswitchinterval(0.0005)
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        rows = measure(args.presses, Path(tmp))
    load_after = os.getloadavg()
    write_csv(out_path('halt_latency.csv'), rows)
    summary = []
    for key, what in (('reply_to_halt', 'board reply -> halt (probe)'),
                      ('reply_to_hold_cmd', 'board reply -> gait hold command (probe)'),
                      ('reply_to_set_target', 'board reply -> hold Set Target at the board')):
        ms = np.array([r[key] for r in rows], dtype=float) * 1e3
        ms = ms[np.isfinite(ms)]
        summary.append({'stage': what, 'n': int(ms.size),
                        'median': float(np.median(ms)) if ms.size else np.nan,
                        'p95': float(np.percentile(ms, 95)) if ms.size else np.nan,
                        'max': float(ms.max()) if ms.size else np.nan})
    print(f'{os.cpu_count()} cpu(s); load average (1, 5, 15 min) before {load_before[0]:.2f} {load_before[1]:.2f} '
          f'{load_before[2]:.2f}, after {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}; '
          f'{len(rows)} of {args.presses} presses halted')
    print(markdown_table(summary, [('stage', 'stage', ''), ('n', 'presses', 'd'), ('median', 'median (ms)', '.2f'),
                                   ('p95', 'p95 (ms)', '.2f'), ('max', 'max (ms)', '.2f')]))
    print(f'CSV: {out_path("halt_latency.csv")}')


if __name__ == '__main__':
    main()
