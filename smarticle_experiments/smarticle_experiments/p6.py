"""Paper P6 in simulation: C2 pairs of the `feedback` robot, open loop against impact-halt feedback.

The batch core runs directly (no ROS): a batch trial (``run_trial``) whose runner has, before the gait
controller, a ``FeedbackController`` that feeds every control tick's FSR forces of both robots to one
``ImpactController`` per robot; a halt decided in a tick is part of that tick, so the in-process halt
latency is at most one control tick. The trials run as the ``p6`` trial kind on the experiments engine
(``smarticle-experiments p6``, or a spec of kind ``p6``); ``smarticle-experiments p6 --quick`` runs a small
version.

Lifetime of a pair: the glider analysis of ``smarticle_tracking.gliders`` (``analyse_gliders`` with
``min_periods = 1`` and ``r_bind`` in feedback-robot body lengths); the lifetime is the length of the
bound run that starts in period 0 (0 if the pair is unbound in its first period), censored at the end
of the trial.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import R_BIND_BL
from smarticle_common.gait import GaitConfig

from smarticle_feedback.controller import FeedbackConfig, ImpactController

#: The C2 start of the feedback robot (r in BL, theta, phi in deg, phases): where its C2 gliders live.
#: ``smarticle-experiments c2-harvest --seeds 5000..5039 --periods 150`` ran 40 dense open-loop trials of 7 feedback
#: robots (90 deg, in phase, as the paper's collectives start) and sampled every C2 glider at its period
#: boundaries: 3705 samples of 36 gliders in 26 trials, median r 1.474 BL (quartiles 1.390-1.515), theta
#: 98.8 deg (76.0-116.3), phi 6.6 deg (-3.5-20.7); docs/feedback.md. In phase and alone, such a pair does
#: not touch: the robots' gait clocks (noise with a cause, ``p6_noise``) bring them into contact.
C2_START = (1.47, 99.0, 7.0, (0.0, 0.0))
#: A pair that collides from its first period (robot 2 a quarter period ahead, the paper's basin-scan
#: phase p = 0.25, side by side): the earlier P6 start, kept for the tests of the feedback paths, which
#: need halts within a few periods, and as ``--start colliding``.
COLLIDING_START = (1.3, 0.0, 350.0, (0.0, 0.25))
#: The named starts of ``smarticle-experiments p6 --start`` and ``c2-collisions --start`` placed from pair
#: coordinates.
STARTS = {'harvested': C2_START, 'colliding': COLLIDING_START}
#: The start taken from the full state of C2 gliders held by collisions in dense runs (``held_scene``).
HELD = 'held'
#: Every start name: ``STARTS`` and ``HELD``.
START_NAMES: tuple[str, ...] = (*STARTS, HELD)
#: The shipped starts of ``HELD``: ``smarticle-experiments c2-harvest --seeds 5000..5039 --periods 150`` wrote them
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
                   noise: Any = None, physics_changes: Mapping[str, Any] | None = None,
                   engine: Any = None) -> PairTrial:
    """Run one C2 pair for ``periods`` gait periods, with the impact controller when ``condition.feedback``.

    ``robot_changes`` replaces fields of the preset's ``RobotSpec`` (the sensitivity study of the assumed values),
    ``physics_changes`` fields of its ``PhysicsConfig`` (a physics candidate, e.g. another restitution).
    ``count_contacts`` lists the gait periods in which the robots touched at any physics step
    (``PairTrial.contact_periods``; a step hook, the trajectory is the same).
    ``noise`` is a ``NoiseConfig`` (None: off); its draws take the trial ``seed`` unless it names its own.
    ``base`` is a start's pair coordinates (``STARTS``) or ``HELD``: the full state of a held C2 (``held_scene``).
    ``engine`` builds the world (``smarticle_sim.engines.engine_factory``; None: Bullet).
    """
    from smarticle_sim.batch import run_trial
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.engine import Engine
    from smarticle_sim.runner import ContactPeriods, Controller, FeedbackController, GaitController
    from smarticle_common.pairs import pair_coordinates

    wall0 = time.perf_counter()
    # the pair scene carries the trial seed the noise draws take
    config = build_config(preset, physics_changes, robot_changes, noise)
    gait = GaitConfig.from_degrees(condition.alpha_max_deg, servo_speed=config.robot.servo_speed)
    scene, (r, theta, phi), phases = start_scene(config, gait, seed, base)
    feedback_controllers: list[FeedbackController] = []

    # every manifold point between the two robots counts, as the contact tables of docs/feedback.md were made
    counter = ContactPeriods(gait.period, start_time, max_distance=math.inf) if count_contacts else None

    def add_feedback(_: Engine, gaits: GaitController) -> Sequence[Controller]:
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
                          start_time=start_time, engine=engine)
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


def window_values(path: str | Path) -> dict[str, Any]:
    """The impact-window parameters of a YAML file: a ROS parameter file with a ``feedback`` (or ``/**``)
    section, e.g. ``config/feedback.yaml``, or a flat mapping such as the ``feedback parameters`` that
    ``smarticle-feedback-calibrate`` prints; checked by building their config. ParameterError / ValueError /
    OSError name the problem (an unknown or out-of-range parameter, a file without windows, no file)."""
    import yaml
    from smarticle_common.params import ParameterError, read_defaults_yaml
    from smarticle_feedback.parameters import NODE_NAME

    try:
        data: Any = read_defaults_yaml(str(path), NODE_NAME)
    except ParameterError:   # no node section: a flat mapping
        data = yaml.safe_load(Path(path).read_text(encoding='utf-8'))
    if not isinstance(data, dict) or not any(str(k).endswith(('_min', '_max', '_enabled')) for k in data):
        raise ParameterError(f'{path}: no impact windows (<face>_min / _max / _enabled) in it')
    values = {str(k): v for k, v in data.items()}
    windows_config(values)
    return values


def windows_config(values: Mapping[str, Any]) -> FeedbackConfig:
    """The feedback config of the shipped defaults with the parameters ``values`` (``window_values``)."""
    from smarticle_feedback.parameters import config_from_values, default_values

    return config_from_values(default_values(**dict(values)))


def windows_file(path: str | Path) -> FeedbackConfig:
    """The feedback config of the shipped defaults with the impact windows of a YAML file (``window_values``)."""
    return windows_config(window_values(path))


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


def format_summary(rows: Sequence[dict[str, object]], periods: float) -> str:
    """Markdown table of ``summarize`` rows."""
    out = [f'| condition | n | lifetime mean +- SE (periods) | median | reached the end ({periods:g}) | '
           'halts / period | travel +- SE (W) | trouble |', '| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    for row in rows:
        out.append(f'| {row["condition"]} | {row["n"]} | {row["mean_lifetime"]:.1f} +- {row["se_lifetime"]:.1f} | '
                   f'{row["median_lifetime"]:.0f} | {row["censored"]} | {row["halts_per_period"]:.2f} | '
                   f'{row["travel_w"]:.2f} +- {row["se_travel_w"]:.2f} | {row["trouble"]} |')
    return '\n'.join(out)
