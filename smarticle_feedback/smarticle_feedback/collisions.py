"""The collisions of a pair run, one event per contact: gait quarter, links and faces touched, FSR peaks, dr.

Pure NumPy (no sim, no rclpy). Input: a per-physics-step record of a two-robot run (``CollisionRecord``:
times, the FSR forces of both robots, which links of robot 0 touch which links of robot 1, and the
pair distance r). An *event* is a run of steps in which the robots touch, runs closer than ``merge_gap``
seconds merged. For each event: the gait quarter of each robot at the event's peak force, the link
pairs touched (``arm1>body``: robot 0's arm 1 on robot 1's body), the peak force of every FSR face of
both robots, and the change of r it produced: ``r_after - r_before``, r just before the event against
r ``settle`` seconds after its end (or just before the next event, whichever is first).

Kinds, by effect (the paper's Fig. 4a(ii)): ``compression`` when the event pushes the pair apart by more
than ``dr_tolerance`` body lengths (collision 2, a body enveloped by the other's arms); ``bracing`` when it
pulls them together by more than that (collisions 1 and 3, an arm bracing the other's body); ``neutral``
otherwise. ``enveloped`` marks events in which both arms of one robot touched the other's body.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from smarticle_common.topics import FSR_FACES

from .errors import CalibrationInputError

#: Link names of a robot, in the order of ``CollisionRecord.links``' axes (body, arm 1, arm 2).
LINKS = ('body', 'arm1', 'arm2')
#: Contact runs closer than this (s) are one event (a kick that rattles for a step or two).
MERGE_GAP = 0.010
#: r is read this long (s) after an event's end (the pair slides apart or together after a kick).
SETTLE = 0.10
#: |dr| (BL) below this is a neutral event.
DR_TOLERANCE = 0.002


@dataclass(frozen=True)
class CollisionRecord:
    """Per-step record of a two-robot run (S steps)."""

    times: np.ndarray        # (S,) s
    fsr: np.ndarray          # (S, 2, 4) N, faces in FSR_FACES order
    links: np.ndarray        # (S, 3, 3) bool: links[s, i, j] = robot 0's link i touches robot 1's link j
    r: np.ndarray            # (S,) pair distance (BL)
    period: float            # gait period (s)
    phases: tuple[float, float]
    start_time: float = 0.0
    #: Each robot's gait clock rate (1 + eps, noise with a cause): its gait time is (t - start) * rate.
    clock_rates: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        s = self.times.shape[0]
        for name, shape in (('fsr', (s, 2, len(FSR_FACES))), ('links', (s, 3, 3)), ('r', (s,))):
            if getattr(self, name).shape != shape:
                raise CalibrationInputError(f'CollisionRecord.{name} must have shape {shape}, '
                                            f'got {getattr(self, name).shape}')
        if not (math.isfinite(self.period) and self.period > 0.0):
            raise CalibrationInputError(f'CollisionRecord.period must be > 0 s, got {self.period!r}')

    def save(self, path: str | Path) -> Path:
        """Write the record as an npz (``load_record`` reads it back)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, times=self.times, fsr=self.fsr, links=self.links, r=self.r,
                            period=self.period, phases=np.asarray(self.phases), start_time=self.start_time,
                            clock_rates=np.asarray(self.clock_rates), kind='collision_steps')
        return path


def load_record(path: str | Path) -> CollisionRecord:
    """Read an npz written by ``CollisionRecord.save`` (CalibrationInputError if it is not one)."""
    with np.load(path, allow_pickle=False) as data:
        if 'kind' not in data.files or str(data['kind']) != 'collision_steps':
            raise CalibrationInputError(f'{path}: not a per-step collision record (record one with '
                                        '`smarticle-experiments c2-collisions`)')
        phases = data['phases']
        rates = data['clock_rates'] if 'clock_rates' in data.files else np.ones(2)   # records before noise
        return CollisionRecord(data['times'], data['fsr'], data['links'].astype(bool), data['r'],
                               float(data['period']), (float(phases[0]), float(phases[1])),
                               float(data['start_time']), (float(rates[0]), float(rates[1])))


@dataclass(frozen=True)
class CollisionEvent:
    """One contact event of the pair."""

    index: int
    t_start: float
    t_end: float
    t_peak: float
    quarters: tuple[int, int]        # gait quarter (0-3) of robot 0 and robot 1 at the peak
    periods: tuple[int, int]         # gait period of robot 0 and robot 1 at the peak
    links: tuple[str, ...]           # 'arm1>body' = robot 0's arm 1 touched robot 1's body
    peaks: np.ndarray                # (2, 4) peak force (N) of every face of both robots
    r_before: float                  # BL
    r_after: float                   # BL
    enveloped: bool                  # both arms of one robot touched the other's body
    kind: str                        # 'compression', 'bracing' or 'neutral'
    steps: int = 1                   # physics steps in contact

    @property
    def dr(self) -> float:
        """Change of r (BL) the event produced (> 0: pushed apart)."""
        return self.r_after - self.r_before

    @property
    def duration(self) -> float:
        """Contact time (s)."""
        return self.t_end - self.t_start

    def faces(self, floor: float) -> list[str]:
        """'k:face' for each FSR face of robot k whose peak exceeds ``floor`` (N)."""
        return [f'{k}:{face}' for k in range(2) for i, face in enumerate(FSR_FACES) if self.peaks[k, i] > floor]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) indices of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), (np.flatnonzero(edges == -1) - 1).tolist(), strict=True))


