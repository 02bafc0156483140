"""Paper P6 in simulation: C2 pairs of the `feedback` robot, open loop against impact-halt feedback.

The batch core runs directly (no ROS): a batch trial (``run_trial``) whose runner has, before the gait
controller, a ``FeedbackController`` that feeds every control tick's FSR forces of both robots to one
``ImpactController`` per robot; a halt decided in a tick is part of that tick, so the in-process halt
latency is at most one control tick. ``smarticle-p6 --quick`` runs a small version.

Lifetime of a pair: the glider analysis of ``smarticle_tracking.gliders`` (``analyse_gliders`` with
``min_periods = 1`` and ``r_bind`` in feedback-robot body lengths); the lifetime is the length of the
bound run that starts in period 0 (0 if the pair is unbound in its first period), censored at the end
of the trial.
"""

from __future__ import annotations

import argparse
import csv
import functools
import math
import sys
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import GAIT_PERIOD, R_BIND_BL
from smarticle_common.gait import GaitConfig

from smarticle_feedback.controller import FeedbackConfig, ImpactController

#: The C2 start of the feedback robot (r in BL, theta, phi in deg, phases): where its C2 gliders live.
#: ``smarticle-c2-harvest --seeds 5000-5039 --periods 150`` ran 40 dense open-loop trials of 7 feedback
#: robots (90 deg, in phase, as the paper's collectives start) and sampled every C2 glider at its period
#: boundaries: 3705 samples of 36 gliders in 26 trials, median r 1.474 BL (quartiles 1.390-1.515), theta
#: 98.8 deg (76.0-116.3), phi 6.6 deg (-3.5-20.7); docs/feedback.md. In phase and alone, such a pair does
#: not touch: the robots' gait clocks (noise with a cause, ``p6_noise``) bring them into contact.
C2_START = (1.47, 99.0, 7.0, (0.0, 0.0))
#: A pair that collides from its first period (robot 2 a quarter period ahead, the paper's basin-scan
#: phase p = 0.25, side by side): the earlier P6 start, kept for the tests of the feedback paths, which
#: need halts within a few periods, and as ``--start colliding``.
COLLIDING_START = (1.3, 0.0, 350.0, (0.0, 0.25))
#: The named starts of ``smarticle-p6 --start`` and ``smarticle-c2-collisions --start`` placed from pair
#: coordinates.
STARTS = {'harvested': C2_START, 'colliding': COLLIDING_START}
#: The start taken from the full state of C2 gliders held by collisions in dense runs (``held_scene``).
HELD = 'held'
#: Every start name: ``STARTS`` and ``HELD``.
START_NAMES: tuple[str, ...] = (*STARTS, HELD)
#: The shipped starts of ``HELD``: ``smarticle-c2-harvest --seeds 5000-5039 --periods 150`` wrote them
#: (``c2_held_starts.csv``); see docs/feedback.md "Starting from the held C2".
HELD_STARTS_FILE = 'p6_held_c2.csv'


def start_base(name: str) -> tuple[float, float, float, tuple[float, float]] | str:
    """The ``base`` of ``run_pair_trial`` for a start name (ValueError naming the known ones)."""
    if name == HELD:
        return HELD
    if name not in STARTS:
        raise ValueError(f'start must be one of {", ".join(START_NAMES)}, got {name!r}')
    return STARTS[name]


def held_starts_path() -> Path:
    """The shipped held-C2 starts (config of the package: source tree or install share)."""
    here = Path(__file__).resolve().parent.parent / 'config' / HELD_STARTS_FILE
    if here.is_file():
        return here
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory('smarticle_experiments')) / 'config' / HELD_STARTS_FILE
    except (ImportError, LookupError, ValueError):
        return here


def load_held_starts(path: str | Path | None = None) -> tuple[Any, ...]:
    """The held-C2 starts (``C2Sample`` with state) of ``path`` (default: the shipped file), read once per
    process. ValueError if the file has no start with a state."""
    return _read_held_starts(str(path or held_starts_path()))


@functools.cache
def _read_held_starts(path: str) -> tuple[Any, ...]:
    from smarticle_experiments.c2_harvest import read_csv

    starts = tuple(s for s in read_csv(path) if s.state is not None)
    if not starts:
        raise ValueError(f'{path}: no start with a recorded state')
    return starts


