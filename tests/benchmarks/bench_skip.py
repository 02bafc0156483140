"""What each skip saves: FSR for all robots vs some vs none, recording every tick vs decimated, trouble checks.

One scene (7 robots dense, seed 1, by default) is run many ways in one process, interleaved, best of
``--repeats``; each row gives the wall time and its cost against ``Runner.run`` (no extras) and against a
raw PyBullet loop of the same scene:

* FSR (the sim bridge's per-robot FSR topics): ``Physics.fsr`` for all robots every control tick (60 Hz),
  for one robot (the only one listened to), none; and the robot-robot contact matrix every tick;
* batch recording (``run_trial``): poses every tick, every 3 ticks (20 Hz, the default), every 6,
  every 30; poses + FSR + contacts every tick and at 20 Hz;
* trouble checks: every tick, every 6 ticks (the default), every 60 ticks.

Every run also times its own ``Physics.step`` calls, so each row reports the time spent outside the
physics step on the same trajectory (steady even on a busy machine); the raw loop has no Physics.step.
Rendering does not exist yet, so it is not measured. Writes ``out/benchmarks/sim_skip.csv``.

    .venv/bin/python tests/benchmarks/bench_skip.py --quick
    .venv/bin/python tests/benchmarks/bench_skip.py
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import (PhysicsTimer, Progress, add_clock_argument, clock_of, machine_line, markdown_table, out_path,
                     write_csv)
from smarticle_common.gait import GaitConfig
from smarticle_sim.batch import scene_period
from smarticle_sim.benchmark import bare_loop, batch_loop
from smarticle_sim.scenes import Scene, dense_scene
from smarticle_sim.settings import SimConfig
from smarticle_sim.physics import Physics
from smarticle_sim.runner import Runner

Loop = Callable[[], tuple[int, float]]


def world_with(config: SimConfig, scene: Scene, periods: float,
               per_tick: Callable[[Physics], object] | None = None,
               clock: Callable[[], float] = time.perf_counter) -> tuple[int, float]:
    """Runner.tick loop calling ``per_tick(world)`` after every tick (e.g. an FSR read); timed."""
    with Runner.with_gaits(config, scene) as run:
        world = run.physics
        ticks = world.ticks_for(periods * scene_period(scene))
        run.gaits.start(0.0)
        tick = run.tick
        start = clock()
        if per_tick is None:
            for _ in range(ticks):
                tick()
        else:
            for _ in range(ticks):
                tick()
                per_tick(world)
        return world.step_count, clock() - start


def variants(config: SimConfig, scene: Scene, periods: float,
             clock: Callable[[], float]) -> list[tuple[str, str, Loop]]:
    """(group, name, loop) of every measured variant; the first two are the baselines."""
    one = [0]

    def world(cfg: SimConfig = config, per_tick: Callable[[Physics], object] | None = None) -> Loop:
        return lambda: world_with(cfg, scene, periods, per_tick, clock)

    def batch(every: int | None = None, fsr: bool = False) -> Loop:
        return lambda: batch_loop(config, scene, periods, every, fsr, clock)

    return [
        ('baseline', 'raw PyBullet loop', lambda: bare_loop(config, scene, periods, clock)),
        ('baseline', 'Runner.run: no FSR, no recording', world()),
        ('FSR (bridge, 60 Hz)', 'FSR for all robots every tick', world(per_tick=lambda w: w.fsr())),
        ('FSR (bridge, 60 Hz)', 'FSR for 1 robot every tick', world(per_tick=lambda w: w.fsr(one))),
        ('FSR (bridge, 60 Hz)', 'contact matrix every tick', world(per_tick=lambda w: w.robot_contacts())),
        ('FSR (bridge, 60 Hz)', 'ground-truth state every tick', world(per_tick=lambda w: w.state())),
        ('batch recording', 'poses every tick (60 Hz)', batch(1)),
        ('batch recording', 'poses every 3 ticks (20 Hz, default)', batch()),
        ('batch recording', 'poses every 6 ticks (10 Hz)', batch(6)),
        ('batch recording', 'poses every 30 ticks (2 Hz)', batch(30)),
        ('batch recording', 'poses+FSR+contacts every tick', batch(1, True)),
        ('batch recording', 'poses+FSR+contacts at 20 Hz', batch(None, True)),
        ('trouble checks', 'every tick', world(config.with_physics(trouble_every=1))),
        ('trouble checks', 'every 6 ticks (default)', world()),
        ('trouble checks', 'every 60 ticks', world(config.with_physics(trouble_every=60))),
    ]


def main(argv: list[str] | None = None) -> int:
    """Time every variant, print the table, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--quick', action='store_true', help='10 periods, 2 repeats (~1 min)')
    parser.add_argument('--periods', type=float, default=None, help='gait periods per run (default 40)')
    parser.add_argument('--repeats', type=int, default=None, help='interleaved repeats (default 3)')
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--out-dir', type=Path, default=None)
    parser.add_argument('--no-progress', action='store_true')
    add_clock_argument(parser)
    args = parser.parse_args(argv)
    periods = args.periods or (10.0 if args.quick else 40.0)
    repeats = args.repeats or (2 if args.quick else 3)
    config = SimConfig()
    scene = dense_scene(config.robot, GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed),
                        args.robots, seed=args.seed)
    runs = variants(config, scene, periods, clock_of(args.clock))
    print(f'# skips: {args.robots} robots dense (seed {args.seed}), {periods:g} periods, best of {repeats} '
          f'interleaved, {args.clock} time; {machine_line()}')
    progress = Progress(repeats, 'skip', not args.no_progress)
    clock = clock_of(args.clock)
    best: dict[str, tuple[int, float, float]] = {}
    for rep in range(repeats):
        for _, name, fn in runs:
            with PhysicsTimer(clock) as timer:
                steps, wall = fn()
            if name not in best or wall < best[name][1]:
                best[name] = (steps, wall, timer.inside)
        progress.step(f'repeat {rep + 1} done')
    dt = config.physics.time_step
    raw = best['raw PyBullet loop'][1] / best['raw PyBullet loop'][0]
    world = best['Runner.run: no FSR, no recording'][1] / best['Runner.run: no FSR, no recording'][0]
    rows = []
    for group, name, _ in runs:
        steps, wall, inside = best[name]
        per = wall / steps
        rows.append({'group': group, 'variant': name, 'wall_s': wall, 'physics_s': inside,
                     'real_time_factor': steps * dt / wall,
                     'outside_physics': wall / inside - 1.0 if inside > 0 else float('nan'),
                     'cost_vs_world': per / world - 1.0, 'cost_vs_raw': per / raw - 1.0})
    print(markdown_table(rows, [('group', 'group', ''), ('variant', 'variant', ''), ('wall_s', 'time (s)', '.2f'),
                                ('real_time_factor', 'x real time', '.1f'),
                                ('outside_physics', 'time outside stepSimulation', '+.1%'),
                                ('cost_vs_world', 'vs Runner.run (separate runs)', '+.1%'),
                                ('cost_vs_raw', 'vs raw (separate runs)', '+.1%')]))
    print('\n"time outside stepSimulation" = total / time inside Physics.step - 1, measured within each run '
          '(the same trajectory): the steady measure of what the extras cost. The separate-run ratios '
          'include run-to-run noise of the shared machine (+-10 % or more).')
    path = write_csv(out_path('sim_skip.csv', args.out_dir), rows)
    print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