def find_events(rec: CollisionRecord, merge_gap: float = MERGE_GAP, settle: float = SETTLE,
                dr_tolerance: float = DR_TOLERANCE) -> list[CollisionEvent]:
    """Every contact event of the record, in time order."""
    touching = np.asarray(rec.links.any(axis=(1, 2)), dtype=bool)
    runs = _runs(touching)
    merged: list[tuple[int, int]] = []
    for first, last in runs:
        if merged and rec.times[first] - rec.times[merged[-1][1]] <= merge_gap:
            merged[-1] = (merged[-1][0], last)
        else:
            merged.append((first, last))
    events: list[CollisionEvent] = []
    times = rec.times
    for n, (first, last) in enumerate(merged):
        seg = slice(first, last + 1)
        total = rec.fsr[seg].sum(axis=(1, 2))
        peak_at = first + int(np.argmax(total))
        t_peak = float(times[peak_at])
        taus = [(t_peak - rec.start_time) * rate / rec.period + p for p, rate in zip(rec.phases, rec.clock_rates,
                                                                                   strict=True)]
        quarters = (int(math.floor(4.0 * taus[0])) % 4, int(math.floor(4.0 * taus[1])) % 4)
        periods = (int(math.floor(taus[0])), int(math.floor(taus[1])))
        touched = np.asarray(rec.links[seg].any(axis=0), dtype=bool)
        links = tuple(f'{LINKS[i]}>{LINKS[j]}' for i in range(3) for j in range(3) if touched[i, j])
        enveloped = bool((touched[1, 0] and touched[2, 0]) or (touched[0, 1] and touched[0, 2]))
        before = max(first - 1, 0)
        after_t = times[last] + settle
        after = int(np.searchsorted(times, after_t))
        if n + 1 < len(merged):
            after = min(after, merged[n + 1][0] - 1)
        after = min(max(after, last), len(times) - 1)
        r_before, r_after = float(rec.r[before]), float(rec.r[after])
        dr = r_after - r_before
        kind = 'compression' if dr > dr_tolerance else 'bracing' if dr < -dr_tolerance else 'neutral'
        events.append(CollisionEvent(n, float(times[first]), float(times[last]), t_peak, quarters, periods, links,
                                     rec.fsr[seg].max(axis=0), r_before, r_after, enveloped, kind,
                                     int(touching[seg].sum())))
    return events


def format_events(events: Sequence[CollisionEvent], floor: float = 0.05, limit: int | None = None) -> str:
    """Markdown table: one row per event (the paper's Fig. 4a/b as a table)."""
    head = ('| # | t (s) | period | quarter 0 / 1 | steps | links (robot 0 > robot 1) | enveloped | '
            + ' | '.join(f'{k}:{f}' for k in range(2) for f in FSR_FACES) + ' | dr (BL) | kind |')
    rows = [head, '| ' + ' | '.join(['---:'] * 5 + ['---', '---'] + ['---:'] * 9 + ['---']) + ' |']
    for ev in events[:limit]:
        forces = ' | '.join(f'{v:.2f}' if v > floor else '' for v in ev.peaks.ravel())
        rows.append(f'| {ev.index} | {ev.t_peak:.3f} | {ev.periods[0]} | {ev.quarters[0]} / {ev.quarters[1]} | '
                    f'{ev.steps} | {" ".join(ev.links)} | {"yes" if ev.enveloped else ""} | {forces} | '
                    f'{ev.dr:+.4f} | {ev.kind} |')
    return '\n'.join(rows)


