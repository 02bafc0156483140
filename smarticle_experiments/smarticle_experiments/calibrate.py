"""Calibration from recorded bags: rebuild each run's scene, simulate it, compare, fit, write a preset file.

A bag of a run (the robots' boards and the overhead tracker, or the sim bridge with ``record:=true
record_robots:=true``) holds what a comparison needs: ``/smarticles/poses`` (the tracked poses),
``/smarticles/start`` (the gaits' shared start) and each robot's ``joint_commands`` or ``joint_states`` (the
gait amplitude and each robot's clock, ``smarticle_tracking.clocks``) and ``fsr``. ``load_run`` reads it into a
``BagRun`` (its poses once per gait period from the start). The run is cut into segments of one burn-in period
and ``SEGMENT_PERIODS`` compared periods, one every ``SEGMENT_PERIODS`` periods; ``simulate`` restarts the batch
core (no ROS) at each segment from the bag's poses at its start (``scene_of``: the bag's gait amplitude and
period, the phase each robot's clock has reached, its measured clock rate), so a chaotic run's divergence stays
within one segment. The observables of a segment, over its compared periods:

* ``speed``: each robot's travel per period (BL / period);
* ``turn``: each robot's heading change per period (rad / period);
* ``r``, ``phi``: each pair's centre distance (BL) and relative heading (rad, wrapped) at the segment's end
  (runs of two or three robots);
* ``fsr``: each robot's mean per-period peak FSR force (N), where the bag recorded FSR.

The gap of an observable is the root mean square of (sim - bag) over its segments and components. The
distance a fit minimises is stated once:

    D(p) = sum over observables and terms of soft_l1((sim - bag) / SCALES[observable])
    soft_l1(z) = 2 (sqrt(1 + z^2) - 1)

(z^2 near zero, 2 |z| far out, so one segment where a robot flips does not outweigh the rest), each gap
normalised by a fixed scale (``SCALES``, about what a tracker resolves) so no observable outweighs the others
by its unit. The fit is a coarse grid (``scipy.optimize.brute``) then ``scipy.optimize.minimize`` (Powell,
bounded, on parameters scaled to [0, 1]); the sim is deterministic (no noise: common random numbers by
construction), so ``D`` is a function of the parameters alone. Each fitted value's 95 % interval is a
bootstrap over the runs' segments: each resample of the segments picks, among the parameter values the
search evaluated, the one with the least distance over it; the interval holds the middle 95 % of the picks
(``fit``). Trials run on Dask (``smarticle_experiments.engine.dask_client``) when asked.

Binding and lifetimes are compared over the whole run, not per segment (a segment of ``SEGMENT_PERIODS``
periods cannot show a bound pair's life), and are reported but not part of ``D``: a free-running chaotic sim
of a dense run diverges from the bag within a few periods, so which pair is bound when is no match to fit,
only the run's statistics are. For each run of two or more robots the sim runs once from the bag's poses at
the first period that sees every robot (``scene_of``, each robot's measured clock rate) to the run's end
(``simulate_whole``); in the bag's strobe and the sim's alike, a pair is bound in period q if its centre
distance at the period's strobe (its first pose, start + q T) is under the bind radius (``R_BIND_BL`` body
lengths of the preset's robot, ``smarticle_tracking.gliders.frame_hits``: the project's one bound rule, an
unseen robot binds nothing). ``binding_stats`` gives:

* ``bound share``: the bound pair-periods over all pair-periods of the runs (a fraction);
* ``lifetime``: the mean length (periods) of the bound runs, maximal stretches of consecutive bound periods
  (``smarticle_tracking.gliders.bound_runs``); a run still bound at the end of the data is counted as long as
  it was seen (censored), NaN if no pair was ever bound.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import optimize

from smarticle_common.facts import GAIT_PERIOD, PRESETS, R_BIND_BL, RobotSpec
from smarticle_common.gait import GaitConfig
from smarticle_sim.config_builder import build_config, is_preset_file, read_preset_file
from smarticle_sim.errors import ConfigError
from smarticle_sim.settings import PhysicsConfig, SimConfig

from .errors import ExperimentError

FloatArray = npt.NDArray[np.float64]

#: Compared gait periods per segment of a run (the unit of the observables and of the bootstrap).
SEGMENT_PERIODS = 2
#: The scale of each observable's gap in the distance (its unit: BL / period, rad / period, BL, rad, N). FSR's is
#: wide: a contact is there or not, and a pose a fraction of a millimetre off switches a period's peak.
SCALES: dict[str, float] = {'speed': 0.002, 'turn': 0.01, 'r': 0.05, 'phi': 0.1, 'fsr': 0.5}
#: Units of the observables, for the report.
UNITS: dict[str, str] = {'speed': 'BL/period', 'turn': 'rad/period', 'r': 'BL', 'phi': 'rad', 'fsr': 'N'}
#: The whole-run binding observables (reported, not in the distance) and their units.
BINDING_UNITS: dict[str, str] = {'bound share': 'fraction', 'lifetime': 'periods'}


class BagFitError(ExperimentError, ValueError):
    """Bad input to the calibration: a missing bag, a bag without poses, an unknown parameter."""


@dataclass(frozen=True)
class Parameter:
    """A parameter the fit can move: its group (physics or robot), field and bounds."""

    name: str
    group: str
    lo: float
    hi: float


def _float_fields(cls: type, exclude: set[str]) -> dict[str, float]:
    defaults = cls() if cls is PhysicsConfig else PRESETS['small']
    return {f.name: float(getattr(defaults, f.name)) for f in fields(cls)
            if f.name not in exclude and isinstance(getattr(defaults, f.name), float)
            and not isinstance(getattr(defaults, f.name), bool)}


#: Physics fields that shape the run's numerics or its trouble checks, not the robots: not fitted.
_NOT_FITTED = {'time_step', 'control_tick', 'plate_size', 'plate_thickness', 'max_tilt', 'max_speed',
               'max_penetration', 'fsr_window', 'contact_breaking_threshold', 'gravity', 'position_gain',
               'ccd_swept_sphere_radius', 'restitution_velocity_threshold'}
#: Default bounds of the named parameters (others: half to twice their default).
_BOUNDS: dict[str, tuple[float, float]] = {
    'friction_body_plate': (0.05, 1.0), 'friction_robot_robot': (0.05, 1.0), 'restitution': (0.0, 1.0),
    'servo_bandwidth': (20.0, 1000.0),
    # rad/s: the default is the slowest servo whose 180 deg stroke of the 90 deg gait fits a quarter of the 1.6 s
    # period (``GaitConfig``), so the default bounds run from it up to twice it
    'servo_speed': (PRESETS['small'].servo_speed, 2.0 * PRESETS['small'].servo_speed),
}


def fittable() -> dict[str, Parameter]:
    """Every parameter name ``--fit`` accepts: float PhysicsConfig fields (friction coefficients, restitution,
    servo bandwidth, ...) and RobotSpec fields (servo speed, masses, ...), with their default bounds."""
    out: dict[str, Parameter] = {}
    for group, cls, exclude in (('physics', PhysicsConfig, _NOT_FITTED), ('robot', RobotSpec, set())):
        for name, value in _float_fields(cls, exclude).items():
            lo, hi = _BOUNDS.get(name, (0.5 * value, 2.0 * value) if value > 0 else (0.0, 1.0))
            out[name] = Parameter(name, group, lo, hi)
    for name in ('restitution_body_plate', 'servo_bandwidth', 'friction_arm_arm'):  # optional floats
        lo, hi = _BOUNDS.get(name, (0.05, 1.0))
        out.setdefault(name, Parameter(name, 'physics', lo, hi))
    return out


def parse_fit(text: str) -> list[Parameter]:
    """``NAME[=LO:HI][,NAME...]`` into parameters; BagFitError naming an unknown name or a bad bound."""
    known = fittable()
    out = []
    for item in (s.strip() for s in text.split(',')):
        if not item:
            continue
        name, _, bounds = item.partition('=')
        if name not in known:
            raise BagFitError(f'--fit: {name!r} is no parameter to fit; known: {", ".join(sorted(known))}')
        param = known[name]
        if bounds:
            try:
                lo, hi = (float(v) for v in bounds.split(':'))
            except ValueError:
                raise BagFitError(f'--fit: {item!r}: bounds are LO:HI, two numbers') from None
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise BagFitError(f'--fit: {item!r}: bounds need LO < HI, both finite')
            param = Parameter(name, param.group, lo, hi)
        out.append(param)
    if not out:
        raise BagFitError('--fit names no parameter')
    return out


def check_bounds(params: Sequence[Parameter], runs: Sequence[BagRun]) -> None:
    """BagFitError if a bound of ``servo_speed`` is too slow for a run's gait: a stroke of 2 alpha_max must take
    at most a quarter period (``GaitConfig``), so the fit could not build that run's scene there."""
    from smarticle_common.gait import GaitError, slowest_servo

    for param in params:
        if param.name != 'servo_speed':
            continue
        for run in runs:
            try:
                GaitConfig(run.alpha_max, run.period, param.lo)
            except GaitError as err:
                least = slowest_servo(run.alpha_max, run.period)
                raise BagFitError(f'--fit servo_speed: its lower bound {param.lo:g} rad/s is too slow for the gait '
                                  f'of {run.name} ({err}); give servo_speed=LO:HI with LO >= {least:.4g}') from None


