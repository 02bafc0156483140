"""Halt latency of the hardware path: FSR sample -> feedback -> gait -> servo bridge -> Set Target bytes.

Board emulator in this process; servo_bridge, gait and feedback as separate processes over DDS on
localhost. Every other gait period the emulator's arm1_front input is pressed (15 N, 30 ms) early in
quarter 0, while arm 1 strokes. Per halt it measures, from the stamp of the triggering FSR sample (the
halt message carries it):
  hold_cmd     the gait's hold command (its joint_commands stamp: when the gait node acted on the halt)
  set_target   the hold Set Target received by the emulator (the servo target actually changed)
  last_leg     set_target - hold_cmd: gait -> servo_bridge -> serial (one DDS hop and the bridge)
and the CPU time of the servo_bridge process over the run (% of one core).
Prints a table (median, 95th percentile, max in ms) and writes CSV under out/benchmarks/.

``--baseline REF`` compares the working tree's servo_bridge with the one of git revision REF (its
``smarticle_driver`` package, extracted to a temporary folder and put first on the bridge's PYTHONPATH;
gait and feedback are the working tree's) or of REF = a folder holding a ``smarticle_driver`` package
(a ``setup.py`` beside the inner ``smarticle_driver/``); repeat it for more variants. ``--rounds`` rounds
run every variant once each, in an order rotated by one per round, each a fresh start of the three
processes with ``--halts`` halts, and the table pools each variant's rounds.
Usage: python tests/benchmarks/bench_feedback_latency.py [--halts 20] [--quick] [--baseline HEAD --rounds 4]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
from smarticle_common.launching import DomainReservation, ProcessGroup, isolated_ros_env

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers
from tests.benchmarks._common import ROOT, markdown_table, out_path, write_csv
from tests.helpers.fake_board import running_emulator
from tests.helpers.hardware_rig import HardwareRig

PERIOD = 0.8
WORKING_TREE = 'working tree'


class BridgeFromSource(ProcessGroup):
    """A ProcessGroup that runs servo_bridge with ``source`` (a smarticle_driver package folder) first on
    its PYTHONPATH, so the bridge's code comes from there; every other executable is unchanged."""

    def __init__(self, log_dir: Path, env: dict[str, str], source: Path | None) -> None:
        super().__init__(log_dir, env)
        self.source = source

    def start(self, name: str, *args: str, env: dict[str, str] | None = None) -> subprocess.Popen[bytes]:
        if name == 'servo_bridge' and self.source is not None:
            path = [str(self.source)] + [p for p in (self.env or {}).get('PYTHONPATH', '').split(os.pathsep) if p]
            env = {**(env or {}), 'PYTHONPATH': os.pathsep.join(path)}
        return super().start(name, *args, env=env)


def extract_package(ref: str, into: Path) -> Path:
    """Extract ``smarticle_driver/`` of git revision ``ref`` into ``into``; return its package folder.

    A ``ref`` that is a package folder already is returned as it is.
    """
    if (Path(ref) / 'smarticle_driver' / 'servo_bridge_node.py').is_file():
        return Path(ref).resolve()
    into.mkdir(parents=True, exist_ok=True)
    archive = into / 'source.tar'
    with archive.open('wb') as handle:
        subprocess.run(['git', '-C', str(ROOT), 'archive', ref, 'smarticle_driver'], stdout=handle, check=True)
    with tarfile.open(archive) as tar:
        if hasattr(tarfile, 'data_filter'):    # Python >= 3.10.12 / 3.11.4
            tar.extractall(into, filter='data')
        else:  # pragma: no cover
            tar.extractall(into)
    return into / 'smarticle_driver'


