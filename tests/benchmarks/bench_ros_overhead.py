"""ROS overhead: the lock-step sim-in-the-loop (sim bridge + gait nodes over DDS) against the batch core.

Runs the same scene three ways in one go and prints a table (CSV and PNG under out/benchmarks/):
  batch-world   Runner with its gait controller (what the batch CLI does), no ROS
  batch-bridge  SimBridgeCore driven in-process exactly like the lock-step ROS path, no ROS
  ros-lockstep  sim_bridge + one gait node per robot, separate processes over DDS, for each publish period
Usage: python tests/benchmarks/bench_ros_overhead.py [--robots 7] [--periods 20] [--quick]
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

from smarticle_common import topics
from smarticle_common.gait import SquareGait
from smarticle_common.launching import ProcessGroup, isolated_ros_env
from smarticle_sim.bridge import BridgeSettings, SimBridgeCore
from smarticle_sim.scenes import build_scene
from smarticle_sim.runner import Runner

START_AT = 0.5


def batch_world(settings: BridgeSettings, seconds: float) -> float:
    """Wall time of a Runner with its gait controller for ``seconds``."""
    r, theta, phi, p0, p1 = settings.pair
    scene = build_scene(settings.scene_kind, settings.sim.robot, settings.gait, settings.robots,
                        seed=settings.seed, r=r, theta=theta, phi=phi, phases=(p0, p1))
    with Runner.with_gaits(settings.sim, scene) as run:
        world = run.physics
        run.gaits.start(START_AT)
        ticks = world.ticks_for(seconds)
        t0 = time.perf_counter()
        run.run(ticks)
        return time.perf_counter() - t0


def batch_bridge(settings: BridgeSettings, seconds: float) -> float:
    """Wall time of SimBridgeCore driven like the lock-step path, commands from in-process gait cores."""
    core = SimBridgeCore(settings)
    gaits = [SquareGait(settings.gait) for _ in range(core.n_robots)]
    for gait in gaits:
        gait.start(START_AT)
    barriers = round(seconds / settings.publish_period)
    t0 = time.perf_counter()
    for _ in range(barriers):
        now = core.time_ns
        for k, gait in enumerate(gaits):
            cmd = gait.command(now * 1e-9)
            core.apply_command(k, list(topics.JOINT_NAMES), list(cmd.targets), [cmd.speed] * 2, now)
        core.advance()
        core.physics.poses()
    wall = time.perf_counter() - t0
    core.close()
    return wall


def ros_lockstep(robots: int, seconds: float, publish_period: float, log_dir: Path) -> float:
    """Wall time of the stepping part of a lock-step run, as reported by the sim bridge's own log."""
    with ProcessGroup(log_dir, isolated_ros_env()) as group:
        for k in range(robots):
            group.start('gait', '--ros-args', '-p', f'robot_id:={k}', '-p', 'lockstep:=true',
                        '-p', f'start_at:={START_AT}')
        bridge = group.start('sim_bridge', '--ros-args', '-p', f'robots:={robots}', '-p', f'duration:={seconds}',
                             '-p', f'publish_period:={publish_period}', '-p', f'start_at:={START_AT}')
        bridge.wait(timeout=1200)
        log = group.output(bridge)
    if bridge.returncode != 0:
        raise RuntimeError(log[-2000:])
    rtf = float(log.rsplit('real-time factor', 1)[1].split()[0])
    return seconds / rtf


def main() -> None:
    """Run the comparison and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--periods', type=float, default=20.0)
    parser.add_argument('--publish-periods', type=float, nargs='+', default=[0.05, 0.1, 1.0 / 60.0])
    parser.add_argument('--quick', action='store_true', help='5 periods, publish period 0.05 s only')
    parser.add_argument('--out', type=Path, default=Path('out/benchmarks'))
    args = parser.parse_args()
    if args.quick:
        args.periods, args.publish_periods = 5.0, [0.05]
    args.out.mkdir(parents=True, exist_ok=True)
    seconds = args.periods * 1.6
    rows = []
    settings = BridgeSettings.defaults(robots=args.robots)
    print(f'{args.robots} robots, dense scene, {args.periods:g} periods = {seconds:.1f} sim s, '
          f'time step {settings.sim.physics.time_step:.5f} s', flush=True)
    wall = batch_world(settings, seconds)
    rows.append(('batch-world', '-', wall))
    print(f'  batch-world  {wall:7.2f} s wall', flush=True)
    for period in args.publish_periods:
        s = BridgeSettings.defaults(robots=args.robots, publish_period=period)
        wall = batch_bridge(s, seconds)
        rows.append(('batch-bridge', period, wall))
        print(f'  batch-bridge publish {period:g} s: {wall:7.2f} s wall', flush=True)
        wall = ros_lockstep(args.robots, seconds, period, args.out / 'ros_overhead_logs')
        rows.append(('ros-lockstep', period, wall))
        print(f'  ros-lockstep publish {period:g} s: {wall:7.2f} s wall', flush=True)
    base = rows[0][2]
    table = [('mode', 'publish period (s)', 'wall (s)', 'x real time', 'cost vs batch-world')]
    for mode, period, wall in rows:
        table.append((mode, str(period), f'{wall:.2f}', f'{seconds / wall:.1f}', f'{wall / base:.2f}'))
    widths = [max(len(r[i]) for r in table) for i in range(len(table[0]))]
    print()
    for row in table:
        print('  '.join(cell.rjust(w) for cell, w in zip(row, widths, strict=True)))
    with open(args.out / 'ros_overhead.csv', 'w', newline='') as handle:
        csv.writer(handle).writerows(table)
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.5))
    ax = fig.add_subplot(1, 1, 1)
    labels = [f'{m}\n{p}' for m, p, _ in rows]
    ax.bar(labels, [seconds / w for _, _, w in rows], color=['gray'] + ['tab:blue', 'tab:orange'] * 10)
    ax.axhline(5.0, color='red', lw=1, ls='--', label='target for lock-step: 5x')
    ax.set_ylabel('x real time')
    ax.set_title(f'{args.robots} robots: batch core vs lock-step sim-in-the-loop', fontsize=9)
    ax.tick_params(axis='x', labelsize=7)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out / 'ros_overhead.png')
    print(f'\nwrote {args.out / "ros_overhead.csv"} and {args.out / "ros_overhead.png"}')


if __name__ == '__main__':
    main()