@dataclass(frozen=True)
class BagRun:
    """One recorded run: stroboscopic poses (one per gait period from the start) and what the scene needs."""

    name: str
    start: float                      # the gaits' start (s, bag stamps)
    period: float                     # the nominal gait period (s)
    alpha_max: float                  # rad
    first: FloatArray                 # (n, 3) the first tracked poses at or after the start
    strobe: FloatArray                # (periods + 1, n, 3) poses at start + k * period (NaN if unseen)
    phases: tuple[float, ...]
    rates: tuple[float, ...]
    fsr_peaks: FloatArray | None      # (periods, n) per-period peak FSR force, or None
    notes: tuple[str, ...] = ()

    @property
    def robots(self) -> int:
        return int(self.first.shape[0])

    @property
    def periods(self) -> int:
        return int(self.strobe.shape[0]) - 1


def _strobe(times: FloatArray, xyh: FloatArray, at: npt.NDArray[Any]) -> FloatArray:
    """Poses at times ``at`` (nearest sample within half a sampling interval; NaN otherwise), headings unwrapped."""
    if len(times) < 2:
        raise BagFitError('a run needs at least two pose samples')
    step = float(np.median(np.diff(times)))
    idx = np.clip(np.searchsorted(times, at), 1, len(times) - 1)
    idx = np.where(np.abs(times[idx - 1] - at) <= np.abs(times[idx] - at), idx - 1, idx)
    out = xyh[idx].copy()
    out[np.abs(times[idx] - at) > 0.5 * step + 1e-9] = np.nan
    out[..., 2] = _unwrap(out[..., 2])
    return out


