"""Calibrate the impact window from a recorded run: per-face force distribution during collisions.

Input: an npz of ``smarticle-sim run ... --fsr`` (``fsr`` (S, N, 4) newtons, ``contacts`` (S, N, N)),
typically pairs in the C2 conformation (docs/feedback.md). A sample of robot k counts as "during a
collision" when k touches another robot at that sample; of those, the forces above ``floor`` newtons on
each face form that face's distribution. With ``c2_only`` (pair runs) only samples whose relative
heading phi lies within ``c2_tolerance`` of 0 count. The suggested window is
``[percentile(low), percentile(high)]`` of the pooled forces of all faces (the FSRs are the same part),
by default P80 to the largest: the compression collision is the hard end of the distribution, the many
light resting touches stay below f_min. The table shows each face too.
Command line: ``smarticle-feedback-calibrate run.npz``.

From the compression signature (the paper's way: the window of the compression collision): given a
per-step collision record of ``smarticle-experiments c2-collisions`` (``c2_steps.npz``), the tool cuts it into
contact events (``collisions.find_events``), and for each face proposes the window that best separates
the peaks of the compression events (dr > 0) from those of the bracing ones (dr < 0): ``f_min`` the
compression peak that maximises (compression caught / compression) - (bracing caught / bracing) on that
face, ``f_max`` the largest compression peak times ``HEADROOM``; a face is enabled when its window
catches a fraction of the compression peaks at least ``SEPARATION`` above that of the bracing peaks
(several records are pooled). A window set that catches no compression event, or that
catches most bracing events, is reported with the counts and refused (exit code 3).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from smarticle_common.topics import FSR_FACES

from .collisions import CollisionEvent, find_events, load_record
from .errors import CalibrationInputError
from smarticle_common.cli import add_version, closed_pipe_safe

#: Forces below this (N) are contact noise, not impacts (the sim reports tiny resting forces).
DEFAULT_FLOOR = 0.05


@dataclass(frozen=True)
class FaceStats:
    """Distribution of one face's collision forces (N)."""

    face: str
    count: int
    p05: float
    p25: float
    median: float
    p75: float
    p95: float
    max: float


@dataclass(frozen=True)
class WindowSuggestion:
    """Per-face statistics and the suggested impact window [f_min, f_max] (N)."""

    faces: tuple[FaceStats, ...]
    pooled: FaceStats
    f_min: float
    f_max: float
    samples: int              # robot samples during collisions
    forces: dict[str, np.ndarray]


def collision_forces(fsr: np.ndarray, contacts: np.ndarray, floor: float = DEFAULT_FLOOR,
                     keep: np.ndarray | None = None) -> tuple[dict[str, np.ndarray], int]:
    """Per-face forces above ``floor`` at samples where the robot touches another one; and the sample count."""
    fsr = np.asarray(fsr, dtype=float)
    contacts = np.asarray(contacts, dtype=bool)
    if fsr.ndim != 3 or fsr.shape[2] != len(FSR_FACES):
        raise CalibrationInputError(f'fsr must have shape (samples, robots, {len(FSR_FACES)}), got {fsr.shape}')
    if contacts.shape != fsr.shape[:2] + (fsr.shape[1],):
        raise CalibrationInputError(f'contacts must have shape {fsr.shape[:2] + (fsr.shape[1],)}, '
                                    f'got {contacts.shape}')
    touching = contacts.any(axis=2)                         # (S, N)
    if keep is not None:
        touching &= np.asarray(keep, dtype=bool)[:, None]
    picked = fsr[touching]                                  # (M, 4)
    picked = picked[np.isfinite(picked).all(axis=1)]
    out = {face: picked[:, i][picked[:, i] > floor] for i, face in enumerate(FSR_FACES)}
    return out, int(touching.sum())


def face_stats(face: str, values: np.ndarray) -> FaceStats:
    """Percentiles of one set of forces (NaN when empty)."""
    if values.size == 0:
        return FaceStats(face, 0, *([math.nan] * 6))
    p05, p25, median, p75, p95 = (float(v) for v in np.percentile(values, [5, 25, 50, 75, 95]))
    return FaceStats(face, int(values.size), p05, p25, median, p75, p95, float(values.max()))


