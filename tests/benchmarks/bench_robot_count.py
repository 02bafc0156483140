"""Cost against robot count: the composed lock-step stack and the batch core side by side, and where the time goes.

For each robot count (dense scene, seed 1, the shipped stack.yaml, on the shipped 0.6 m plate up to 20 robots
and a 2 m plate beyond; feedback on unless ``--no-feedback``) one
run of the batch core (``Runner`` with the gait cores and the impact controllers, no ROS) and one of the
composed lock-step stack (``smarticle-compose sim_stack.launch.xml``, EventsExecutor), interleaved, the same sim
duration: x real time of each, the stack's share of the batch core (per wall and per CPU second), the share of
the bridge's wall time in the physics, and whether the final poses are equal bit for bit. With ``--profile`` the
largest count is run once more under cProfile and the top of its profile printed (where the time goes there).

Usage: ``python tests/benchmarks/bench_robot_count.py [--robots 1,2,7,20,50] [--periods 3] [--no-feedback]
[--profile]``. The machine may be shared: read the ratios (the same run), the load is printed.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers

from tests.benchmarks._common import machine_line, markdown_table, out_path, stack_params, write_csv
from tests.benchmarks.bench_lockstep import PERIOD, START_AT, batch_rtf, print_profile, ros_rtf

#: The plate (m) of each run: the shipped 0.6 m up to ``SHIPPED_PLATE_ROBOTS`` robots, beyond it the 2 m plate of
#: the dense50 spec (a dense scene of 50 robots reaches off the shipped plate); the stack and the batch core take
#: the same plate (a preset file given to the sim bridge through the stack's params file).
SHIPPED_PLATE_ROBOTS = 20
LARGE_PLATE = 2.0


def plate_for(robots: int) -> float:
    """The plate side (m) for a run of ``robots`` robots."""
    return 0.6 if robots <= SHIPPED_PLATE_ROBOTS else LARGE_PLATE


def main(argv: list[str] | None = None) -> int:
    """Run the batch core and the composed stack at every robot count; print the table, write the CSV."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--robots', default='1,2,7,20,50', help='robot counts, comma-separated')
    parser.add_argument('--periods', type=float, default=3.0, help='gait periods after the start (s = 0.5 + 1.6 P)')
    parser.add_argument('--no-feedback', action='store_true', help='gait only (no feedback nodes)')
    parser.add_argument('--profile', action='store_true', help='profile the stack at the largest count')
    args = parser.parse_args(argv)
    try:
        counts = [int(n) for n in args.robots.split(',') if n]
    except ValueError:
        parser.error(f'--robots takes whole numbers separated by commas, got {args.robots!r}')
    if not counts or min(counts) < 1:
        parser.error('--robots needs robot counts of at least 1')
    feedback = not args.no_feedback
    duration = START_AT + args.periods * PERIOD
    print(f'# cost against robot count, feedback {"on" if feedback else "off"}, {duration:g} sim s per run; '
          f'{machine_line()}', flush=True)
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix='bench_robot_count_') as work:
        for n in counts:
            plate = plate_for(n)
            params = stack_params(Path(work) / f'plate_{n}', plate)
            wall_b, cpu_b, digest_b = batch_rtf(n, duration, feedback, str(params.parent / 'plate_preset.yaml'))
            wall_s, cpu_s, physics, digest_s, note = ros_rtf('composed', 'events', n, duration, feedback,
                                                             Path(work) / f'{n}', params_file=params)
            rows.append({'robots': n, 'plate': plate, 'batch': wall_b, 'stack': wall_s, 'of_batch': wall_s / wall_b,
                         'cpu_of_batch': cpu_s / cpu_b, 'physics': physics,
                         'poses': 'equal' if digest_s == digest_b else 'DIFFER', 'note': note})
            print(f'{n} robots: batch x {wall_b:.2f}, stack x {wall_s:.2f} real time ({wall_s / wall_b:.2f} of the '
                  f'batch core), physics {physics:.0f}% of the bridge\'s wall', flush=True)
        if args.profile:
            profile = out_path('robot_count_composed.pstats')
            ros_rtf('composed', 'events', max(counts), duration, feedback, Path(work) / 'profile', profile,
                    params_file=stack_params(Path(work) / 'plate_profile', plate_for(max(counts))))
    print()
    print(markdown_table(rows, [('robots', 'robots', 'd'), ('plate', 'plate (m)', '.1f'),
                                ('batch', 'batch core x real time', '.2f'),
                                ('stack', 'composed stack x real time', '.2f'),
                                ('of_batch', 'stack of the batch core', '.2f'),
                                ('cpu_of_batch', 'per CPU second, of the batch', '.2f'),
                                ('physics', "physics % of the bridge's wall", '.0f'),
                                ('poses', 'final poses vs batch', ''), ('note', 'note', '')]))
    print(f'\nload after the runs: {os.getloadavg()[0]:.2f} (1 min); CSV: '
          f'{write_csv(out_path("robot_count.csv"), rows)}')
    if args.profile:
        print_profile(out_path('robot_count_composed.pstats'))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