def _unwrap(h: FloatArray) -> FloatArray:
    out = h.copy()
    for k in range(h.shape[1]):
        ok = np.isfinite(h[:, k])
        out[ok, k] = np.unwrap(h[ok, k])
    return out


def load_run(path: str | Path, period: float = GAIT_PERIOD, alpha_max_deg: float | None = None,
             duration: float | None = None) -> BagRun:
    """Read a bag into a BagRun; BagFitError (one line) if it is missing or holds no poses."""
    from smarticle_bags import arrays
    from smarticle_bags.errors import BagError
    from smarticle_bags.reader import BagReader
    from smarticle_common import topics as contract
    from smarticle_tracking.clocks import ClockError, estimate_clock

    notes: list[str] = []
    try:
        reader = BagReader(path)
        poses_topic = contract.topic('poses')
        if poses_topic not in reader.topics:
            raise BagFitError(f'{path}: holds no {poses_topic}: nothing to compare')
        poses = arrays.read_poses(reader)
        start_topic = contract.topic('start')
        starts = ([m.stamp.sec + 1e-9 * m.stamp.nanosec for _, m in reader.decoded([start_topic])]
                  if start_topic in reader.topics else [])
        commands = arrays.read_robot_topic(reader, 'joint_commands')
        states = arrays.read_robot_topic(reader, 'joint_states')
        fsr = arrays.read_fsr(reader)
    except BagError as err:
        raise BagFitError(str(err)) from None
    times, xyh = poses.stamp, poses.xyh
    if len(times) < 2 or xyh.shape[1] == 0:
        raise BagFitError(f'{path}: {poses_topic} holds fewer than two poses')
    start = starts[-1] if starts else float(times[0])
    if not starts:
        notes.append('no /smarticles/start: the gaits start at the first pose')
    seen = np.all(np.isfinite(xyh[:, :, :2]), axis=(1, 2)) & (times >= start - 1e-6)
    if not np.any(seen):
        raise BagFitError(f'{path}: no pose after the gait start sees every robot')
    first = xyh[int(np.argmax(seen))]
    end = float(times[-1]) if duration is None else min(float(times[-1]), start + duration)
    n_periods = int(math.floor((end - start) / period + 1e-9))
    if n_periods < SEGMENT_PERIODS + 1:
        raise BagFitError(f'{path}: {end - start:.3g} s after the gait start is shorter than '
                               f'{SEGMENT_PERIODS + 1} gait periods of {period:g} s')
    strobe = _strobe(times, xyh, start + period * np.arange(n_periods + 1))
    n = xyh.shape[1]
    # gait amplitude: the commands' (or states') largest arm angle, else the option
    amplitude = alpha_max_deg
    joints = commands or states
    if amplitude is None and joints:
        values = [np.nanmax(np.abs(s.position[:, [s.names.index('arm1'), s.names.index('arm2')]]))
                  for s in joints.values() if {'arm1', 'arm2'} <= set(s.names) and len(s.stamp)]
        if values:
            amplitude = round(math.degrees(float(np.nanmax(values))))
    if amplitude is None:
        amplitude = 90.0
        notes.append('no joint topics: alpha_max 90 deg')
    phases, rates = [0.0] * n, [1.0] * n
    for k in range(n):
        source = commands if k in commands else states if k in states else None
        if source is None:
            notes.append(f'robot {k}: no joint topics: clock rate 1, phase 0')
            continue
        s = source[k]
        try:
            arms = [s.names.index('arm1'), s.names.index('arm2')]
            est = estimate_clock(s.stamp, s.position[:, arms], kind='commands' if source is commands else 'states',
                                 period=period, start=start, velocity=s.velocity[:, arms], robot=k)
        except (ClockError, ValueError) as err:
            notes.append(f'robot {k}: clock not estimated ({err}): rate 1, phase 0')
            continue
        rates[k], phases[k] = float(est.rate), float(est.phase) % 1.0
    fsr_peaks = None
    if fsr and all(k in fsr for k in range(n)):
        fsr_peaks = np.full((n_periods, n), np.nan)
        for k in range(n):
            s = fsr[k]
            force = np.nanmax(np.nan_to_num(s.effort, nan=0.0), axis=1) if s.effort.size else np.zeros(0)
            for j in range(n_periods):
                inside = (s.stamp >= start + j * period) & (s.stamp < start + (j + 1) * period)
                if np.any(inside):
                    fsr_peaks[j, k] = float(np.max(force[inside]))
    if not np.any(np.all(np.isfinite(strobe[:n_periods - SEGMENT_PERIODS:SEGMENT_PERIODS, :, :2]), axis=(1, 2))):
        raise BagFitError(f'{path}: no segment start (every {SEGMENT_PERIODS} periods) sees every robot')
    return BagRun(Path(path).name, start, period, math.radians(amplitude), first, strobe, tuple(phases),
                  tuple(rates), fsr_peaks, tuple(notes))