def start_scene(config: Any, gait: GaitConfig, seed: int,
                base: tuple[float, float, float, tuple[float, float]] | str = C2_START,
                ) -> tuple[Any, tuple[float, float, float], tuple[float, float]]:
    """The pair scene of the seed's start, that start (r BL, theta deg, phi deg) and the two gait phases:
    ``base`` is a start's pair coordinates and phases (``STARTS``, ``c2_scene``) or ``HELD`` (``held_scene``,
    both in phase). ValueError for any other string."""
    if isinstance(base, str):
        if base != HELD:
            raise ValueError(f'base must be pair coordinates or {HELD!r}, got {base!r}')
        scene, start = held_scene(config, gait, seed)
        return scene, start, (0.0, 0.0)
    scene, start = c2_scene(config, gait, seed, base)
    return scene, start, base[3]


def held_scene(config: Any, gait: GaitConfig, seed: int, path: str | Path | None = None
               ) -> tuple[Any, tuple[float, float, float]]:
    """The pair scene of the seed's held-C2 start: the start drawn uniformly (``numpy`` generator of the seed)
    from ``load_held_starts(path)``, both robots at their recorded state, centred on the plate, each gait at
    its phase 0 (a period boundary of an in-phase run), and that start (r BL, theta deg, phi deg)."""
    from smarticle_sim.scenes import state_scene

    starts = load_held_starts(path)
    pick = starts[int(np.random.default_rng(seed).integers(len(starts)))]
    scene = state_scene(pick.state, [gait, gait], name='held-c2', seed=seed)
    return scene, (pick.r_bl, pick.theta_deg, pick.phi_deg)
#: Seeded jitter of the start (r in BL, theta and phi in deg).
C2_JITTER = (0.04, 4.0, 4.0)
#: Draws of the jittered start before giving up when they overlap (robots' arms at the start phases).
START_ATTEMPTS = 20


def p6_noise(name: str = 'paper') -> Any:
    """``NoiseConfig`` of a ``--noise`` name: 'paper' (every source at its cited default; the draws take the
    trial seed) or 'none' (None). The paper's robots start in phase and drift apart in phase; without
    clock noise two in-phase robots at the C2 start never touch."""
    from smarticle_sim.settings import NoiseConfig

    if name == 'paper':
        return NoiseConfig.paper()
    if name == 'none':
        return None
    raise ValueError(f"noise must be 'paper' or 'none', got {name!r}")


@dataclass(frozen=True)
class Condition:
    """One arm of the experiment: amplitude (deg) and whether the feedback controller runs."""

    alpha_max_deg: float
    feedback: bool

    @property
    def label(self) -> str:
        """Short name used in tables and figures."""
        return f'{"feedback" if self.feedback else "open loop"} {self.alpha_max_deg:g} deg'


@dataclass
class PairTrial:
    """Outcome of one pair trial."""

    condition: Condition
    seed: int
    times: np.ndarray                  # (S,) s
    r: np.ndarray                      # (S,) body lengths
    phi: np.ndarray                    # (S,) rad
    halts: list[tuple[float, int, str]] = field(default_factory=list)  # (time, robot, face)
    lifetime_periods: int = 0
    censored: bool = False
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    trouble: str = ''
    wall: float = 0.0
    travel_w: float = 0.0              # centre-of-mass displacement over the bound run (W = BL)
    #: With ``record_samples``: the FSR samples the controllers saw, (time, forces (2, 4) N) per tick.
    samples: list[tuple[float, np.ndarray]] = field(default_factory=list)
    #: With ``count_contacts``: the gait periods in which the robots touched (any physics step).
    contact_periods: list[int] = field(default_factory=list)


def c2_start(seed: int, base: tuple[float, float, float, tuple[float, float]] = C2_START,
             jitter: tuple[float, float, float] = C2_JITTER, attempt: int = 0) -> tuple[float, float, float]:
    """The seed's start (r BL, theta deg, phi deg): ``base`` plus uniform jitter (seed 0 = ``base``).

    ``attempt`` > 0 draws again (for a draw whose robots overlap); the draw depends only on (seed, attempt).
    """
    r, theta, phi, _ = base
    if seed == 0 and attempt == 0:
        return (r, theta, phi)
    u = np.random.default_rng([seed, attempt] if attempt else seed).uniform(-1.0, 1.0, size=3)
    return (r + jitter[0] * u[0], theta + jitter[1] * u[1], phi + jitter[2] * u[2])



