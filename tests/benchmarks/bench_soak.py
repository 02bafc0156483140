"""A soak run of the composed lock-step stack: memory over time, nothing lost, an intact bag, the batch core's poses.

``sim.launch.xml`` with 7 robots (dense, seed 1, the shipped stack.yaml with the sim bridge's ``preset`` a preset
file of the small robot on a ``--plate-size`` plate: over an hour gliders travel metres and would leave the
shipped 0.6 m plate, a physical end of the run), feedback, the glider monitor and the
recorder (``record:=true``: /smarticles/poses, /clock, /smarticles/start, /smarticles/gliders,
/smarticles/markers, in sim time), composed (``smarticle-compose`` on the EventsExecutor, the recorder as its
own process), for ``--duration`` sim seconds (default one hour). Meanwhile the resident memory (RSS) of every
process of the launch is sampled every ``--sample`` wall seconds. At the end it prints:

* each process's RSS over time and its growth per simulated hour (a straight line fitted to the second half
  of the samples, so start-up and warm-up do not count);
* messages published against recorded, for /clock and /smarticles/poses (the sim bridge's counts, its last
  log line, against the bag's): 0 lost is the target;
* the bag's integrity check (``smarticle-bag check``: every chunk CRC and record);
* the final poses against the batch core's for the same seed and duration (``bench_lockstep.batch_rtf``, the
  feedback sampled at the publish period as the stack samples it): equal bit for bit (SHA-256 of the poses).

Exit code 0 when every check holds, 1 otherwise. ``tests/smarticle_bringup/test_soak.py`` runs a two-minute
version. Usage: ``python tests/benchmarks/bench_soak.py [--duration 3600] [--robots 7] [--sample 5]
[--plate-size 12] [--out DIR]`` (the bag and logs go to DIR, default a temporary folder).
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers

from smarticle_common.launching import DomainReservation, executable, isolated_ros_env

from tests.benchmarks._common import machine_line, markdown_table, out_path, stack_params, write_csv

PUBLISHED = re.compile(r'final poses: sha256 ([0-9a-f]{64}); published: /clock (\d+), /smarticles/poses (\d+)')
RTF = re.compile(r'done at sim time ([\d.]+) s, real-time factor ([\d.]+)')


@dataclass
class SoakResult:
    """What a soak run measured, and whether each check held."""

    duration: float
    wall: float = 0.0
    rtf: float = float('nan')
    exit_code: int = 0
    rss: dict[str, list[tuple[float, float]]] = field(default_factory=dict)   # process -> (wall s, MB)
    published: dict[str, int] = field(default_factory=dict)
    recorded: dict[str, int] = field(default_factory=dict)
    bag_check: str = ''
    bag_ok: bool = False
    digest: str = ''
    batch_digest: str = ''
    problems: list[str] = field(default_factory=list)

    @property
    def lost(self) -> dict[str, int]:
        """Messages published but not in the bag, by topic."""
        return {t: n - self.recorded.get(t, 0) for t, n in self.published.items()}

    def growth_per_sim_hour(self, name: str) -> float:
        """MB per simulated hour of process ``name``: a least-squares line over the second half of its samples."""
        samples = self.rss.get(name, [])
        tail = samples[len(samples) // 2:]
        if len(tail) < 2 or not self.rtf or self.rtf != self.rtf:
            return float('nan')
        n = len(tail)
        mean_t = sum(t for t, _ in tail) / n
        mean_m = sum(m for _, m in tail) / n
        var = sum((t - mean_t) ** 2 for t, _ in tail)
        if var == 0.0:
            return float('nan')
        slope = sum((t - mean_t) * (m - mean_m) for t, m in tail) / var   # MB per wall second
        return slope / self.rtf * 3600.0

    @property
    def ok(self) -> bool:
        """Every check held: the run ended well, nothing lost, the bag is intact, the poses are the batch core's."""
        return (not self.problems and self.exit_code == 0 and bool(self.published)
                and all(v == 0 for v in self.lost.values()) and self.bag_ok
                and bool(self.digest) and self.digest == self.batch_digest)


def process_name(proc: Any) -> str:
    """A short name of a launched process: its console script or node executable."""
    import psutil

    try:
        words = proc.cmdline()
    except psutil.Error:   # the process ended between the listing and the look
        return f'pid {proc.pid}'
    for word in words:
        base = os.path.basename(word)
        if base.startswith(('smarticle-', 'recorder', 'sim_bridge', 'gait', 'feedback', 'glider_monitor')):
            return base
    return os.path.basename(words[0]) if words else f'pid {proc.pid}'