def segment_starts(run: BagRun) -> list[int]:
    """The periods at which the run's segments start: every ``SEGMENT_PERIODS`` periods, each segment one burn-in
    period and ``SEGMENT_PERIODS`` compared periods long, where the bag sees every robot at the start."""
    out = []
    for s in range(0, run.periods - SEGMENT_PERIODS, SEGMENT_PERIODS):
        if np.all(np.isfinite(run.strobe[s, :, :3])):
            out.append(s)
    return out


def scene_of(run: BagRun, config: SimConfig, at: int = 0) -> Any:
    """The scene of the run's segment starting at period ``at``: each robot at its tracked pose then (centred on
    the plate), with the bag's gait amplitude and period and the phase its clock has reached; footprints may
    overlap by 2 mm (the tracker's error)."""
    from smarticle_sim.scenes import RobotPlacement, Scene, start_angles

    poses = run.strobe[at]
    centre = np.nanmean(poses[:, :2], axis=0)
    robots = []
    for k in range(run.robots):
        phase = (run.phases[k] + (run.rates[k] - 1.0) * at) % 1.0
        gait = GaitConfig(run.alpha_max, run.period, config.robot.servo_speed, phase)
        a1, a2 = start_angles(gait)
        x, y, h = (float(v) for v in poses[k])
        robots.append(RobotPlacement(x - float(centre[0]), y - float(centre[1]), h, a1, a2, gait))
    return Scene(tuple(robots), name=f'bag:{run.name}@{at}', seed=0, overlap_tolerance=0.002)


def _segment_observables(a: FloatArray, b: FloatArray, fsr: FloatArray | None,
                         body_length: float) -> dict[str, FloatArray]:
    """Observables (segments, components) from poses ``a`` and ``b`` (segments, n, 3) ``SEGMENT_PERIODS`` apart
    and each segment's mean per-period peak FSR force (segments, n) or None."""
    seg = SEGMENT_PERIODS
    out = {'speed': np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]) / body_length / seg,
           'turn': (b[..., 2] - a[..., 2]) / seg}
    n = a.shape[1]
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    if pairs and n <= 3:
        out['r'] = np.stack([np.hypot(*(b[:, j, :2] - b[:, i, :2]).T) for i, j in pairs], axis=1) / body_length
        out['phi'] = np.stack([b[:, j, 2] - b[:, i, 2] for i, j in pairs], axis=1)
    if fsr is not None:
        out['fsr'] = fsr
    return out


def bag_observables(run: BagRun, body_length: float) -> dict[str, FloatArray]:
    """The bag's observables over each segment's compared periods (``segment_starts``)."""
    starts = np.array(segment_starts(run), dtype=int)
    seg = SEGMENT_PERIODS
    fsr = None
    if run.fsr_peaks is not None:
        fsr = np.stack([run.fsr_peaks[s + 1:s + 1 + seg].mean(axis=0) for s in starts]) if len(starts) else None
    return _segment_observables(run.strobe[starts + 1], run.strobe[starts + 1 + seg], fsr, body_length)


def measured_clocks(run: BagRun) -> Callable[[Any, Any], list[Any]]:
    """``run_trial``'s ``controllers`` hook that runs each robot's gait clock at its measured rate."""
    rates = tuple(float(r) for r in run.rates)

    def clocks(_physics: Any, gaits: Any) -> list[Any]:
        gaits.clock_rates = rates
        return []

    return clocks