def suggest_window(forces: dict[str, np.ndarray], samples: int, low: float = 80.0,
                   high: float = 100.0) -> WindowSuggestion:
    """Statistics per face and pooled, and the window [P_low, P_high] of the pooled forces."""
    if not (0.0 <= low < high <= 100.0):
        raise CalibrationInputError(f'percentiles must satisfy 0 <= low < high <= 100, got {low}, {high}')
    pooled = np.concatenate([forces[f] for f in FSR_FACES])
    if pooled.size == 0:
        raise CalibrationInputError('no collision forces in the recording: record with --fsr a run in '
                                    'which the robots touch')
    f_min, f_max = (float(v) for v in np.percentile(pooled, [low, high]))
    return WindowSuggestion(tuple(face_stats(f, forces[f]) for f in FSR_FACES), face_stats('all', pooled),
                            f_min, f_max, samples, forces)


def c2_mask(poses: np.ndarray, tolerance: float) -> np.ndarray:
    """Samples of a two-robot run whose relative heading phi lies within ``tolerance`` rad of 0."""
    if poses.shape[1] != 2:
        raise CalibrationInputError(f'--c2-only needs a two-robot (pair) run, got {poses.shape[1]} robots')
    phi = poses[:, 1, 2] - poses[:, 0, 2]
    return np.abs(np.angle(np.exp(1j * phi))) <= tolerance


def calibrate_recording(path: str | Path, floor: float = DEFAULT_FLOOR, low: float = 80.0, high: float = 100.0,
                        c2_only: bool = False, c2_tolerance: float = math.radians(45.0)) -> WindowSuggestion:
    """Load an npz of ``smarticle-sim run --fsr`` and suggest an impact window."""
    from smarticle_common.runs import load_npz

    rec = load_npz(path)
    if not rec.meta.get('fsr_recorded') or not rec.meta.get('contacts_recorded'):
        raise CalibrationInputError(f'{path}: FSR forces and contacts were not recorded; rerun '
                                    '`smarticle-sim run ... --fsr`')
    keep = c2_mask(rec.poses, c2_tolerance) if c2_only else None
    forces, samples = collision_forces(rec.fsr, rec.contacts, floor, keep)
    return suggest_window(forces, samples, low, high)