def c2_scene(config: Any, gait: GaitConfig, seed: int,
             base: tuple[float, float, float, tuple[float, float]] = C2_START,
             ) -> tuple[Any, tuple[float, float, float]]:
    """The pair scene of the seed's C2 start (the first admissible of ``START_ATTEMPTS`` seeded draws) and
    that start (r BL, theta deg, phi deg)."""
    from smarticle_sim.errors import SceneError
    from smarticle_sim.scenes import pair_scene

    for attempt in range(START_ATTEMPTS):
        r, theta, phi = c2_start(seed, base, attempt=attempt)
        try:
            scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi), phases=base[3],
                               seed=seed)
        except SceneError:
            continue
        return scene, (r, theta, phi)
    raise SceneError(f'seed {seed}: no admissible C2 start near {base[:3]} at '
                     f'{math.degrees(gait.alpha_max):g} deg in {START_ATTEMPTS} draws')

def pair_lifetime(times: np.ndarray, poses: np.ndarray, period: float, body_length: float,
                  r_bind_bl: float = R_BIND_BL, t0: float = 0.0) -> tuple[int, bool]:
    """Bound periods from the start (glider analysis, K = 1) and whether the run lasted to the end."""
    from smarticle_tracking.gliders import GliderConfig, analyse_gliders

    cfg = GliderConfig(period=period, r_bind=r_bind_bl * body_length, min_periods=1,
                       body_length=body_length, width=body_length)
    analysis = analyse_gliders(times, poses, cfg, t0=t0)
    first = [g for g in analysis.gliders if g.start_period == 0]
    if not first:
        return 0, False
    return first[0].lifetime_periods, first[0].ongoing


def run_pair_trial(condition: Condition, seed: int, periods: float, feedback: FeedbackConfig | None = None,
                   preset: str = 'feedback', start_time: float = 0.0,
                   base: tuple[float, float, float, tuple[float, float]] | str = C2_START,
                   r_bind_bl: float = R_BIND_BL, sample_every: int = 3, record_samples: bool = False,
                   robot_changes: Mapping[str, float] | None = None, count_contacts: bool = False,
                   noise: Any = None, physics_changes: Mapping[str, Any] | None = None) -> PairTrial:
    """Run one C2 pair for ``periods`` gait periods, with the impact controller when ``condition.feedback``.

    ``robot_changes`` replaces fields of the preset's ``RobotSpec`` (the sensitivity study of the assumed values),
    ``physics_changes`` fields of its ``PhysicsConfig`` (a physics candidate, e.g. another restitution).
    ``count_contacts`` lists the gait periods in which the robots touched at any physics step
    (``PairTrial.contact_periods``; a step hook, the trajectory is the same).
    ``noise`` is a ``NoiseConfig`` (None: off); its draws take the trial ``seed`` unless it names its own.
    ``base`` is a start's pair coordinates (``STARTS``) or ``HELD``: the full state of a held C2 (``held_scene``).
    """
    from smarticle_sim.batch import run_trial
    from smarticle_sim.physics import Physics
    from smarticle_sim.runner import ContactPeriods, Controller, FeedbackController, GaitController
    from smarticle_sim.settings import SimConfig
    from smarticle_common.pairs import pair_coordinates

    wall0 = time.perf_counter()
    config = SimConfig.from_preset(preset)
    if robot_changes:
        config = replace(config, robot=replace(config.robot, **dict(robot_changes)))  # type: ignore[arg-type]
    if physics_changes:
        config = config.with_physics(**dict(physics_changes))
    if noise is not None:
        config = config.with_noise(noise)   # the pair scene carries the trial seed its draws take
    gait = GaitConfig.from_degrees(condition.alpha_max_deg, servo_speed=config.robot.servo_speed)
    scene, (r, theta, phi), phases = start_scene(config, gait, seed, base)
    feedback_controllers: list[FeedbackController] = []

    # every manifold point between the two robots counts, as the contact tables of docs/feedback.md were made
    counter = ContactPeriods(gait.period, start_time, max_distance=math.inf) if count_contacts else None

    def add_feedback(_: Physics, gaits: GaitController) -> Sequence[Controller]:
        extra: list[Controller] = [counter] if counter is not None else []
        if not condition.feedback:
            return extra
        fb = feedback or default_feedback_config()
        policies = {k: ImpactController(replace(fb, period=gait.period, phase=p)) for k, p in enumerate(phases)}
        for policy in policies.values():
            policy.start(start_time)
        feedback_controllers.append(FeedbackController(gaits, policies, record=record_samples))
        return [*extra, *feedback_controllers]

    recording = run_trial(config, scene, periods, sample_every=sample_every, controllers=add_feedback,
                          start_time=start_time)
    trial = PairTrial(condition, seed, recording.time, np.empty(0), np.empty(0), start=(r, theta, phi),
                      trouble=recording.trouble)
    if counter is not None:
        trial.contact_periods = sorted(counter.periods.get((0, 1), set()))
    if feedback_controllers:
        trial.halts = list(feedback_controllers[0].halts)
        trial.samples = list(feedback_controllers[0].samples or [])
    coords = pair_coordinates(recording.poses)
    trial.r = coords.r[:, 0] / config.robot.body_length
    trial.phi = coords.phi[:, 0]
    trial.lifetime_periods, trial.censored = pair_lifetime(recording.time, recording.poses, gait.period,
                                                          config.robot.body_length, r_bind_bl, t0=start_time)
    com = recording.poses[:, :, :2].mean(axis=1)
    end = int(np.searchsorted(recording.time, start_time + trial.lifetime_periods * gait.period))
    end = min(max(end, 0), len(com) - 1)
    trial.travel_w = float(np.linalg.norm(com[end] - com[0]) / config.robot.body_length)
    trial.wall = time.perf_counter() - wall0
    return trial