def simulate(run: BagRun, config: SimConfig, engine: str = 'bullet') -> dict[str, FloatArray]:
    """The sim's observables of the run: each segment simulated from the bag's poses at its start (one
    burn-in period, then the ``SEGMENT_PERIODS`` compared), with each robot's measured clock rate. Restarting
    from the bag every segment keeps a chaotic run's divergence to one segment, so the distance is smooth."""
    from smarticle_sim.batch import run_trial
    from smarticle_sim.engines import engine_factory

    seg = SEGMENT_PERIODS
    want_fsr = run.fsr_peaks is not None
    clocks = measured_clocks(run)
    firsts, lasts, peaks = [], [], []
    for s in segment_starts(run):
        # FSR: every control tick, so each period's peak is the peak over all its ticks (the bag's sampled peaks)
        rec = run_trial(config, scene_of(run, config, s), float(seg + 1), sample_every=1 if want_fsr else None,
                        record_fsr=want_fsr, controllers=clocks, engine=engine_factory(engine))
        times = np.asarray(rec.time)
        strobe = _strobe(times, np.asarray(rec.poses), run.period * np.arange(seg + 2))
        firsts.append(strobe[1])
        lasts.append(strobe[1 + seg])
        if want_fsr:
            force = np.asarray(rec.fsr).max(axis=2)
            per = [force[(times >= j * run.period) & (times < (j + 1) * run.period)].max(axis=0)
                   for j in range(1, seg + 1)]
            peaks.append(np.mean(per, axis=0))
    n = run.robots
    a = np.array(firsts).reshape(-1, n, 3)
    b = np.array(lasts).reshape(-1, n, 3)
    return _segment_observables(a, b, np.array(peaks).reshape(-1, n) if want_fsr else None, config.robot.body_length)


def first_seen(run: BagRun) -> int:
    """The first period whose strobe sees every robot (where a whole-run sim starts)."""
    seen = np.all(np.isfinite(run.strobe[:run.periods, :, :3]), axis=(1, 2))
    if not np.any(seen):
        raise BagFitError(f'{run.name}: no period start sees every robot')
    return int(np.argmax(seen))


def simulate_whole(run: BagRun, config: SimConfig, engine: str = 'bullet') -> FloatArray:
    """The sim's strobe of the whole run: one run from the bag's poses at ``first_seen`` to the run's end, each
    robot at its measured clock rate; (periods + 1, n, 3) poses at start + q T like ``BagRun.strobe`` (NaN
    before the sim's start and after a trouble stop)."""
    from smarticle_sim.batch import run_trial
    from smarticle_sim.engines import engine_factory

    at = first_seen(run)
    rec = run_trial(config, scene_of(run, config, at), float(run.periods - at), controllers=measured_clocks(run),
                    engine=engine_factory(engine))
    out = np.full_like(run.strobe, np.nan)
    out[at:] = _strobe(np.asarray(rec.time), np.asarray(rec.poses), run.period * np.arange(run.periods - at + 1))
    return out


def bound_table(strobe: FloatArray, r_bind: float) -> npt.NDArray[np.bool_]:
    """(periods, pairs) whether each pair is bound in each period: its centre distance at the period's strobe
    (``strobe`` (periods, n, 3), m) under ``r_bind`` (m), by the one bound rule
    (``smarticle_tracking.gliders.frame_hits``; an unseen robot binds nothing)."""
    from smarticle_common.pairs import pair_coordinates
    from smarticle_tracking.gliders import frame_hits

    return frame_hits(pair_coordinates(strobe).r, r_bind)


def binding_stats(tables: Sequence[npt.NDArray[np.bool_]]) -> dict[str, float]:
    """``bound share`` (bound pair-periods over all pair-periods) and ``lifetime`` (mean length in periods of
    the maximal runs of bound periods, censored runs counted as seen; NaN if none) of bound tables (periods,
    pairs), pooled over runs."""
    from smarticle_tracking.gliders import bound_runs

    cells = sum(int(t.size) for t in tables)
    bound = sum(int(np.count_nonzero(t)) for t in tables)
    lengths = np.concatenate([np.asarray(r.stop - r.start, dtype=float)
                              for r in (bound_runs(t) for t in tables)]) if tables else np.zeros(0)
    return {'bound share': bound / cells if cells else math.nan,
            'lifetime': float(np.mean(lengths)) if lengths.size else math.nan}


def binding_runs(runs: Sequence[BagRun]) -> list[BagRun]:
    """The runs whose binding is compared: those of two or more robots."""
    return [run for run in runs if run.robots >= 2]


def bag_binding(runs: Sequence[BagRun], r_bind: float) -> dict[str, float]:
    """The bag's ``binding_stats`` over the runs of two or more robots, from ``first_seen`` to the last period."""
    return binding_stats([bound_table(run.strobe[first_seen(run):run.periods], r_bind)
                          for run in binding_runs(runs)])


