"""The lock-step sim-in-the-loop stack against the batch core on the same scene: x real time of each configuration.

Configurations, one run each, interleaved, on the demo's scene (``dense``, 7 robots, seed 1, the shipped
stack.yaml): the sim stack of ``sim_stack.launch.xml`` (sim bridge in lock-step, a gait node per robot, with
feedback a feedback node per robot, the glider monitor)

* composed as ``sim.launch.xml`` runs it (``smarticle-launch ... composed:=true``): every node in one process
  (``smarticle-compose``) but the glider monitor, which runs beside it in its own process, on each executor
  of ``--executors`` (``single``: rclpy's SingleThreadedExecutor; ``events``: rclpy's experimental
  EventsExecutor);
* as separate processes (``smarticle-launch``; the bridge's loop on rclpy's EventsExecutor, the other nodes spun
  by rclpy's SingleThreadedExecutor);

each with feedback on and off, next to the batch core (``Runner`` with the gait cores and, with feedback,
the impact controllers; no ROS) on the same scene and duration. The ROS figure is the sim bridge's own (sim
seconds per wall second from the moment every gait node has answered to the end); the batch figure is sim
seconds per wall second of ``Runner.run``. The machine may be shared: compare the ratios within one run
(the load is printed).

The bridge also reports sim seconds per CPU second of its process (all threads) and the share of its wall
time spent in the physics (steps and FSR); the batch core's CPU figure is its process time.

Usage: ``python tests/benchmarks/bench_lockstep.py [--robots 7] [--periods 5] [--rounds 3]
[--executors single,events] [--no-separate] [--profile]``; ``--profile`` also writes a cProfile of the
composing host with feedback on the last executor, without the monitor (``out/benchmarks/lockstep_composed.pstats``)
and prints its top entries.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers

from smarticle_common.launching import DomainReservation, executable, isolated_ros_env

from tests.benchmarks._common import machine_line, markdown_table, out_path, write_csv

ROOT = Path(__file__).resolve().parents[2]
SIM_FILE = ROOT / 'smarticle_bringup' / 'launch' / 'sim.launch.xml'
STACK_FILE = ROOT / 'smarticle_bringup' / 'launch' / 'sim_stack.launch.xml'
START_AT, PERIOD = 0.5, 1.6
DIGEST = re.compile(r'final poses: sha256 ([0-9a-f]{64})')
RTF = re.compile(r'done at sim time ([\d.]+) s, real-time factor ([\d.]+) \(([\d.]+) per CPU second of this '
                 r'process; physics steps and FSR: (\d+)% of the wall time\)')


class EveryNth:
    """A controller that acts every ``n``-th tick only: the batch core's feedback sampled at the bridge's
    publish period, as the lock-step stack samples it (the peak of the FSR readings since the last sample)."""

    def __init__(self, controller: Any, n: int) -> None:
        self.controller, self.n, self.ticks = controller, n, 0

    def before_tick(self, runner: Any) -> None:
        """Pass the tick on to the controller on every n-th tick, from the first."""
        if self.ticks % self.n == 0:
            self.controller.before_tick(runner)
        self.ticks += 1


def batch_rtf(robots: int, duration: float, feedback: bool, preset: str = 'small') -> tuple[float, float, str]:
    """x real time of the batch core (Runner + gait cores [+ impact controllers, sampling at the bridge's
    publish period]) on the stack's scene with the sim bridge's ``preset`` (a name or a preset file): (per wall
    second, per CPU second, final poses digest)."""
    from smarticle_experiments.p6 import default_feedback_config
    from smarticle_feedback.controller import ImpactController
    from smarticle_sim.bridge import BridgeSettings, poses_digest
    from smarticle_sim.physics import Physics
    from smarticle_sim.runner import FeedbackController, GaitController, Runner

    settings = BridgeSettings.defaults(robots=robots, scene='dense', seed=1, preset=preset)
    scene = settings.scene()
    physics = Physics(settings.sim, scene)
    gaits = GaitController(physics, [r.gait for r in scene.robots])
    runner = Runner(physics, [gaits])
    runner.gaits = gaits
    gaits.start(START_AT)
    if feedback:
        config = default_feedback_config()
        policies = {k: ImpactController(replace(config, period=settings.gait.period, phase=r.gait.phase))
                    for k, r in enumerate(scene.robots) if r.gait is not None}
        for policy in policies.values():
            policy.start(START_AT)
        runner.controllers.insert(0, EveryNth(FeedbackController(gaits, policies), settings.ticks_per_publish))
    ticks = round(duration / settings.sim.physics.control_tick)
    try:
        start, cpu = time.perf_counter(), time.process_time()
        runner.run(ticks)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        digest = poses_digest(physics.poses())
    finally:
        runner.close()
    sim = ticks * settings.sim.physics.control_tick
    return sim / wall, sim / cpu, digest


def ros_rtf(mode: str, executor: str, robots: int, duration: float, feedback: bool, log_dir: Path,
            profile: Path | None = None, params_file: Path | None = None) -> tuple[float, float, float, str, str]:
    """x real time of the sim stack in ``mode`` ('composed' or 'separate'): (per wall second, per CPU second
    of the bridge's process, % of the wall time the bridge spent in the physics, final poses digest, note).
    ``params_file``: the stack's parameter file instead of the shipped config/stack.yaml."""
    words = [f'robots:={robots}', f'duration:={duration!r}', f'feedback:={str(feedback).lower()}']
    if params_file is not None:
        words.append(f'params_file:={params_file}')
    domain = DomainReservation()
    env = isolated_ros_env(domain.domain_id)
    try:
        if profile:   # the host alone (no monitor: it runs in its own process), under the profiler
            command = [sys.executable, '-m', 'cProfile', '-o', str(profile), '-m', 'smarticle_bringup.compose',
                       str(STACK_FILE), *words, 'monitor:=false', 'wait_for_subscribers:=0', '--executor', executor]
        elif mode == 'composed':   # as sim.launch.xml runs it: the host, the monitor in its own process
            command = [executable('smarticle-launch'), str(SIM_FILE), *words, 'composed:=true',
                       f'executor:={executor}', '--log-dir', str(log_dir)]
        else:
            command = [executable('smarticle-launch'), str(STACK_FILE), *words, 'wait_for_subscribers:=1',
                       '--log-dir', str(log_dir)]
        result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=3600)
    finally:
        domain.close()
    text = result.stdout + result.stderr + '\n'.join(p.read_text(errors='replace') for p in log_dir.glob('*.log'))
    match, digest = RTF.search(text), DIGEST.search(text)
    if result.returncode != 0 or match is None or digest is None:
        return (float('nan'), float('nan'), float('nan'), '',
                f'failed (exit {result.returncode}): {text[-300:]!r}')
    return float(match.group(2)), float(match.group(3)), float(match.group(4)), digest.group(1), ''