def default_feedback_config() -> FeedbackConfig:
    """The controller config of the shipped defaults (config/feedback.yaml)."""
    from smarticle_feedback.parameters import config_from_values, default_values

    return config_from_values(default_values())


def windows_file(path: str | Path) -> FeedbackConfig:
    """The feedback config of the shipped defaults with the impact windows of a YAML file: a ROS parameter
    file with a ``feedback`` (or ``/**``) section, e.g. ``config/feedback.yaml``, or a flat mapping such as the
    ``feedback parameters`` that ``smarticle-feedback-calibrate`` prints. ParameterError / ValueError name
    the problem (an unknown or out-of-range parameter, a file without windows)."""
    import yaml
    from smarticle_common.params import ParameterError, read_defaults_yaml
    from smarticle_feedback.parameters import NODE_NAME, config_from_values, default_values

    try:
        data: Any = read_defaults_yaml(str(path), NODE_NAME)
    except ParameterError:   # no node section: a flat mapping
        data = yaml.safe_load(Path(path).read_text(encoding='utf-8'))
    if not isinstance(data, dict) or not any(str(k).endswith(('_min', '_max', '_enabled')) for k in data):
        raise ParameterError(f'{path}: no impact windows (<face>_min / _max / _enabled) in it')
    return config_from_values(default_values(**data))


def _run(args: tuple[Condition, int, float, bool, str, str, FeedbackConfig | None, dict[str, Any]]) -> PairTrial:
    condition, seed, periods, contacts, start, noise, feedback, physics = args
    return run_pair_trial(condition, seed, periods, feedback=feedback, count_contacts=contacts, base=start_base(start),
                          noise=p6_noise(noise), physics_changes=physics)


def run_p6(conditions: Sequence[Condition], seeds: Sequence[int], periods: float, jobs: int = 2,
           progress: bool = True, contacts: bool = False, start: str = 'harvested',
           noise: str = 'paper', feedback: FeedbackConfig | None = None,
           physics: Mapping[str, Any] | None = None) -> list[PairTrial]:
    """Every (condition, seed) trial, ``jobs`` processes in parallel (at most 2 on the shared machine), from
    the named ``start`` (``STARTS``) with the named ``noise`` (``p6_noise``); the feedback conditions use
    ``feedback`` (default: the shipped windows, ``default_feedback_config``); ``physics`` replaces fields of
    the ``PhysicsConfig``."""
    start_base(start)
    p6_noise(noise)
    changes = dict(physics or {})
    work = [(c, s, periods, contacts, start, noise, feedback, changes) for c in conditions for s in seeds]
    trials: list[PairTrial] = []
    with ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
        for trial in pool.map(_run, work):
            trials.append(trial)
            if progress:
                sys.stderr.write(f'{trial.condition.label} seed {trial.seed}: lifetime {trial.lifetime_periods}'
                                 f'{"+" if trial.censored else ""} periods, {len(trial.halts)} halts, '
                                 f'{trial.wall:.1f} s\n')
    return trials