def residuals(sim: Mapping[str, FloatArray], bag: Mapping[str, FloatArray], flat: bool = True) -> dict[str, FloatArray]:
    """sim - bag per observable, over the segments both have (phi wrapped to [-pi, pi)); ``flat``: the finite
    values in one array, else (segments, components) with NaN where either side is unseen."""
    out = {}
    for name in bag:
        if name not in sim:
            continue
        m = min(len(sim[name]), len(bag[name]))
        d = sim[name][:m] - bag[name][:m]
        if name == 'phi':
            d = (d + math.pi) % (2 * math.pi) - math.pi
        out[name] = d[np.isfinite(d)] if flat else d
    return out


def soft_l1(z: FloatArray) -> FloatArray:
    """2 (sqrt(1 + z^2) - 1): z^2 for small z, 2 |z| for large (scipy's least_squares soft_l1 loss)."""
    return 2.0 * (np.sqrt(1.0 + z ** 2) - 1.0)


def distance(res: Mapping[str, FloatArray]) -> float:
    """The stated distance: the sum over observables and terms of soft_l1(residual / SCALES[observable])."""
    return float(sum(np.sum(soft_l1(r / SCALES[name])) for name, r in res.items()))


def gaps(res: Mapping[str, FloatArray]) -> dict[str, float]:
    """Root mean square residual per observable."""
    return {name: float(np.sqrt(np.mean(r ** 2))) if r.size else math.nan for name, r in res.items()}


@dataclass
class Problem:
    """The runs, the base config (preset name or file) and the parameters to fit; evaluates the distance."""

    runs: Sequence[BagRun]
    preset: str
    params: Sequence[Parameter]
    engine: str = 'bullet'
    mapper: Callable[[Callable[[Any], Any], Sequence[Any]], list[Any]] | None = None
    cache: dict[tuple[float, ...], dict[str, FloatArray]] = field(default_factory=dict)
    #: Per parameter values evaluated: each segment's share of the distance (all runs' segments in order).
    segment_terms: dict[tuple[float, ...], FloatArray] = field(default_factory=dict)

    def config(self, values: Sequence[float]) -> SimConfig:
        groups: dict[str, dict[str, float]] = {'physics': {}, 'robot': {}}
        for p, v in zip(self.params, values, strict=True):
            groups[p.group][p.name] = float(v)
        return build_config(self.preset, groups['physics'], groups['robot'], engine=self.engine)

    def residuals(self, values: Sequence[float]) -> dict[str, FloatArray]:
        key = tuple(round(float(v), 12) for v in values)
        if key not in self.cache:
            config = self.config(values)
            jobs = [(run, config, self.engine) for run in self.runs]
            outs = (self.mapper or _map)(_simulate_job, jobs)
            merged: dict[str, list[FloatArray]] = {}
            per_segment = []
            for run, sim in zip(self.runs, outs, strict=True):
                bag = bag_observables(run, config.robot.body_length)
                res = residuals(sim, bag)
                for name, r in res.items():
                    merged.setdefault(name, []).append(r.ravel())
                terms = np.zeros(len(bag['speed']))
                for name, d in residuals(sim, bag, flat=False).items():
                    terms[:len(d)] += np.nansum(soft_l1(d / SCALES[name]).reshape(len(d), -1), axis=1)
                per_segment.append(terms)
            self.cache[key] = {name: np.concatenate(rs) for name, rs in merged.items()}
            self.segment_terms[key] = np.concatenate(per_segment)
        return self.cache[key]

    def distance(self, values: Sequence[float]) -> float:
        return distance(self.residuals(values))

    def bind_radius(self) -> float:
        """The bind radius (m): ``R_BIND_BL`` body lengths of the preset's robot, the same for bag and sim."""
        return R_BIND_BL * build_config(self.preset).robot.body_length

    def binding(self, values: Sequence[float]) -> dict[str, float]:
        """The sim's whole-run ``binding_stats`` at the parameter values (one run per bag of two or more
        robots, on the mapper); not part of the distance."""
        runs = binding_runs(self.runs)
        config = self.config(values)
        strobes = (self.mapper or _map)(_whole_job, [(run, config, self.engine) for run in runs])
        r_bind = self.bind_radius()
        return binding_stats([bound_table(strobe[first_seen(run):run.periods], r_bind)
                              for run, strobe in zip(runs, strobes, strict=True)])

    def defaults(self) -> list[float]:
        config = build_config(self.preset)
        return [float(getattr(config.physics if p.group == 'physics' else config.robot, p.name) or p.lo)
                for p in self.params]


def _map(fn: Callable[[Any], Any], items: Sequence[Any]) -> list[Any]:
    return [fn(item) for item in items]


def _simulate_job(job: tuple[BagRun, SimConfig, str]) -> dict[str, FloatArray]:
    run, config, engine = job
    return simulate(run, config, engine)


def _whole_job(job: tuple[BagRun, SimConfig, str]) -> FloatArray:
    run, config, engine = job
    return simulate_whole(run, config, engine)


