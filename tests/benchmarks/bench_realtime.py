"""Real time held: the composed stack in free-running mode at real time, and how late its ticks come.

The sim bridge in ``mode:=free`` at ``real_time_factor:=1`` with 7 robots (dense, seed 1, the shipped
stack.yaml), a gait and a feedback node per robot (not lock-step: the gait on its own timer in sim time, halts
on /smarticle_<k>/halt) and the glider monitor, composed in one process (``smarticle-compose``, EventsExecutor),
plus the recorder as its own process (``smarticle-bag record --use-sim-time``, the topics of sim.launch.xml's
record:=true), for ``--minutes`` wall minutes (default 10). The bridge measures, for every tick, how late its
publication came after the tick's wall-clock due time, and logs the distribution at the end; this script prints
it: p50, p99 and the maximum, and the ticks more than one tick period late (skipped in real time). Targets:
p99 <= 2 ms, no tick skipped. Exit code 0 when both hold.

Usage: ``python tests/benchmarks/bench_realtime.py [--minutes 10] [--robots 7] [--no-recorder]``.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers

from smarticle_common.launching import DomainReservation, executable, isolated_ros_env

from tests.benchmarks._common import machine_line

ROOT = Path(__file__).resolve().parents[2]
STACK_YAML = ROOT / 'smarticle_bringup' / 'config' / 'stack.yaml'
RECORDED = ('/smarticles/poses', '/clock', '/smarticles/start', '/smarticles/gliders', '/smarticles/markers')
LATENESS = re.compile(r'tick lateness over (\d+) ticks: p50 ([\d.]+) ms, p99 ([\d.]+) ms, max ([\d.]+) ms; (\d+) '
                      r'tick\(s\) more than a tick period')


def launch_file(robots: int, duration: float, subscribers: int) -> str:
    """The launch file of the free-running stack (sim bridge, monitor, gait and feedback per robot)."""
    robot_nodes = ''.join(f'''
  <group>
    <push-ros-namespace namespace="smarticle_{k}"/>
    <node pkg="smarticle_driver" exec="gait" name="gait">
      <param from="{STACK_YAML}"/>
      <param name="use_sim_time" value="true"/>
    </node>
    <node pkg="smarticle_feedback" exec="feedback" name="feedback">
      <param from="{STACK_YAML}"/>
      <param name="use_sim_time" value="true"/>
    </node>
  </group>''' for k in range(robots))
    return f'''<launch>
  <node pkg="smarticle_sim" exec="sim_bridge" name="sim_bridge">
    <param from="{STACK_YAML}"/>
    <param name="mode" value="free"/>
    <param name="real_time_factor" value="1.0"/>
    <param name="robots" value="{robots}"/>
    <param name="duration" value="{duration!r}"/>
    <param name="wait_for_subscribers" value="{subscribers}"/>
  </node>
  <node pkg="smarticle_tracking" exec="glider_monitor" name="glider_monitor">
    <param from="{STACK_YAML}"/>
    <param name="use_sim_time" value="true"/>
    <param name="show_arms" value="false"/>
  </node>{robot_nodes}
</launch>
'''


def main(argv: list[str] | None = None) -> int:
    """Run the free-running stack for the given minutes; print the lateness distribution."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--minutes', type=float, default=10.0, help='wall (= sim) minutes to run')
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--no-recorder', action='store_true', help='without the bag recorder')
    args = parser.parse_args(argv)
    if args.minutes <= 0 or args.robots < 2:
        parser.error('--minutes must be positive and --robots at least 2')
    duration = round(args.minutes * 60.0 / 0.05) * 0.05
    print(f'# real time held: free-running composed stack, {args.robots} robots, feedback, monitor'
          f'{"" if args.no_recorder else ", recorder"}, {duration:g} s at real time; {machine_line()}', flush=True)
    domain = DomainReservation()
    env = isolated_ros_env(domain.domain_id)
    try:
        with tempfile.TemporaryDirectory(prefix='bench_realtime_') as work:
            stack = Path(work) / 'realtime.launch.xml'
            stack.write_text(launch_file(args.robots, duration, 1 + (not args.no_recorder)))
            recorder = None
            if not args.no_recorder:
                recorder = subprocess.Popen([executable('smarticle-bag'), 'record', '--use-sim-time', '-o',
                                             str(Path(work) / 'bag'), *RECORDED], env=env,
                                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            started = time.monotonic()
            host = subprocess.run([executable('smarticle-compose'), str(stack), '--executor', 'events'], env=env,
                                  capture_output=True, text=True, timeout=duration * 3 + 600)
            wall = time.monotonic() - started
            recorded = ''
            if recorder is not None:
                recorder.send_signal(signal.SIGINT)
                recorded = recorder.communicate(timeout=120)[0]
    finally:
        domain.close()
    text = host.stdout + host.stderr
    match = LATENESS.search(text)
    if host.returncode != 0 or match is None:
        print(f'the run failed (exit {host.returncode}): {text[-800:]}')
        return 1
    ticks, p50, p99, worst, behind = (float(g) for g in match.groups())
    print(f'\n{int(ticks)} ticks in {wall:.0f} wall s (load {os.getloadavg()[0]:.2f})\n')
    print('| ticks | lateness p50 (ms) | p99 (ms) | max (ms) | ticks skipped (> one tick period late) |')
    print('| ---: | ---: | ---: | ---: | ---: |')
    print(f'| {int(ticks)} | {p50:.1f} | {p99:.1f} | {worst:.1f} | {int(behind)} |')
    said = [line for line in recorded.splitlines() if 'message' in line and 'rosout' not in line]
    if said:
        print(f'\nrecorder: {said[-1].strip()}')
    held = p99 <= 2.0 and behind == 0
    print(f'\nreal time {"held" if held else "NOT held"} (target: p99 <= 2 ms, no tick skipped)')
    return 0 if held else 1


if __name__ == '__main__':
    raise SystemExit(main())
