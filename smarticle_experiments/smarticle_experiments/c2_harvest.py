"""Where the feedback robot's C2 gliders live: their pair coordinates, harvested from dense open-loop runs.

P6 starts a pair of feedback robots "in the C2 conformation". Rather than guess that conformation, this
module lets the robots find it: it runs dense 7-robot trials of the feedback robot (in phase, open loop,
as the paper's collectives start), finds every C2 glider with the glider analysis (the one bound rule of
docs/gliders.md), and samples each glider's pair coordinates (r, theta, phi) at its period boundaries,
where both robots, being in phase, are at the gait's start shape. The median over those samples is a
start that ``pair_scene`` can place exactly (phases 0 and 0): ``p6.C2_START``.

A pair is written in the order that puts theta in [0, 180) deg (robot 2 on robot 1's front side): the two
orders of one C2 pair differ by about 180 deg in theta, and the median needs one of them.

Each dense trial is a ``c2_harvest`` trial kind on the experiments engine; the command line
``smarticle-experiments c2-harvest --seeds 5000..5019 --periods 150`` runs them into the store and writes
the table (stdout), the CSV of every sample, the held starts and the histogram PNG from the stored trials.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import R_BIND_BL
from smarticle_sim.scenes import STATE_FIELDS, RobotPlacement, RobotState

#: Periods skipped at the start of each glider (it settles onto its limit cycle first).
SETTLE_PERIODS = 5
#: Shortest glider that is harvested (periods): the paper's steady-state time, as in P1-P3.
MIN_PERIODS = 30


@dataclass(frozen=True)
class C2Sample:
    """One period boundary of one C2 glider."""

    seed: int
    i: int
    j: int
    period: int
    r_bl: float
    theta_deg: float
    phi_deg: float
    touched: bool = False   # the two robots touched at some physics step of the period that starts here
    #: The two robots' full state at this period boundary (robot i, then j), from which a new trial can start
    #: (``smarticle_sim.scenes.state_scene``); None when not recorded.
    state: tuple[RobotPlacement, RobotPlacement] | None = None


class PeriodSnapshots:
    """A controller that keeps every robot's full state (``Physics.placements``) at each gait period boundary."""

    def __init__(self, period: float, start_time: float = 0.0) -> None:
        self.period = period
        self.start_time = start_time
        self.states: dict[int, tuple[RobotPlacement, ...]] = {}

    def before_tick(self, runner: Any) -> None:
        """At a period boundary (the tick's time within 1e-9 s of one), keep the state."""
        k = round((runner.time - self.start_time) / self.period)
        if abs(runner.time - self.start_time - k * self.period) < 1e-9 and k not in self.states:
            self.states[k] = runner.physics.placements()


def harvest_trial(seed: int, periods: float = 150.0, preset: str = 'feedback', alpha_max_deg: float = 90.0,
                  robots: int = 7, min_periods: int = MIN_PERIODS, settle: int = SETTLE_PERIODS,
                  sample_every: int = 4) -> list[C2Sample]:
    """The C2 samples of one dense open-loop trial (seeded scene, in phase)."""
    return harvest_recording(seed, periods, preset, alpha_max_deg, robots, min_periods, settle, sample_every)[0]


def harvest_recording(seed: int, periods: float = 150.0, preset: str = 'feedback', alpha_max_deg: float = 90.0,
                      robots: int = 7, min_periods: int = MIN_PERIODS, settle: int = SETTLE_PERIODS,
                      sample_every: int = 4) -> tuple[list[C2Sample], str]:
    """The C2 samples of one dense open-loop trial and the SimTrouble message that ended it early ('' if none)."""
    from smarticle_common.gait import GaitConfig
    from smarticle_sim.batch import run_trial
    from smarticle_sim.runner import ContactPeriods
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.scenes import dense_scene
    from smarticle_tracking.gliders import GliderClass, GliderConfig, analyse_gliders

    config = build_config(preset)
    bl = config.robot.body_length
    gait = GaitConfig.from_degrees(alpha_max_deg, servo_speed=config.robot.servo_speed)
    scene = dense_scene(config.robot, gait, n=robots, seed=seed)
    watch = ContactPeriods(gait.period)   # contacts at every physics step (a kick lasts one to a few steps)
    snapshots = PeriodSnapshots(gait.period)   # reads only: the trajectory is the same
    rec = run_trial(config, scene, periods, sample_every=sample_every, record_contacts=False,
                    controllers=lambda physics, gaits: [watch, snapshots])
    cfg = GliderConfig(period=gait.period, r_bind=R_BIND_BL * bl, min_periods=min_periods, body_length=bl, width=bl)
    analysis = analyse_gliders(rec.time, rec.poses, cfg, t0=0.0)
    samples: list[C2Sample] = []
    for g in analysis.gliders:
        if g.glider_class is not GliderClass.C2:
            continue
        for k in range(g.start_period + settle, g.start_period + g.lifetime_periods):
            idx = int(np.argmin(np.abs(rec.time - k * gait.period)))
            if abs(rec.time[idx] - k * gait.period) > 1e-6:
                continue
            a, b, (r, theta, phi) = front_order(g.i, g.j, rec.poses[idx])
            touched = k in watch.periods.get((min(g.i, g.j), max(g.i, g.j)), set())
            state = snapshots.states.get(k)
            samples.append(C2Sample(seed, a, b, k, r / bl, theta, phi, touched,
                                    (state[a], state[b]) if state is not None else None))
    return samples, rec.trouble