@dataclass(frozen=True)
class FitResult:
    """Fitted values, their 95 % bootstrap intervals, the distance at the defaults and at the fit, and the gaps."""

    names: tuple[str, ...]
    values: tuple[float, ...]
    intervals: tuple[tuple[float, float], ...]
    distance_default: float
    distance_fit: float
    terms: int
    gaps_default: dict[str, float]
    gaps_fit: dict[str, float]
    evaluations: int


#: Resamples of the segments for each fitted value's interval, and their seed.
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0
#: Grid points per parameter of the first, coarse search (by the number of parameters fitted; none beyond).
GRID_POINTS: dict[int, int] = {1: 21, 2: 7}


def fit(problem: Problem, max_evaluations: int = 40) -> FitResult:
    """Minimise the distance: a coarse grid over the bounds (``scipy.optimize.brute``, ``GRID_POINTS``; the
    distance of a chaotic run is rough, so a local search alone stalls in the nearest dip), then scipy's
    Powell (bounded, parameters scaled to [0, 1], at most ``max_evaluations``) from the best of the grid and
    the defaults. Each fitted value's 95 % interval is a bootstrap over the runs' segments
    (``BOOTSTRAP_RESAMPLES``, seeded): each resample of the segments picks the evaluated parameter values
    with the least distance over it, and the interval is the 2.5 and 97.5 percentiles of those picks (widened
    to hold the fit). No further sim runs: every evaluated value keeps its distance per segment."""
    lo = np.array([p.lo for p in problem.params])
    hi = np.array([p.hi for p in problem.params])
    k = len(lo)
    x0 = np.clip((np.array(problem.defaults()) - lo) / (hi - lo), 0.0, 1.0)

    def value(u: FloatArray) -> list[float]:
        return [float(v) for v in lo + np.clip(u, 0.0, 1.0) * (hi - lo)]

    def objective(u: FloatArray) -> float:
        return problem.distance(value(np.atleast_1d(u)))

    d0 = objective(x0)
    start, d_start = x0, d0
    if k in GRID_POINTS:
        grid = np.atleast_1d(optimize.brute(objective, [(0.0, 1.0)] * k, Ns=GRID_POINTS[k], finish=None))
        if objective(grid) < d_start:
            start, d_start = grid, objective(grid)
    step = 0.5 / GRID_POINTS.get(k, 4)
    res = optimize.minimize(objective, start, method='Powell', bounds=[(0.0, 1.0)] * k,
                            options={'xtol': 1e-3, 'ftol': 1e-6, 'maxfev': max_evaluations,
                                     'direc': np.eye(k) * step})
    best, d_min = np.clip(np.atleast_1d(res.x), 0.0, 1.0), objective(np.atleast_1d(res.x))
    if d_start < d_min:
        best, d_min = start, d_start
    terms = int(sum(r.size for r in problem.residuals(value(best)).values()))
    # the interval: a bootstrap over the runs' segments, each resample's fit the best of the evaluated values
    keys = list(problem.segment_terms)
    table = np.stack([problem.segment_terms[key] for key in keys])      # (values evaluated, segments)
    points = np.array(keys)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    segments = table.shape[1]
    picks = np.array([int(np.argmin(table[:, rng.integers(0, segments, segments)].sum(axis=1)))
                      for _ in range(BOOTSTRAP_RESAMPLES)])
    fitted = value(best)
    intervals = []
    for i in range(k):
        lo_i, hi_i = np.percentile(points[picks, i], [2.5, 97.5])
        intervals.append((float(min(lo_i, fitted[i])), float(max(hi_i, fitted[i]))))
    return FitResult(tuple(p.name for p in problem.params), tuple(value(best)),
                     tuple((a, b) for a, b in intervals), d0, d_min, terms,
                     gaps(problem.residuals(value(x0))), gaps(problem.residuals(value(best))), len(problem.cache))


def write_preset(path: str | Path, preset: str, params: Sequence[Parameter], result: FitResult,
                 bags: Sequence[str]) -> Path:
    """Write the calibrated preset file: the base preset, the fitted overrides and the provenance."""
    import yaml

    base, physics, robot = (read_preset_file(preset) if is_preset_file(preset) else (preset, {}, {}))
    for p, v in zip(params, result.values, strict=True):
        (physics if p.group == 'physics' else robot)[p.name] = float(v)
    data: dict[str, Any] = {
        'preset': base,
        'physics': physics,
        'robot': robot,
        'calibration': {
            'bags': list(bags),
            'distance': 'sum over observables and terms of soft_l1((sim - bag) / scale), '
                        'soft_l1(z) = 2 (sqrt(1 + z^2) - 1); scales: '
                        + ', '.join(f'{k} {v:g} {UNITS[k]}' for k, v in SCALES.items()),
            'distance_default': float(result.distance_default),
            'distance_fit': float(result.distance_fit),
            'terms': result.terms,
            'fitted': {name: {'value': float(v), 'interval_95': [float(e) for e in iv]}
                       for name, v, iv in zip(result.names, result.values, result.intervals, strict=True)},
        },
    }
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(yaml.safe_dump(data, sort_keys=False), encoding='utf-8')
    try:
        build_config(str(out))
    except ConfigError as err:
        raise BagFitError(f'the written preset file does not load: {err}') from None
    return out