def format_table(s: WindowSuggestion) -> str:
    """Markdown table of the per-face distributions and the suggested window."""
    rows = ['| face | n | p5 | p25 | median | p75 | p95 | max (N) |',
            '| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    for st in (*s.faces, s.pooled):
        rows.append(f'| {st.face} | {st.count} | {st.p05:.3f} | {st.p25:.3f} | {st.median:.3f} | {st.p75:.3f} | '
                    f'{st.p95:.3f} | {st.max:.3f} |')
    rows.append('')
    rows.append(f'suggested impact window: f_min = {s.f_min:.3f} N, f_max = {s.f_max:.3f} N '
                f'({s.samples} robot samples in contact)')
    return '\n'.join(rows)


def yaml_snippet(s: WindowSuggestion) -> str:
    """The window as feedback node parameters (paste into config/feedback.yaml or pass with -p)."""
    return ''.join(f'    {face}_min: {s.f_min:.3f}\n    {face}_max: {s.f_max:.3f}\n' for face in FSR_FACES)


def plot_window(s: WindowSuggestion, path: str | Path, title: str = '') -> Path:
    """Histograms of the per-face collision forces with the suggested window shaded (PNG, Agg)."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    path = Path(path)
    fig = Figure(figsize=(9, 6), dpi=100)
    top = max((float(v.max()) for v in s.forces.values() if v.size), default=1.0)
    bins = np.linspace(0.0, top * 1.02, 40)
    for i, face in enumerate(FSR_FACES):
        ax = fig.add_subplot(2, 2, i + 1)
        values = s.forces[face]
        ax.hist(values, bins=bins.tolist(), color='tab:blue', alpha=0.8)
        ax.axvspan(s.f_min, s.f_max, color='tab:orange', alpha=0.2, label='impact window')
        ax.set_title(f'{face} (n = {values.size})', fontsize=9)
        ax.set_xlabel('force (N)')
        ax.set_ylabel('samples')
        if i == 0:
            ax.legend(fontsize=8)
    fig.suptitle(title or f'collision forces; window [{s.f_min:.2f}, {s.f_max:.2f}] N', fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


#: f_max of a face = its largest compression peak times this (room for a harder hit than recorded).
HEADROOM = 1.25
#: A face is enabled when its window catches this much larger a fraction of the compression peaks than of
#: the bracing peaks (a face whose kicks are as hard either way cannot tell them apart).
SEPARATION = 0.3


@dataclass(frozen=True)
class FaceWindow:
    """Proposed window of one face and what it catches among the recorded events."""

    face: str
    f_min: float
    f_max: float
    enabled: bool
    compression: int           # compression peaks of this face (both robots)
    compression_caught: int
    bracing: int
    bracing_caught: int


@dataclass(frozen=True)
class SignatureWindows:
    """Per-face windows from the compression signature, and the events caught by the enabled faces."""

    faces: tuple[FaceWindow, ...]
    compression_events: int
    compression_caught: int
    bracing_events: int
    bracing_caught: int

    @property
    def problems(self) -> list[str]:
        """Why this window set must not be shipped (empty if it may)."""
        out = []
        if self.compression_caught == 0:
            out.append(f'no recorded compression event falls into the window (0 of {self.compression_events})')
        if self.bracing_events and self.bracing_caught > self.bracing_events / 2:
            out.append(f'the window also catches most bracing events ({self.bracing_caught} of '
                       f'{self.bracing_events})')
        return out


def _caught(events: Sequence[CollisionEvent], windows: Sequence[FaceWindow]) -> int:
    """Events in which some robot's enabled face peaks inside its window."""
    n = 0
    for ev in events:
        if any(w.enabled and w.f_min <= ev.peaks[k, i] <= w.f_max for k in range(2) for i, w in enumerate(windows)):
            n += 1
    return n


def face_window(face: str, comp: np.ndarray, brace: np.ndarray) -> FaceWindow:
    """The window [f_min, HEADROOM x max] of one face that best separates compression from bracing peaks."""
    if comp.size == 0:
        return FaceWindow(face, 0.0, 0.0, False, 0, 0, int(brace.size), 0)
    f_max = float(comp.max()) * HEADROOM
    best, f_min = -math.inf, float(comp.min())
    for lo in np.unique(comp):
        score = float((comp >= lo).mean()) - (float(((brace >= lo) & (brace <= f_max)).mean()) if brace.size else 0.0)
        if score > best:
            best, f_min = score, float(lo)
    c = int(((comp >= f_min) & (comp <= f_max)).sum())
    b = int(((brace >= f_min) & (brace <= f_max)).sum())
    separation = c / comp.size - (b / brace.size if brace.size else 0.0)
    return FaceWindow(face, f_min, f_max, c > 0 and separation >= SEPARATION, int(comp.size), c, int(brace.size), b)


def windows_from_events(events: Sequence[CollisionEvent], floor: float = DEFAULT_FLOOR) -> SignatureWindows:
    """Per-face windows from the compression and bracing events' FSR peaks (both robots)."""
    faces = []
    for i, face in enumerate(FSR_FACES):
        comp = np.array([ev.peaks[k, i] for ev in events if ev.kind == 'compression' for k in range(2)])
        brace = np.array([ev.peaks[k, i] for ev in events if ev.kind == 'bracing' for k in range(2)])
        faces.append(face_window(face, comp[comp > floor], brace[brace > floor]))
    comp_ev = [ev for ev in events if ev.kind == 'compression']
    brace_ev = [ev for ev in events if ev.kind == 'bracing']
    return SignatureWindows(tuple(faces), len(comp_ev), _caught(comp_ev, faces), len(brace_ev),
                            _caught(brace_ev, faces))


def format_windows(w: SignatureWindows) -> str:
    """Markdown table of the proposed per-face windows with the events each catches."""
    rows = ['| face | enabled | f_min (N) | f_max (N) | compression caught | bracing caught |',
            '| --- | --- | ---: | ---: | ---: | ---: |']
    for f in w.faces:
        rows.append(f'| {f.face} | {"yes" if f.enabled else "no"} | {f.f_min:.2f} | {f.f_max:.2f} | '
                    f'{f.compression_caught} / {f.compression} | {f.bracing_caught} / {f.bracing} |')
    rows.append('')
    rows.append(f'events caught by the enabled faces: compression {w.compression_caught} of {w.compression_events}, '
                f'bracing {w.bracing_caught} of {w.bracing_events}')
    return '\n'.join(rows)


def windows_yaml(w: SignatureWindows) -> str:
    """The windows as feedback node parameters."""
    return ''.join(f'    {f.face}_min: {f.f_min:.2f}\n    {f.face}_max: {f.f_max:.2f}\n'
                   f'    {f.face}_enabled: {"true" if f.enabled else "false"}\n' for f in w.faces)


def check_windows(events: Sequence[CollisionEvent], windows: Sequence[tuple[str, float, float, bool]],
                  floor: float = DEFAULT_FLOOR) -> SignatureWindows:
    """What given windows (face, f_min, f_max, enabled) catch among recorded events (e.g. the shipped ones)."""
    faces = []
    for i, (face, f_min, f_max, enabled) in enumerate(windows):
        comp = np.array([ev.peaks[k, i] for ev in events if ev.kind == 'compression' for k in range(2)])
        brace = np.array([ev.peaks[k, i] for ev in events if ev.kind == 'bracing' for k in range(2)])
        comp, brace = comp[comp > floor], brace[brace > floor]
        faces.append(FaceWindow(face, f_min, f_max, enabled, int(comp.size),
                                int(((comp >= f_min) & (comp <= f_max)).sum()), int(brace.size),
                                int(((brace >= f_min) & (brace <= f_max)).sum())))
    comp_ev = [ev for ev in events if ev.kind == 'compression']
    brace_ev = [ev for ev in events if ev.kind == 'bracing']
    return SignatureWindows(tuple(faces), len(comp_ev), _caught(comp_ev, faces), len(brace_ev),
                            _caught(brace_ev, faces))


def shipped_windows() -> list[tuple[str, float, float, bool]]:
    """The windows of the shipped parameters (config/feedback.yaml)."""
    from .parameters import DEFAULT_WINDOWS

    return [(face, *DEFAULT_WINDOWS[face]) for face in FSR_FACES]


def main_events(paths: Sequence[str], floor: float, check_shipped: bool = False) -> int:
    """Calibrate from per-step collision records (events pooled); exit code 3 when the windows must not be shipped."""
    events = [ev for path in paths for ev in find_events(load_record(path))]
    if check_shipped:
        checked = check_windows(events, shipped_windows(), floor)
        sys.stdout.write('shipped windows on this record:\n' + format_windows(checked) + '\n')
        if checked.problems:
            sys.stderr.write('smarticle-feedback-calibrate: the shipped windows fail here: '
                             + '; '.join(checked.problems) + '\n')
            return 3
        return 0
    w = windows_from_events(events, floor)
    sys.stdout.write(format_windows(w) + '\n')
    if w.problems:
        sys.stderr.write('smarticle-feedback-calibrate: not shipping these windows: ' + '; '.join(w.problems) + '\n')
        return 3
    sys.stdout.write('\nfeedback parameters:\n' + windows_yaml(w))
    return 0


@closed_pipe_safe
def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of `smarticle-feedback-calibrate`: table on stdout, PNG next to the input (or --png)."""
    parser = argparse.ArgumentParser(prog='smarticle-feedback-calibrate', description=__doc__.split('\n')[0])
    add_version(parser, 'smarticle_feedback')
    parser.add_argument('recording', nargs='+',
                        help='c2_steps.npz of `smarticle-experiments c2-collisions` (several are pooled; per-face '
                        'windows from the '
                        'compression signature), or an npz of `smarticle-sim run ... --fsr` (percentile window)')
    parser.add_argument('--png', help='figure path (default: <recording>_window.png)')
    parser.add_argument('--floor', type=float, default=DEFAULT_FLOOR, help='ignore forces below this (N)')
    parser.add_argument('--low', type=float, default=80.0, help='percentile of f_min (default 80)')
    parser.add_argument('--high', type=float, default=100.0, help='percentile of f_max (default 100 = the largest)')
    parser.add_argument('--c2-only', action='store_true', help='pair runs: only samples with phi near 0')
    parser.add_argument('--check-shipped', action='store_true',
                        help='per-step records: count what the shipped windows catch instead of proposing new ones')
    args = parser.parse_args(argv)
    if all(_is_collision_record(path) for path in args.recording):
        try:
            return main_events(args.recording, args.floor, args.check_shipped)
        except (CalibrationInputError, OSError, KeyError, ValueError) as err:
            sys.stderr.write(f'smarticle-feedback-calibrate: {err}\n')
            return 2
    if len(args.recording) > 1:
        sys.stderr.write('smarticle-feedback-calibrate: several recordings are pooled only for per-step collision '
                         'records (smarticle-experiments c2-collisions)\n')
        return 2
    args.recording = args.recording[0]
    try:
        suggestion = calibrate_recording(args.recording, args.floor, args.low, args.high, args.c2_only)
    except (CalibrationInputError, OSError, KeyError, ValueError) as err:
        sys.stderr.write(f'smarticle-feedback-calibrate: {err}\n')
        return 2
    png = Path(args.png) if args.png else Path(args.recording).with_name(Path(args.recording).stem + '_window.png')
    plot_window(suggestion, png, f'{Path(args.recording).name}: collision forces')
    sys.stdout.write(format_table(suggestion) + '\n\nfeedback parameters:\n' + yaml_snippet(suggestion)
                     + f'\nfigure: {png}\n')
    return 0


def _is_collision_record(path: str) -> bool:
    """True if ``path`` is an npz written by ``CollisionRecord.save``."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return 'kind' in data.files and str(data['kind']) == 'collision_steps'
    except (OSError, ValueError):
        return False


if __name__ == '__main__':
    sys.exit(main())