def summarize(trials: Sequence[PairTrial], periods: float) -> list[dict[str, object]]:
    """One row per condition: n, mean lifetime and its standard error, median, censored count, halts."""
    rows: list[dict[str, object]] = []
    for cond in dict.fromkeys(t.condition for t in trials):
        group = [t for t in trials if t.condition == cond]
        life = np.array([t.lifetime_periods for t in group], dtype=float)
        halts = np.array([len(t.halts) / max(periods, 1e-9) for t in group])
        rows.append({'condition': cond.label, 'alpha_max_deg': cond.alpha_max_deg, 'feedback': cond.feedback,
                     'n': len(group), 'mean_lifetime': float(life.mean()),
                     'se_lifetime': float(life.std(ddof=1) / math.sqrt(len(life))) if len(life) > 1 else math.nan,
                     'median_lifetime': float(np.median(life)),
                     'censored': sum(t.censored for t in group), 'halts_per_period': float(halts.mean()),
                     'travel_w': float(np.mean([t.travel_w for t in group])),
                     'se_travel_w': float(np.std([t.travel_w for t in group], ddof=1) / math.sqrt(len(group)))
                     if len(group) > 1 else math.nan,
                     'trouble': sum(bool(t.trouble) for t in group)})
    return rows


def kaplan_meier(lifetimes: Sequence[float], censored: Sequence[bool]) -> tuple[np.ndarray, np.ndarray]:
    """Kaplan-Meier survival: (times, S(t) just after each time), starting at (0, 1)."""
    life = np.asarray(lifetimes, dtype=float)
    cens = np.asarray(censored, dtype=bool)
    times, surv, s = [0.0], [1.0], 1.0
    for t in np.unique(life[~cens]):
        at_risk = int((life >= t).sum())
        events = int(((life == t) & ~cens).sum())
        s *= 1.0 - events / at_risk
        times.append(float(t))
        surv.append(s)
    return np.asarray(times), np.asarray(surv)


def logrank_test(a: Sequence[PairTrial], b: Sequence[PairTrial]) -> tuple[float, float]:
    """Log-rank test of two groups' lifetimes with censoring (``stats.logrank``): (statistic, p)."""
    from smarticle_experiments.stats import logrank

    return logrank(*(([t.lifetime_periods for t in g], [t.censored for t in g]) for g in (a, b)))


def plot_survival(trials: Sequence[PairTrial], path: Path, periods: float) -> Path:
    """Kaplan-Meier curve of the C2 lifetime of each condition (censored at the end of the run)."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.5), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    for cond in dict.fromkeys(t.condition for t in trials):
        group = [t for t in trials if t.condition == cond]
        times, surv = kaplan_meier([t.lifetime_periods for t in group], [t.censored for t in group])
        ax.step(np.append(times, periods), np.append(surv, surv[-1]), where='post',
                label=f'{cond.label} (n = {len(group)})')
    ax.set_xlabel('C2 lifetime (gait periods)')
    ax.set_ylabel('fraction still bound (Kaplan-Meier)')
    ax.set_xscale('symlog', linthresh=1.0)
    ax.set_title(f'C2 survival; runs censored at {periods:g} periods', fontsize=10)
    ax.legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def plot_transport(trials: Sequence[PairTrial], path: Path) -> Path:
    """Travel of the pair's centre of mass over its bound run against its lifetime, per condition (Fig. S8)."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.5), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    for cond in dict.fromkeys(t.condition for t in trials):
        group = [t for t in trials if t.condition == cond]
        ax.scatter([t.lifetime_periods for t in group], [t.travel_w for t in group], s=12, alpha=0.7,
                   label=f'{cond.label}: mean {np.mean([t.travel_w for t in group]):.2f} W')
    ax.set_xlabel('C2 lifetime (gait periods)')
    ax.set_ylabel('centre-of-mass travel while bound (W)')
    ax.set_title('C2 transport (Fig. S8): travel over the bound run', fontsize=10)
    ax.legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def format_contacts(trials: Sequence[PairTrial], periods: float) -> str:
    """Markdown table: periods in which the robots touched, all and second half, mean +- SE per condition."""
    out = ['| condition | n | periods with contact, mean +- SE | in the second half | final r (BL), median |',
           '| --- | ---: | ---: | ---: | ---: |']
    for cond in dict.fromkeys(t.condition for t in trials):
        group = [t for t in trials if t.condition == cond]
        cells = []
        for values in ([len(t.contact_periods) for t in group],
                       [sum(q >= periods / 2 for q in t.contact_periods) for t in group]):
            v = np.asarray(values, dtype=float)
            se = v.std(ddof=1) / math.sqrt(v.size) if v.size > 1 else math.nan
            cells.append(f'{v.mean():.1f} +- {se:.1f}')
        out.append(f'| {cond.label} | {len(group)} | {cells[0]} | {cells[1]} | '
                   f'{np.median([t.r[-1] for t in group]):.2f} |')
    return '\n'.join(out)