def format_gaps(title: str, before: Mapping[str, float], after: Mapping[str, float] | None = None) -> str:
    """A table of the gap per observable (default and, if given, fitted)."""
    lines = [title, f'{"observable":<10} {"unit":<11} {"default":>10}' + (f' {"fitted":>10}' if after else '')]
    for name, v in before.items():
        row = f'{name:<10} {UNITS[name]:<11} {v:>10.4g}'
        if after is not None:
            row += f' {after.get(name, math.nan):>10.4g}'
        lines.append(row)
    return '\n'.join(lines)


def compare_binding(problem: Problem, fitted: Sequence[float] | None = None) -> dict[str, dict[str, float]]:
    """The whole-run binding observables by column: ``bag``, ``default`` (the sim at the preset's values, as in
    the gap table) and, given fitted values, ``fitted``; empty if no run has two or more robots."""
    if not binding_runs(problem.runs):
        return {}
    out = {'bag': bag_binding(problem.runs, problem.bind_radius()), 'default': problem.binding(problem.defaults())}
    if fitted is not None:
        out['fitted'] = problem.binding(fitted)
    return out


def format_binding(title: str, columns: Mapping[str, Mapping[str, float]]) -> str:
    """A table of the binding observables, one column per source (bag, default, fitted)."""
    lines = [title, f'{"observable":<12} {"unit":<9}' + ''.join(f' {c:>10}' for c in columns)]
    for name, unit in BINDING_UNITS.items():
        lines.append(f'{name:<12} {unit:<9}' + ''.join(f' {col.get(name, math.nan):>10.4g}'
                                                       for col in columns.values()))
    return '\n'.join(lines)


#: Bar colours of the report's columns: the gap panel's default and fitted, the bag in grey.
_COLUMN_COLOURS = {'bag': 'C7', 'default': 'C0', 'fitted': 'C1'}


def draw_gaps(path: str | Path, before: Mapping[str, float], after: Mapping[str, float] | None = None,
              binding: Mapping[str, Mapping[str, float]] | None = None) -> Path:
    """A bar chart of each observable's gap normalised by its scale (default, fitted) and, given ``binding``
    (``compare_binding``), one panel per binding observable with a bar per column (bag, default, fitted)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    names = list(before)
    x = np.arange(len(names))
    panels = 1 + (len(BINDING_UNITS) if binding else 0)
    fig, axes = plt.subplots(1, panels, figsize=(6 + 2.6 * (panels - 1), 3.2), squeeze=False,
                             gridspec_kw={'width_ratios': [max(len(names), 2)] + [1.5] * (panels - 1)})
    ax = axes[0, 0]
    ax.bar(x - 0.2, [before[n] / SCALES[n] for n in names], 0.4, label='default')
    if after is not None:
        ax.bar(x + 0.2, [after.get(n, math.nan) / SCALES[n] for n in names], 0.4, label='fitted')
    ax.set_xticks(x, [f'{n}\n({UNITS[n]})' for n in names])
    ax.set_ylabel('gap / scale (RMS)')
    ax.legend()
    if binding:
        columns = list(binding)
        for ax, (name, unit) in zip(axes[0, 1:], BINDING_UNITS.items(), strict=True):
            ax.bar(np.arange(len(columns)), [binding[c].get(name, math.nan) for c in columns], 0.6,
                   color=[_COLUMN_COLOURS.get(c, 'C2') for c in columns])
            ax.set_xticks(np.arange(len(columns)), columns)
            ax.set_title(f'{name} ({unit}), whole run', fontsize=9)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def write_pose_bag(time: FloatArray, poses: FloatArray, output: str | Path, source: str) -> Path:
    """A bag of ``/smarticles/poses`` from sampled poses (``time`` (T,) s, ``poses`` (T, n, 3)): a batch-core
    run written as the tracker would have seen it (no start topic: the gaits start at the first pose)."""
    from smarticle_bags.csv_import import SENSOR_QOS, encode_pose_array
    from smarticle_bags.writer import BagWriter
    from smarticle_common import topics as contract

    topic = contract.topic('poses')
    with BagWriter(output, custom_data={'recorded_from': source}) as writer:
        writer.add_topic(topic, contract.spec_of('poses').type, [SENSOR_QOS])
        for t, xyh in zip(time, poses, strict=True):
            ns = int(round(float(t) * 1e9))
            writer.write(topic, encode_pose_array(ns, np.asarray(xyh, dtype=float)), ns)
        writer.close()
    return Path(output)