def sample_rss(root: Any, started: float, rss: dict[str, list[tuple[float, float]]],
               names: dict[int, str]) -> None:
    """Add one RSS sample (MB) of ``root`` and every descendant to ``rss``, by name (``names``: pid -> name)."""
    import psutil

    try:
        procs = [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return
    now = time.monotonic() - started
    for proc in procs:
        try:
            mb = proc.memory_info().rss / 2**20
        except psutil.Error:
            continue
        if proc.pid not in names:
            name = process_name(proc)
            names[proc.pid] = name if name not in names.values() else f'{name} (pid {proc.pid})'
        rss.setdefault(names[proc.pid], []).append((now, mb))


def bag_counts(bag: Path) -> dict[str, int]:
    """Messages per topic in the bag (its metadata)."""
    from smarticle_bags.reader import BagReader

    return {name: info.message_count for name, info in BagReader(bag).topics.items()}


def soak(duration: float, robots: int, sample: float, out: Path, plate_size: float = 0.6) -> SoakResult:
    """Run the soak in ``out`` (bag, logs) on a ``plate_size`` m plate; return what it measured."""
    import psutil

    from tests.benchmarks.bench_lockstep import batch_rtf

    result = SoakResult(duration)
    bag, logs = out / 'bag', out / 'logs'
    command = [executable('smarticle-launch'), 'smarticle_bringup', 'sim.launch.xml', f'robots:={robots}',
               f'duration:={duration!r}', 'feedback:=true', 'record:=true', f'bag:={bag}',
               f'params_file:={stack_params(out, plate_size)}', '--log-dir', str(logs)]
    domain = DomainReservation()
    try:
        started = time.monotonic()
        with subprocess.Popen(command, env=isolated_ros_env(domain.domain_id), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True) as proc:
            root = psutil.Process(proc.pid)
            lines: list[str] = []
            reader = threading.Thread(target=lambda: lines.extend(proc.stdout or []), daemon=True)
            reader.start()
            names: dict[int, str] = {}
            while proc.poll() is None:
                sample_rss(root, started, result.rss, names)
                time.sleep(sample)
            reader.join(timeout=10.0)
            result.exit_code = proc.returncode
        result.wall = time.monotonic() - started
    finally:
        domain.close()
    text = ''.join(lines) + '\n'.join(p.read_text(errors='replace') for p in sorted(logs.glob('*.log')))
    rtf, counts = RTF.search(text), PUBLISHED.search(text)
    if rtf is None or counts is None:
        result.problems.append(f'the sim bridge did not report its end (exit {result.exit_code}): {text[-400:]!r}')
        return result
    result.rtf = float(rtf.group(2))
    result.digest = counts.group(1)
    result.published = {'/clock': int(counts.group(2)), '/smarticles/poses': int(counts.group(3))}
    recorded = bag_counts(bag)
    result.recorded = {t: recorded.get(t, 0) for t in result.published}
    check = subprocess.run([executable('smarticle-bag'), 'check', str(bag)], capture_output=True, text=True,
                           timeout=600)
    result.bag_ok = check.returncode == 0
    said = (check.stdout + check.stderr).strip().splitlines()
    result.bag_check = said[-1] if said else f'exit {check.returncode}'
    result.batch_digest = batch_rtf(robots, duration, True, str(out / 'plate_preset.yaml'))[2]
    return result


def report(result: SoakResult) -> list[dict[str, Any]]:
    """Print the soak's tables and checks; return the RSS rows (for the CSV)."""
    print(f'\nsim {result.duration:g} s in {result.wall:.0f} wall s (the bridge: x {result.rtf:.2f} real time), '
          f'exit code {result.exit_code}')
    rows = []
    for name, samples in sorted(result.rss.items()):
        if not samples:
            continue
        rows.append({'process': name, 'first': samples[0][1], 'peak': max(m for _, m in samples),
                     'last': samples[-1][1], 'growth': result.growth_per_sim_hour(name), 'samples': len(samples)})
    print('\n### Resident memory (MB)\n')
    print(markdown_table(rows, [('process', 'process', ''), ('first', 'first', '.1f'), ('peak', 'peak', '.1f'),
                                ('last', 'last', '.1f'), ('growth', 'growth per sim hour', '+.1f'),
                                ('samples', 'samples', 'd')]))
    print('\n### Messages\n')
    print(markdown_table([{'topic': t, 'published': n, 'recorded': result.recorded.get(t, 0),
                           'lost': result.lost[t]} for t, n in result.published.items()],
                         [('topic', 'topic', ''), ('published', 'published', 'd'), ('recorded', 'recorded', 'd'),
                          ('lost', 'lost', 'd')]))
    print(f'\nbag check: {"intact" if result.bag_ok else "DAMAGED"} ({result.bag_check})')
    print(f'final poses: {"equal to" if result.digest == result.batch_digest else "DIFFER from"} the batch '
          f"core's (sha256 {result.digest[:16]} / {result.batch_digest[:16]})")
    for problem in result.problems:
        print(f'problem: {problem}')
    print(f'\nsoak: {"PASS" if result.ok else "FAIL"}')
    return rows


def main(argv: list[str] | None = None) -> int:
    """Run the soak, print the tables; exit code 0 when every check holds."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0] if __doc__ else None)
    parser.add_argument('--duration', type=float, default=3600.0, help='sim seconds (default one hour)')
    parser.add_argument('--robots', type=int, default=7)
    parser.add_argument('--sample', type=float, default=5.0, help='wall seconds between RSS samples')
    parser.add_argument('--plate-size', type=float, default=12.0,
                        help='side of the square plate (m; default 12: an hour of gliding stays on it)')
    parser.add_argument('--out', type=Path, default=None, help='folder for the bag and the logs (kept)')
    args = parser.parse_args(argv)
    if args.duration <= 0 or args.robots < 2 or args.sample <= 0 or args.plate_size <= 0:
        parser.error('--duration, --sample and --plate-size must be positive, --robots at least 2')
    print(f'# soak: composed lock-step stack, {args.robots} robots, feedback, monitor, recorder, {args.duration:g} '
          f'sim s, {args.plate_size:g} m plate; {machine_line()}', flush=True)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        result = soak(args.duration, args.robots, args.sample, args.out, args.plate_size)
        rows = report(result)
    else:
        with tempfile.TemporaryDirectory(prefix='bench_soak_') as work:
            result = soak(args.duration, args.robots, args.sample, Path(work), args.plate_size)
            rows = report(result)
    print(f'CSV: {write_csv(out_path("soak_rss.csv"), rows)}')
    return 0 if result.ok else 1


if __name__ == '__main__':
    raise SystemExit(main())