def front_order(i: int, j: int, poses: np.ndarray) -> tuple[int, int, tuple[float, float, float]]:
    """The pair (i, j) of one frame's poses (N, 3) in the order that puts theta in [0, 180) deg, with its
    coordinates (r m, theta deg in [0, 180), phi deg in [0, 360))."""
    from smarticle_common.pairs import one_pair

    for a, b in ((i, j), (j, i)):
        r, theta, phi = one_pair(poses[a], poses[b])
        if math.degrees(theta) % 360.0 < 180.0:
            break
    return a, b, (r, math.degrees(theta) % 360.0, math.degrees(phi) % 360.0)


def _state_values(p: RobotPlacement) -> list[float]:
    """One robot's state as the ``ROBOT_COLUMNS`` values."""
    return [float(v) for v in (p.x, p.y, p.heading, p.alpha1, p.alpha2, *(p.state.values() if p.state else ()))]


def _placement(values: Sequence[float | str]) -> RobotPlacement:
    """A robot's state from its ``ROBOT_COLUMNS`` values."""
    v = [float(x) for x in values]
    return RobotPlacement(v[0], v[1], v[2], v[3], v[4], None, RobotState.from_values(v[5:]))


def sample_record(s: C2Sample) -> dict[str, Any]:
    """A sample as a JSON-ready dict (the stored form; floats exact, the state as two ``ROBOT_COLUMNS`` lists)."""
    return {'seed': s.seed, 'i': s.i, 'j': s.j, 'period': s.period, 'r_bl': s.r_bl, 'theta_deg': s.theta_deg,
            'phi_deg': s.phi_deg, 'touched': bool(s.touched),
            'state': None if s.state is None else [_state_values(p) for p in s.state]}


def sample_from_record(data: Mapping[str, Any]) -> C2Sample:
    """The sample of a ``sample_record`` dict."""
    state = data.get('state')
    return C2Sample(int(data['seed']), int(data['i']), int(data['j']), int(data['period']), float(data['r_bl']),
                    float(data['theta_deg']), float(data['phi_deg']), bool(data['touched']),
                    None if state is None else (_placement(state[0]), _placement(state[1])))


def signed_deg(angle: np.ndarray) -> np.ndarray:
    """Angles in degrees mapped to (-180, 180]."""
    return -((-np.asarray(angle, dtype=float) + 180.0) % 360.0 - 180.0)


def summary(samples: Sequence[C2Sample]) -> dict[str, float]:
    """Median and quartiles of r, theta and phi (phi about 0: taken in (-180, 180]); glider and seed counts."""
    if not samples:
        raise ValueError('no C2 samples: no C2 glider of the minimum length formed in these trials')
    r = np.array([s.r_bl for s in samples])
    theta = np.array([s.theta_deg for s in samples])
    phi = signed_deg(np.array([s.phi_deg for s in samples]))
    out: dict[str, float] = {'samples': float(len(samples)),
                             'gliders': float(len({(s.seed, min(s.i, s.j), max(s.i, s.j)) for s in samples})),
                             'seeds': float(len({s.seed for s in samples}))}
    for name, values in (('r_bl', r), ('theta_deg', theta), ('phi_deg', phi)):
        q1, med, q3 = np.percentile(values, [25, 50, 75])
        out.update({f'{name}_q1': float(q1), f'{name}_median': float(med), f'{name}_q3': float(q3)})
    return out


def format_summary(s: dict[str, float], touching: dict[str, float] | None = None) -> str:
    """Markdown table of the harvest's medians and quartiles; with ``touching`` (the summary of the samples
    whose period had a contact) a second column pair for those."""
    head = '| coordinate | median | quartiles |'
    rows = [head + (' median, periods with contact | quartiles |' if touching else ''),
            '| --- | ---: | --- |' + (' ---: | --- |' if touching else '')]
    for name, label in (('r_bl', 'r (BL)'), ('theta_deg', 'theta (deg)'), ('phi_deg', 'phi (deg)')):
        row = f'| {label} | {s[f"{name}_median"]:.3f} | {s[f"{name}_q1"]:.3f} - {s[f"{name}_q3"]:.3f} |'
        if touching:
            row += (f' {touching[f"{name}_median"]:.3f} | {touching[f"{name}_q1"]:.3f} - '
                    f'{touching[f"{name}_q3"]:.3f} |')
        rows.append(row)
    rows.append(f'\n{int(s["samples"])} period samples of {int(s["gliders"])} C2 gliders in {int(s["seeds"])} '
                f'trials (the first {SETTLE_PERIODS} periods of each glider skipped).')
    if touching:
        rows.append(f'In {int(touching["samples"])} of them ({touching["samples"] / s["samples"]:.0%}) the pair '
                    f'touched during the period ({int(touching["gliders"])} gliders, {int(touching["seeds"])} '
                    f'trials).')
    return '\n'.join(rows)