def format_summary(rows: Sequence[dict[str, object]], periods: float) -> str:
    """Markdown table of ``summarize`` rows."""
    out = [f'| condition | n | lifetime mean +- SE (periods) | median | reached the end ({periods:g}) | '
           'halts / period | travel +- SE (W) | trouble |', '| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    for row in rows:
        out.append(f'| {row["condition"]} | {row["n"]} | {row["mean_lifetime"]:.1f} +- {row["se_lifetime"]:.1f} | '
                   f'{row["median_lifetime"]:.0f} | {row["censored"]} | {row["halts_per_period"]:.2f} | '
                   f'{row["travel_w"]:.2f} +- {row["se_travel_w"]:.2f} | {row["trouble"]} |')
    return '\n'.join(out)


def plot_traces(trials: Sequence[PairTrial], path: Path, seed: int = 0, period: float = GAIT_PERIOD) -> Path:
    """r(t) of one seed for every condition (Fig. 5(c)); a vertical line marks the breakdown."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4.5), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    for t in (t for t in trials if t.seed == seed):
        line, = ax.plot(t.times / period, t.r, lw=0.8, label=t.condition.label)
        if not t.censored:
            ax.axvline(t.lifetime_periods, color=line.get_color(), lw=1.5)
    ax.axhline(R_BIND_BL, color='k', ls=':', lw=0.8, label=f'r_bind {R_BIND_BL:g} BL')
    ax.set_xlabel('time (gait periods)')
    ax.set_ylabel('r (BL)')
    ax.set_title(f'C2 pair, seed {seed}: r(t); solid vertical lines = breakdown', fontsize=10)
    ax.legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def plot_lifetimes(trials: Sequence[PairTrial], path: Path, periods: float) -> Path:
    """Lifetime distributions per condition (Fig. 5(d)): points per seed, mean +- SE."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.5), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    conds = list(dict.fromkeys(t.condition for t in trials))
    rng = np.random.default_rng(0)
    for x, cond in enumerate(conds):
        life = np.array([t.lifetime_periods for t in trials if t.condition == cond], dtype=float)
        ax.scatter(x + rng.uniform(-0.15, 0.15, life.size), life, s=12, alpha=0.6)
        se = life.std(ddof=1) / math.sqrt(life.size) if life.size > 1 else 0.0
        ax.errorbar(x + 0.3, life.mean(), yerr=se, fmt='s', color='k', capsize=4)
    ax.axhline(periods, color='grey', ls=':', lw=0.8, label='end of trial')
    ax.set_xticks(range(len(conds)), [c.label for c in conds], fontsize=8)
    ax.set_ylabel('C2 lifetime (gait periods)')
    ax.set_title('C2 pair lifetimes (points: seeds; squares: mean +- SE)', fontsize=10)
    ax.legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path


def physics_changes(parser: argparse.ArgumentParser, items: Sequence[str]) -> dict[str, Any]:
    """The ``--set NAME=VALUE`` items as PhysicsConfig changes; a bad name or value is a usage error naming it."""
    from smarticle_experiments.assignments import parse_assignments
    from smarticle_sim.settings import SimConfig

    try:
        changes = parse_assignments(items)
    except ValueError as err:
        parser.error(f'--set {err}')
    try:
        SimConfig.from_preset('feedback').with_physics(**changes)
    except (TypeError, ValueError) as err:   # an unknown field, or a value PhysicsConfig refuses
        parser.error(f'--set: {err}')
    return changes


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of `smarticle-p6`: table on stdout, CSV and PNGs in --out."""
    parser = argparse.ArgumentParser(prog='smarticle-p6', description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=40)
    parser.add_argument('--periods', type=float, default=200.0)
    parser.add_argument('--open-loop', type=float, nargs='*', default=[70.0, 80.0, 85.0, 90.0],
                        help='open-loop amplitudes (deg); none after the flag: no open-loop condition')
    parser.add_argument('--feedback', type=float, nargs='*', default=[90.0],
                        help='feedback amplitudes (deg); none after the flag: no feedback condition')
    parser.add_argument('--jobs', type=int, default=2, help='parallel processes (at most 2 here)')
    parser.add_argument('--out', default='out/feedback', help='output folder')
    parser.add_argument('--contacts', action='store_true',
                        help='also count the periods in which the robots touch (a step hook per trial)')
    parser.add_argument('--start', choices=sorted(START_NAMES), default='harvested',
                        help='harvested: where the C2 gliders of dense runs live (default); held: the full state of '
                             'a C2 glider held by collisions in a dense run (seeded pick of the shipped starts); '
                             'colliding: the earlier start, robot 2 a quarter period ahead')
    parser.add_argument('--noise', choices=['paper', 'none'], default='paper',
                        help='noise with a cause: paper (the cited defaults, default) or none')
    parser.add_argument('--windows', default=None,
                        help='YAML file of impact windows for the feedback conditions (a parameter file such as '
                             "config/feedback.yaml, or the 'feedback parameters' of smarticle-feedback-calibrate); "
                             'default: the shipped windows')
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help='replace a PhysicsConfig field for every trial (repeatable), e.g. restitution=0.5')
    parser.add_argument('--quick', action='store_true', help='3 seeds, 30 periods, open loop 90 vs feedback 90')
    args = parser.parse_args(argv)
    physics = physics_changes(parser, args.set)
    feedback = None
    if args.windows is not None:
        try:
            feedback = windows_file(args.windows)
        except (OSError, ValueError) as err:   # ParameterError is a ValueError
            parser.error(f'--windows: {err}')
    if args.quick:
        args.seeds, args.periods, args.open_loop, args.feedback = 3, 30.0, [90.0], [90.0]
    conditions = [Condition(a, False) for a in args.open_loop] + [Condition(a, True) for a in args.feedback]
    if not conditions:
        parser.error('no condition to run: give --open-loop or --feedback amplitudes')
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    wall = time.perf_counter()
    trials = run_p6(conditions, range(args.seeds), args.periods, min(args.jobs, 2), contacts=args.contacts,
                    start=args.start, noise=args.noise, feedback=feedback, physics=physics)
    rows = summarize(trials, args.periods)
    with (out / 'p6_trials.csv').open('w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(['condition', 'seed', 'r0_bl', 'theta0_deg', 'phi0_deg', 'lifetime_periods', 'censored',
                         'halts', 'final_r_bl', 'travel_w', 'contact_periods', 'contact_periods_second_half',
                         'trouble'])
        for t in trials:
            writer.writerow([t.condition.label, t.seed, f'{t.start[0]:.4f}', f'{t.start[1]:.2f}', f'{t.start[2]:.2f}',
                             t.lifetime_periods, t.censored, len(t.halts), f'{t.r[-1]:.3f}', f'{t.travel_w:.3f}',
                             len(t.contact_periods) if args.contacts else '',
                             sum(q >= args.periods / 2 for q in t.contact_periods) if args.contacts else '',
                             t.trouble])
    with (out / 'p6_summary.csv').open('w', newline='') as handle:
        summary_writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        summary_writer.writeheader()
        summary_writer.writerows(rows)
    plot_traces(trials, out / 'p6_r_traces.png')
    plot_lifetimes(trials, out / 'p6_lifetimes.png', args.periods)
    plot_survival(trials, out / 'p6_survival.png', args.periods)
    plot_transport(trials, out / 'p6_transport.png')
    sys.stdout.write(format_summary(rows, args.periods) + '\n')
    if args.contacts:
        sys.stdout.write(format_contacts(trials, args.periods) + '\n')
    for a in (c for c in conditions if c.feedback):
        for b in (c for c in conditions if not c.feedback and c.alpha_max_deg == a.alpha_max_deg):
            stat, p = logrank_test([t for t in trials if t.condition == b], [t for t in trials if t.condition == a])
            sys.stdout.write(f'log-rank {b.label} vs {a.label}: statistic {stat:.3f}, p = {p:.3g}\n')
    sys.stdout.write(f'\n{len(trials)} trials in {time.perf_counter() - wall:.0f} s; files in {out}/\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