def print_profile(path: Path, lines: int = 25) -> None:
    """The top of a cProfile by cumulative and by own time."""
    import pstats

    stats = pstats.Stats(str(path))
    for key in ('cumulative', 'tottime'):
        print(f'\n### cProfile of the composed stack with feedback, by {key}\n```')
        stats.sort_stats(key).print_stats(lines)
        print('```')


def configurations(executors: list[str], separate: bool) -> list[tuple[str, str, bool]]:
    """(path, executor, feedback) of every configuration, in the order they run within a round."""
    out = []
    for feedback in (True, False):
        out.append(('batch core (no ROS)', '-', feedback))
        out += [('composed', executor, feedback) for executor in executors]
        if separate:
            out.append(('separate processes', 'events', feedback))
    return out


def main(argv: list[str] | None = None) -> int:
    """Run every configuration ``--rounds`` times, interleaved; print the medians and write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--periods', type=float, default=5.0, help='gait periods after the start (s = 0.5 + 1.6 P)')
    parser.add_argument('--rounds', type=int, default=1, help='runs of each configuration (the median is shown)')
    parser.add_argument('--executors', default='single,events', help='composed executors to compare')
    parser.add_argument('--no-separate', action='store_true', help='skip the separate-process runs')
    parser.add_argument('--profile', action='store_true', help='also profile the composed stack with feedback')
    args = parser.parse_args(argv)
    duration = START_AT + args.periods * PERIOD
    print(f'# lock-step stack, {args.robots} robots (dense, seed 1), {duration:g} sim s, {args.rounds} round(s); '
          f'{machine_line()}', flush=True)
    executors = [e for e in args.executors.split(',') if e]
    configs = configurations(executors, not args.no_separate)
    runs: dict[tuple[str, str, bool], list[tuple[float, float, float]]] = {c: [] for c in configs}
    notes: dict[tuple[str, str, bool], str] = {}
    digests: dict[tuple[str, str, bool], set[str]] = {c: set() for c in configs}
    with tempfile.TemporaryDirectory(prefix='bench_lockstep_') as work:
        for round_ in range(args.rounds):
            for config in configs:
                path, executor, feedback = config
                if path.startswith('batch'):
                    wall, cpu, digest = batch_rtf(args.robots, duration, feedback)
                    figures = (wall, cpu, 100.0)
                else:
                    log_dir = Path(work) / f'{path}-{executor}-{feedback}-{round_}'
                    wall, cpu, physics, digest, note = ros_rtf(path.split()[0], executor, args.robots, duration,
                                                               feedback, log_dir)
                    figures = (wall, cpu, physics)
                    if note:
                        notes[config] = note
                runs[config].append(figures)
                digests[config].add(digest)
                print(f'[round {round_ + 1}] {path}, {executor}, feedback {feedback}: x {figures[0]:.2f} real time, '
                      f'x {figures[1]:.2f} per CPU second, physics {figures[2]:.0f}% of wall', flush=True)
        if args.profile:
            profile = out_path('lockstep_composed.pstats')
            ros_rtf('composed', executors[-1], args.robots, duration, True, Path(work), profile)
    rows: list[dict[str, Any]] = []
    for config in configs:
        path, executor, feedback = config
        wall, cpu, physics = (statistics.median(values) for values in zip(*runs[config], strict=True))
        rows.append({'path': path, 'executor': executor, 'feedback': 'on' if feedback else 'off', 'rtf': wall,
                     'cpu_rtf': cpu, 'physics': physics, 'note': notes.get(config, '')})
    for row, config in zip(rows, configs, strict=True):
        batch_config = next(c for c in configs if c[1] == '-' and c[2] == config[2])
        batch = next(r for r in rows if r['executor'] == '-' and r['feedback'] == row['feedback'])
        row['of_batch'] = row['rtf'] / batch['rtf']
        row['cpu_of_batch'] = row['cpu_rtf'] / batch['cpu_rtf']
        row['poses'] = ('-' if row is batch else
                        'equal' if digests[config] == digests[batch_config] and len(digests[config]) == 1 else
                        'DIFFER')
    print()
    print(markdown_table(rows, [('path', 'path', ''), ('executor', 'executor', ''), ('feedback', 'feedback', ''),
                                ('rtf', 'x real time', '.2f'), ('of_batch', 'of the batch core', '.2f'),
                                ('cpu_rtf', 'x per CPU second', '.2f'),
                                ('cpu_of_batch', 'per CPU, of the batch', '.2f'),
                                ('physics', 'physics % of wall', '.0f'),
                                ('poses', 'final poses vs batch', ''), ('note', 'note', '')]))
    print(f'\nload after the runs: {os.getloadavg()[0]:.2f} (1 min); CSV: {write_csv(out_path("lockstep.csv"), rows)}')
    if args.profile:
        print_profile(out_path('lockstep_composed.pstats'))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