#: Columns of one robot's state in the samples CSV (prefixed ``a_`` for robot i, ``b_`` for robot j).
ROBOT_COLUMNS: tuple[str, ...] = ('x', 'y', 'heading', 'alpha1', 'alpha2', *STATE_FIELDS)
#: Columns of the samples CSV.
CSV_COLUMNS: tuple[str, ...] = ('seed', 'i', 'j', 'period', 'r_bl', 'theta_deg', 'phi_deg', 'touched',
                                *(f'{who}_{c}' for who in 'ab' for c in ROBOT_COLUMNS))


def write_csv(samples: Sequence[C2Sample], path: Path) -> Path:
    """Every sample as a CSV row, with the pair's full state (``ROBOT_COLUMNS`` of robots i and j; empty when
    not recorded). Floats are written with ``repr``: a start read back is the state to the last bit."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open('w', newline='') as fh:
        writer = csv.writer(fh)
        writer.writerow(CSV_COLUMNS)
        for s in samples:
            state: list[object] = [''] * (2 * len(ROBOT_COLUMNS))
            if s.state is not None:
                state = [repr(v) for p in s.state for v in _state_values(p)]
            writer.writerow([s.seed, s.i, s.j, s.period, f'{s.r_bl:.5f}', f'{s.theta_deg:.3f}', f'{s.phi_deg:.3f}',
                             int(s.touched), *state])
    return path


def read_csv(path: str | Path) -> list[C2Sample]:
    """The samples of a CSV of ``write_csv`` (with their states when the file has them). ValueError names the
    file and line of a row that cannot be read."""
    out: list[C2Sample] = []
    with Path(path).open(newline='') as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in CSV_COLUMNS[:7] if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f'{path}: not a C2 samples file (no column {missing[0]!r})')
        for line, row in enumerate(reader, start=2):
            try:
                state = None
                if row.get('a_x'):
                    state = (_placement([row[f'a_{c}'] for c in ROBOT_COLUMNS]),
                             _placement([row[f'b_{c}'] for c in ROBOT_COLUMNS]))
                out.append(C2Sample(int(row['seed']), int(row['i']), int(row['j']), int(row['period']),
                                    float(row['r_bl']), float(row['theta_deg']), float(row['phi_deg']),
                                    bool(int(row.get('touched') or 0)), state))
            except (KeyError, TypeError, ValueError) as exc:
                raise ValueError(f'{path}, line {line}: {exc}') from None
    return out


#: A glider is "held by collisions" if its robots touched in at least this share of its sampled periods.
HELD_SHARE = 0.5
#: Of a held glider's samples with contact, every this many-th is a start (consecutive periods of one glider
#: are nearly the same state; this keeps the shipped file small).
HELD_EVERY = 5


def held_starts(samples: Sequence[C2Sample], share: float = HELD_SHARE, every: int = HELD_EVERY) -> list[C2Sample]:
    """The starts of P6's ``held`` condition: of every C2 glider whose robots touched in at least ``share`` of
    its sampled periods (held by its collisions, as the paper's enveloping C2), the samples with contact and
    a recorded state, every ``every``-th of them (the first, the ``every + 1``-th, ...), in file order."""
    if every < 1:
        raise ValueError(f'every must be >= 1, got {every!r}')
    gliders: dict[tuple[int, int, int], list[C2Sample]] = {}
    for s in samples:
        gliders.setdefault((s.seed, min(s.i, s.j), max(s.i, s.j)), []).append(s)
    out: list[C2Sample] = []
    for group in gliders.values():
        if sum(x.touched for x in group) >= share * len(group):
            out += [s for s in group if s.touched and s.state is not None][::every]
    order = {id(s): k for k, s in enumerate(samples)}
    return sorted(out, key=lambda s: order[id(s)])


def plot(samples: Sequence[C2Sample], path: Path) -> Path:
    """Histograms of r, theta and phi of the harvested C2 samples, with their medians."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    s = summary(samples)
    fig = Figure(figsize=(10, 3.2), dpi=110)
    data = (('r_bl', 'r (BL)', [x.r_bl for x in samples]),
            ('theta_deg', 'theta (deg)', [x.theta_deg for x in samples]),
            ('phi_deg', 'phi (deg, signed)', list(signed_deg(np.array([x.phi_deg for x in samples])))))
    for n, (key, label, values) in enumerate(data):
        ax = fig.add_subplot(1, 3, n + 1)
        ax.hist(values, bins=30, color='tab:blue', alpha=0.8)
        ax.axvline(s[f'{key}_median'], color='k', lw=1.2, label=f'median {s[f"{key}_median"]:.2f}')
        ax.set_xlabel(label)
        ax.legend(fontsize=8)
    fig.suptitle(f'C2 gliders of the feedback robot at period boundaries: {int(s["samples"])} samples, '
                 f'{int(s["gliders"])} gliders, {int(s["seeds"])} trials', fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path