def write_events_csv(events: Sequence[CollisionEvent], path: str | Path) -> Path:
    """One CSV row per event (peaks of every face of both robots in N)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open('w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(['index', 't_start', 't_end', 't_peak', 'steps', 'period0', 'quarter0', 'quarter1', 'links',
                         'enveloped', *[f'peak{k}_{f}' for k in range(2) for f in FSR_FACES], 'r_before',
                         'r_after', 'dr', 'kind'])
        for ev in events:
            writer.writerow([ev.index, f'{ev.t_start:.5f}', f'{ev.t_end:.5f}', f'{ev.t_peak:.5f}', ev.steps,
                             ev.periods[0], ev.quarters[0], ev.quarters[1], ' '.join(ev.links), int(ev.enveloped),
                             *[f'{v:.4f}' for v in ev.peaks.ravel()], f'{ev.r_before:.5f}', f'{ev.r_after:.5f}',
                             f'{ev.dr:.5f}', ev.kind])
    return path


@dataclass(frozen=True)
class Signature:
    """How the compression events differ from the bracing ones: counts by quarter, link, face, force."""

    counts: dict[str, int]                          # events of each kind
    quarters: dict[str, dict[tuple[int, int], int]]  # kind -> (quarter 0, quarter 1) -> events
    links: dict[str, dict[str, int]]                # kind -> link pair -> events
    face_peaks: dict[str, dict[str, np.ndarray]]    # kind -> face -> peak forces (N) above the floor, both robots
    mean_dr: dict[str, float]


def signature(events: Sequence[CollisionEvent], floor: float = 0.05) -> Signature:
    """The force, face and phase signature of each kind of event."""
    kinds = ('compression', 'bracing', 'neutral')
    counts = {k: 0 for k in kinds}
    quarters: dict[str, dict[tuple[int, int], int]] = {k: {} for k in kinds}
    links: dict[str, dict[str, int]] = {k: {} for k in kinds}
    peaks: dict[str, dict[str, list[float]]] = {k: {f: [] for f in FSR_FACES} for k in kinds}
    drs: dict[str, list[float]] = {k: [] for k in kinds}
    for ev in events:
        counts[ev.kind] += 1
        quarters[ev.kind][ev.quarters] = quarters[ev.kind].get(ev.quarters, 0) + 1
        for link in ev.links:
            links[ev.kind][link] = links[ev.kind].get(link, 0) + 1
        for k in range(2):
            for i, face in enumerate(FSR_FACES):
                if ev.peaks[k, i] > floor:
                    peaks[ev.kind][face].append(float(ev.peaks[k, i]))
        drs[ev.kind].append(ev.dr)
    return Signature(counts, quarters, links,
                     {k: {f: np.asarray(v) for f, v in faces.items()} for k, faces in peaks.items()},
                     {k: float(np.mean(v)) if v else math.nan for k, v in drs.items()})


def format_signature(sig: Signature) -> str:
    """Markdown tables: per kind the events, mean dr, quarters and links; per face the peak forces."""
    rows = ['| kind | events | mean dr (BL) | quarters (robot 0 / robot 1: events) | links (events) |',
            '| --- | ---: | ---: | --- | --- |']
    for kind, n in sig.counts.items():
        qs = ', '.join(f'{a}/{b}: {c}' for (a, b), c in sorted(sig.quarters[kind].items(), key=lambda x: -x[1]))
        ls = ', '.join(f'{link}: {c}' for link, c in sorted(sig.links[kind].items(), key=lambda x: -x[1]))
        rows.append(f'| {kind} | {n} | {sig.mean_dr[kind]:+.4f} | {qs} | {ls} |')
    rows += ['', '| face | compression: n, median, min-max (N) | bracing: n, median, min-max (N) |',
             '| --- | --- | --- |']
    for face in FSR_FACES:
        cells = []
        for kind in ('compression', 'bracing'):
            v = sig.face_peaks[kind][face]
            cells.append(f'{v.size}, {np.median(v):.2f}, {v.min():.2f}-{v.max():.2f}' if v.size else '0')
        rows.append(f'| {face} | {cells[0]} | {cells[1]} |')
    return '\n'.join(rows)


def plot_events(rec: CollisionRecord, events: Sequence[CollisionEvent], path: str | Path,
                periods: tuple[float, float] | None = None) -> Path:
    """r(t) and each robot's FSR faces over a few periods, events shaded by kind (Fig. 4a/b), PNG."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    path = Path(path)
    lo, hi = periods if periods is not None else (0.0, min(3.0, rec.times[-1] / rec.period))
    sel = (rec.times >= rec.start_time + lo * rec.period) & (rec.times <= rec.start_time + hi * rec.period)
    t = (rec.times[sel] - rec.start_time) / rec.period
    fig = Figure(figsize=(10, 7), dpi=110)
    axes = [fig.add_subplot(3, 1, i + 1) for i in range(3)]
    axes[0].plot(t, rec.r[sel], color='k', lw=1.0)
    axes[0].set_ylabel('r (BL)')
    colours = {'compression': 'tab:red', 'bracing': 'tab:green', 'neutral': 'tab:grey'}
    for k in range(2):
        for i, face in enumerate(FSR_FACES):
            axes[k + 1].plot(t, rec.fsr[sel, k, i], lw=0.8, label=face)
        axes[k + 1].set_ylabel(f'robot {k} FSR (N)')
    for ev in events:
        a, b = ((ev.t_start - rec.start_time) / rec.period, (ev.t_end - rec.start_time) / rec.period)
        if b < lo or a > hi:
            continue
        for ax in axes:
            ax.axvspan(a - 0.004, b + 0.004, color=colours[ev.kind], alpha=0.25)
        axes[0].annotate(f'{ev.index}', ((a + b) / 2, float(np.max(rec.r[sel]))), fontsize=7, ha='center')
    for q in np.arange(math.ceil(4 * lo) / 4, hi, 0.25):
        for ax in axes:
            ax.axvline(q, color='k', lw=0.3, ls=':')
    axes[1].legend(fontsize=7, ncol=4)
    axes[2].set_xlabel('time (gait periods of robot 0; dotted: quarters)')
    axes[0].set_title('C2 pair: contact events (red: compression, dr > 0; green: bracing, dr < 0)', fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path
