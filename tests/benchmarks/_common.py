"""Shared helpers of the simulation benchmark scripts: output folder, tables, CSV, progress lines, timing.

The scripts in this folder are not tests (pytest collects ``test_*.py`` only): they time things, print
Markdown tables and write CSV and PNG files under ``out/benchmarks/``. Run them one at a time.
"""

from __future__ import annotations

import csv
import platform
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

#: Repository root (tests/benchmarks/ is two levels below it).
ROOT = Path(__file__).resolve().parents[2]
#: Where every benchmark writes its CSV and PNG files.
OUT_DIR = ROOT / 'out' / 'benchmarks'


def out_path(name: str, out_dir: Path | None = None) -> Path:
    """Path of output file ``name`` in the benchmark folder (created)."""
    folder = out_dir or OUT_DIR
    folder.mkdir(parents=True, exist_ok=True)
    return folder / name


def figure(width: float = 7.0, height: float = 5.0) -> Any:
    """A matplotlib Figure on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=110)


def write_csv(path: Path, rows: Sequence[dict[str, Any]]) -> Path:
    """Write ``rows`` (dicts with the same keys) to ``path`` as CSV; return the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open('w', newline='') as handle:
        if not rows:
            return path
        names = list(dict.fromkeys(k for row in rows for k in row))
        writer = csv.DictWriter(handle, fieldnames=names, restval='')
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _csv_value(v) for k, v in row.items()})
    return path


def _csv_value(value: Any) -> Any:
    """Floats with 6 significant digits, everything else as is."""
    return f'{value:.6g}' if isinstance(value, float) else value


def markdown_table(rows: Sequence[dict[str, Any]], columns: Sequence[tuple[str, str, str]]) -> str:
    """A Markdown table: ``columns`` = (key, header, format spec); numbers are right-aligned."""
    head = '| ' + ' | '.join(h for _, h, _ in columns) + ' |'
    align = '| ' + ' | '.join('---:' if fmt else '---' for _, _, fmt in columns) + ' |'
    lines = [head, align]
    for row in rows:
        cells = []
        for key, _, fmt in columns:
            value = row.get(key, '')
            if fmt and isinstance(value, (int, float)) and value == value:
                cells.append(format(value, fmt))
            elif isinstance(value, float) and value != value:
                cells.append('-')
            else:
                cells.append(str(value))
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def machine_line() -> str:
    """One line describing the interpreter and machine, for the printed header."""
    import os

    import pybullet  # noqa: F401  (version banner printed once by the import)

    return (f'python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cpu(s), '
            f'load {os.getloadavg()[0]:.2f}')


class Progress:
    """Periodic progress lines on stderr: ``[i/n] label  elapsed``."""

    def __init__(self, total: int, name: str, enabled: bool = True) -> None:
        self.total, self.name, self.enabled = total, name, enabled
        self.done = 0
        self.start = time.perf_counter()

    def step(self, label: str) -> None:
        """Report that one more item (``label``) is done."""
        self.done += 1
        if self.enabled:
            elapsed = time.perf_counter() - self.start
            print(f'[{self.name} {self.done}/{self.total}] {label}  ({elapsed:.0f} s)', file=sys.stderr,
                  flush=True)


def timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    """Run ``fn`` and return (its result, wall seconds)."""
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


def add_clock_argument(parser: Any) -> None:
    """``--clock cpu|wall``: what the timings measure (default cpu)."""
    parser.add_argument('--clock', choices=('cpu', 'wall'), default='cpu',
                        help='time with this process\'s CPU time (default: steadier on a shared machine; '
                             'PyBullet DIRECT steps in-process on one thread) or with wall time')


def clock_of(name: str) -> Callable[[], float]:
    """The clock function named by ``--clock``."""
    return time.process_time if name == 'cpu' else time.perf_counter


class PhysicsTimer:
    """While active, time every ``Physics.step`` call (the stepSimulation loop) of every Physics.

    ``inside`` accumulates clock seconds spent stepping the physics; total - inside is what the
    Physics, the gait cores, the trouble checks and any recording cost on top of the very same
    trajectory, which is far steadier on a shared machine than comparing two separate runs.
    """

    def __init__(self, clock: Callable[[], float]) -> None:
        self.clock = clock
        self.inside = 0.0
        self._saved: Any = None

    def __enter__(self) -> PhysicsTimer:
        from smarticle_sim.physics import Physics

        self._saved = Physics.step
        original, clock = Physics.step, self.clock

        def step(world: Any, n: int = 1) -> None:
            t0 = clock()
            original(world, n)
            self.inside += clock() - t0

        Physics.step = step  # type: ignore[method-assign]
        return self

    def __exit__(self, *exc: object) -> None:
        from smarticle_sim.physics import Physics

        Physics.step = self._saved  # type: ignore[method-assign]


def stack_params(out: Path, plate_size: float) -> Path:
    """The shipped config/stack.yaml with the sim bridge's ``preset`` a preset file of the small robot on a
    ``plate_size`` m plate (both written to ``out``); the path of the params file (``params_file:=``). The
    preset file is ``out/plate_preset.yaml``, which the batch core takes as its ``preset``."""
    import yaml

    from smarticle_bringup.launch_files import package_share

    out.mkdir(parents=True, exist_ok=True)
    preset = out / 'plate_preset.yaml'
    preset.write_text(yaml.safe_dump({'preset': 'small', 'physics': {'plate_size': plate_size}, 'robot': {}}))
    params = yaml.safe_load((package_share('smarticle_bringup') / 'config' / 'stack.yaml').read_text())
    params['/sim_bridge'] = {'ros__parameters': {'preset': str(preset)}}
    path = out / 'plate_stack.yaml'
    path.write_text(yaml.safe_dump(params))
    return path