def cpu_seconds(pid: int) -> float:
    """User + system CPU time (s) of process ``pid`` so far (Linux /proc)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def spin_to(node: object, wall: float) -> None:
    """Spin ``node`` until time.time() reaches ``wall``."""
    while time.time() < wall:
        rclpy.spin_once(node, timeout_sec=min(0.01, max(wall - time.time(), 0.0)))


def measure(halts: int, workdir: Path, bridge_source: Path | None = None) -> tuple[list[dict[str, float]], float]:
    """Run the rig; return one row of latencies (s) per halt and the bridge's CPU use (% of one core)."""
    domain = DomainReservation()
    env = isolated_ros_env(domain.domain_id)
    os.environ.update({k: env[k] for k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')})
    rclpy.init()
    probe = rclpy.create_node('feedback_latency_probe')
    rows: list[dict[str, float]] = []
    try:
        workdir.mkdir(parents=True, exist_ok=True)
        with running_emulator(workdir / 'maestro') as emulator, \
                BridgeFromSource(workdir / 'logs', env, bridge_source) as procs:
            rig = HardwareRig(procs, emulator, probe, period=PERIOD, alpha_max_deg=45.0)
            deadline = time.time() + 30.0
            while not rig.ready() and time.time() < deadline:
                rclpy.spin_once(probe, timeout_sec=0.05)
            if not rig.ready():
                raise RuntimeError('nodes did not connect; see ' + str(workdir / 'logs'))
            if bridge_source is not None and str(bridge_source) not in procs.output(rig.bridge):
                raise RuntimeError(f'the servo_bridge did not load its code from {bridge_source}')
            rig.start(1.0)
            cpu0, wall0 = cpu_seconds(rig.bridge.pid), time.monotonic()
            for i in range(halts):
                n = 2 + 2 * i
                spin_to(probe, rig.period_start(n) + 0.03)
                before = len(rig.observed.halts)
                rig.pulse('arm1_front', 11.0)     # inside the shipped arm1_front window [7.37, 15.07] N
                spin_to(probe, rig.period_start(n + 1) - 0.05)
                if len(rig.observed.halts) <= before:
                    continue
                stamp = rig.observed.halts[before][0]
                hold = [c for c in rig.observed.commands if c[0] >= stamp - 1e-6]
                targets = rig.targets_between(stamp, rig.period_start(n + 1) - 0.05)
                hold_cmd = hold[0][0] - stamp if hold else float('nan')
                set_target = rig.wall(targets[0]) - stamp if targets else float('nan')
                rows.append({'halt': i, 'hold_cmd': hold_cmd, 'set_target': set_target,
                             'last_leg': set_target - hold_cmd})
            cpu = 100.0 * (cpu_seconds(rig.bridge.pid) - cpu0) / (time.monotonic() - wall0)
    finally:
        probe.destroy_node()
        rclpy.try_shutdown()
        domain.close()
    return rows, cpu


def summarise(rows: list[dict[str, object]], variant: str, cpu: list[float]) -> list[dict[str, object]]:
    """Median, p95 and max (ms) of each stage of ``variant``'s rows, and the bridge's mean CPU use."""
    summary: list[dict[str, object]] = []
    for key, what in (('hold_cmd', 'FSR stamp -> gait hold command'),
                      ('set_target', 'FSR stamp -> hold Set Target at the board'),
                      ('last_leg', 'gait hold command -> Set Target (last leg)')):
        ms = np.array([r[key] for r in rows if r['variant'] == variant], dtype=float) * 1e3
        ms = ms[np.isfinite(ms)]
        summary.append({'variant': variant, 'stage': what, 'n': int(ms.size),
                        'median': float(np.median(ms)) if ms.size else np.nan,
                        'p95': float(np.percentile(ms, 95)) if ms.size else np.nan,
                        'max': float(ms.max()) if ms.size else np.nan,
                        'bridge_cpu': float(np.mean(cpu)) if cpu else np.nan})
    return summary


def main() -> None:
    """Measure, print the table, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--halts', type=int, default=20, help='halts per run (per round with --baseline)')
    parser.add_argument('--quick', action='store_true', help='5 halts')
    parser.add_argument('--baseline', metavar='REF', action='append', default=[],
                        help="also run the servo_bridge of git revision REF (e.g. HEAD) or of a package "
                        "folder, alternating with the working tree's; may be repeated")
    parser.add_argument('--rounds', type=int, default=4, help='rounds with --baseline (each runs every variant)')
    args = parser.parse_args()
    halts = 5 if args.quick else args.halts
    rows: list[dict[str, object]] = []
    cpu: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        variants: list[tuple[str, Path | None]] = [(WORKING_TREE, None)]
        for i, ref in enumerate(args.baseline):
            variants.append((ref, extract_package(ref, Path(tmp) / f'baseline{i}')))
        rounds = args.rounds if args.baseline else 1
        for r in range(rounds):
            k = r % len(variants)
            for j, (name, source) in enumerate(variants[k:] + variants[:k]):
                run, used = measure(halts, Path(tmp) / f'run{r}-{j}', source)
                print(f'round {r + 1}/{rounds} {name}: {len(run)} halts, bridge CPU {used:.0f} %', flush=True)
                rows += [{'variant': name, 'round': r, **row} for row in run]
                cpu.setdefault(name, []).append(used)
    write_csv(out_path('feedback_latency.csv'), rows)
    summary = []
    for name, _ in variants:
        summary += summarise(rows, name, cpu.get(name, []))
    write_csv(out_path('feedback_latency_summary.csv'), summary)
    columns = [('stage', 'stage', ''), ('n', 'halts', 'd'), ('median', 'median (ms)', '.2f'),
               ('p95', 'p95 (ms)', '.2f'), ('max', 'max (ms)', '.2f'), ('bridge_cpu', 'bridge CPU (%)', '.0f')]
    if args.baseline:
        columns.insert(0, ('variant', 'servo_bridge', ''))
    print(markdown_table(summary, columns))
    print(f'CSV: {out_path("feedback_latency.csv")}')


if __name__ == '__main__':
    main()
