"""Each robot's gait clock from its recorded arms: rate and phase, with intervals. Pure: NumPy and SciPy.

A gait started at ``t0`` with phase ``p`` on a board whose clock runs ``rate`` times as fast crosses its
quarter boundaries (``smarticle_common.gait``: quarter q moves arm 1 in quarters 0 and 2, arm 2 in 1 and 3,
toward -alpha_max in quarters 0 and 1, toward +alpha_max in 2 and 3) at

    t_Q = t0 + (Q / 4 - p) * T / rate        (Q = 0, 1, 2, ...; Q mod 4 = the quarter)

so the boundary times are a straight line in the boundary index Q, of slope T / (4 rate). ``quarter_events``
finds the boundaries in a robot's joint commands (the first message whose target of the moving arm is the
next corner) or its joint states (the arm passing the middle of its stroke, less the half stroke's
duration at the measured speed); ``fit_clock`` numbers them (each event's quarter is known from which arm
moves which way; the index between two events from the time between them) and fits time against index
by least squares after dropping events far off the line (a halt's shortened stroke, say). The rate is
``T / (4 slope)``, its 95 % interval from the slope's standard error (``scipy.stats.linregress``) with a
Student t quantile; the phase at a reference time (the bag's start) is the gait time the line gives there,
modulo one period, with the interval of the line's value at the nearest event. A command's time is known
to one message period only (it is the first message at or after the boundary), so the residual spread is
floored at that period's rounding error (period / sqrt(12)), the rate's interval also holds every rate
whose line passes each boundary within its tick (``tick_slopes``) and, when the boundaries fall between the
messages (a clock running off the message ticks), the times are taken half a message period earlier and the
phase's interval widened by that half period (the delay of each message is known only to lie in one period).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np
import numpy.typing as npt
from scipy import optimize, stats

from smarticle_common.facts import GAIT_PERIOD

from .errors import ClockError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Event quarter of (arm index, direction of its new corner): arm 1 to -a starts quarter 0, arm 2 to -a
#: quarter 1, arm 1 to +a quarter 2, arm 2 to +a quarter 3.
QUARTER_OF: dict[tuple[int, int], int] = {(0, -1): 0, (1, -1): 1, (0, 1): 2, (1, 1): 3}
#: Events further off the fitted line than this many robust standard deviations are dropped.
REJECT_SIGMAS = 5.0
#: Fewest events a fit needs.
MIN_EVENTS = 6

Source = Literal['commands', 'states']


@dataclass(frozen=True)
class ClockEstimate:
    """One robot's gait clock: rate against the nominal period and phase at ``start``, with 95 % intervals."""

    robot: int | None
    source: str                          # 'commands' or 'states'
    events: int                          # quarter boundaries used by the fit
    dropped: int                         # boundaries found but off the line (halts, glitches)
    rate: float                          # nominal period / fitted period (1 + the clock's relative error)
    rate_interval: tuple[float, float]   # 95 %
    period: float                        # fitted gait period on the recording's clock (s)
    phase: float                         # gait time at ``start`` modulo 1 (fraction of a period)
    phase_halfwidth: float               # 95 % half width of ``phase`` (periods)
    start: float                         # the reference time of ``phase`` (s)
    first_event: float                   # time of the first boundary used (s)
    residual_sd: float                   # spread of the boundary times about the line (s)

    @property
    def rate_offset(self) -> float:
        """The relative clock error ``rate - 1`` (a gait node's ``clock_rate_offset``)."""
        return self.rate - 1.0


def _amplitude(values: FloatArray) -> float:
    """The gait's amplitude from arm angles or targets: the 90th percentile of their magnitudes."""
    finite = np.abs(values[np.isfinite(values)])
    if finite.size == 0:
        raise ClockError('no arm angle recorded')
    amplitude = float(np.percentile(finite, 90.0))
    if amplitude < math.radians(2.0):
        raise ClockError(f'the arms do not move (largest angles {math.degrees(amplitude):.2f} deg)')
    return amplitude


def command_events(stamp: FloatArray, targets: FloatArray) -> tuple[FloatArray, IntArray]:
    """Quarter boundaries in joint commands: (times, quarters 0..3) where a target switches to a corner."""
    stamp, targets = np.asarray(stamp, dtype=float), np.asarray(targets, dtype=float)
    amplitude = _amplitude(targets)
    tol = max(0.02, 0.02 * amplitude)
    times: list[float] = []
    quarters: list[int] = []
    for arm in range(2):
        column = targets[:, arm]
        for sign in (-1, 1):
            at_corner = np.abs(column - sign * amplitude) <= tol
            arrive = np.flatnonzero(at_corner[1:] & ~at_corner[:-1] & np.isfinite(column[:-1])) + 1
            times += stamp[arrive].tolist()
            quarters += [QUARTER_OF[(arm, sign)]] * arrive.size
    order = np.argsort(times, kind='stable')
    return np.asarray(times)[order], np.asarray(quarters, dtype=np.int64)[order]


def state_events(stamp: FloatArray, angles: FloatArray,
                 velocity: FloatArray | None = None) -> tuple[FloatArray, IntArray]:
    """Quarter boundaries in joint states: each stroke's zero crossing less the half stroke at its speed."""
    stamp, angles = np.asarray(stamp, dtype=float), np.asarray(angles, dtype=float)
    amplitude = _amplitude(angles)
    times: list[float] = []
    quarters: list[int] = []
    speeds: list[float] = []
    measured: list[bool] = []
    for arm in range(2):
        p = angles[:, arm]
        v = None if velocity is None else np.asarray(velocity, dtype=float)[:, arm]
        side = np.where(p > amplitude / 2.0, 1, np.where(p < -amplitude / 2.0, -1, 0))
        sided = np.flatnonzero(side != 0)
        for before, after in zip(sided[:-1], sided[1:], strict=True):
            if side[before] == side[after]:
                continue
            segment = p[before:after + 1]
            crossings = np.flatnonzero(np.sign(segment[:-1]) != np.sign(segment[1:]))
            if crossings.size == 0:
                continue
            i = before + int(crossings[-1])
            p0, p1, t0, t1 = p[i], p[i + 1], stamp[i], stamp[i + 1]
            if p1 == p0 or t1 <= t0:
                continue
            times.append(t0 + (0.0 - p0) * (t1 - t0) / (p1 - p0))
            quarters.append(QUARTER_OF[(arm, int(side[after]))])
            has_velocity = v is not None and bool(np.isfinite(v[i]) and np.isfinite(v[i + 1]))
            speeds.append(max(abs(v[i]), abs(v[i + 1])) if v is not None and has_velocity else
                          abs(p1 - p0) / (t1 - t0))
            measured.append(has_velocity)
    # without recorded velocities, the speed through the middle of a stroke is the median over all strokes
    speed = np.where(measured, speeds, np.median(speeds) if speeds else 1.0)
    times = (np.asarray(times) - amplitude / np.maximum(speed, 1e-9)).tolist()
    order = np.argsort(times, kind='stable')
    return np.asarray(times)[order], np.asarray(quarters, dtype=np.int64)[order]


def number_events(times: FloatArray, quarters: IntArray, quarter_time: float) -> IntArray:
    """Boundary index Q of each event (times sorted): Q mod 4 = its quarter, Q - Q_prev from the time between."""
    index = np.empty(len(times), dtype=np.int64)
    if len(times) == 0:
        return index
    index[0] = quarters[0]
    step = quarter_time
    for i in range(1, len(times)):
        predicted = index[i - 1] + (times[i] - times[i - 1]) / step
        index[i] = quarters[i] + 4 * round((predicted - quarters[i]) / 4.0)
        if i >= 4 and index[i] > index[0]:
            step = (times[i] - times[0]) / float(index[i] - index[0])
    return index


def _between_ticks(index: FloatArray, times: FloatArray, slope: float, intercept: float, quantum: float) -> bool:
    """True when the boundaries fall between the message ticks: the times scatter about their line by more
    than a quarter of a tick's rounding error (a clock on the ticks leaves them on the line)."""
    residual = times - (intercept + slope * index)
    return bool(np.std(residual) > 0.25 * quantum / math.sqrt(12.0))


def tick_slopes(index: FloatArray, times: FloatArray, quantum: float) -> tuple[float, float] | None:
    """The range of quarter durations whose line passes every boundary within its message tick, or None.

    Each message marks the first tick at or after its boundary, so the boundary lies in (time - tick,
    time]; the lines ``b + s Q`` meeting every such window form a convex set, and its extreme slopes
    come from two linear programs (``scipy.optimize.linprog``). Jitter beyond the tick widens the windows
    step by step until some line fits; if none does, None.
    """
    design = np.column_stack([np.ones_like(index), index])
    a_ub = np.vstack([design, -design])
    for jitter in (0.0, 0.1, 0.25, 0.5, 1.0):
        b_ub = np.concatenate([times + jitter * quantum, -(times - (1.0 + jitter) * quantum)])
        low = optimize.linprog([0.0, 1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None), (None, None)])
        high = optimize.linprog([0.0, -1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None), (None, None)])
        if low.status == 0 and high.status == 0:
            return float(low.x[1]), float(high.x[1])
    return None


def fit_clock(times: Sequence[float] | FloatArray, quarters: Sequence[int] | IntArray,
              period: float = GAIT_PERIOD, start: float | None = None, quantum: float = 0.0,
              robot: int | None = None, source: str = 'commands', confidence: float = 0.95) -> ClockEstimate:
    """Fit boundary times against their index: rate, period and phase at ``start`` with intervals."""
    if not (math.isfinite(period) and period > 0.0):
        raise ClockError(f'the nominal period must be a positive number of seconds, got {period!r}')
    t = np.asarray(times, dtype=float)
    q = np.asarray(quarters, dtype=np.int64)
    if t.shape != q.shape or t.ndim != 1:
        raise ClockError(f'times and quarters must be two arrays of one length, got {t.shape} and {q.shape}')
    if t.size < MIN_EVENTS:
        raise ClockError(f'{t.size} quarter boundaries found, at least {MIN_EVENTS} are needed '
                         f'({MIN_EVENTS / 4:g} gait periods)')
    order = np.argsort(t, kind='stable')
    t, q = t[order], q[order]
    index = number_events(t, q, period / 4.0)
    keep = np.ones(t.size, dtype=bool)
    for _ in range(10):
        if keep.sum() < MIN_EVENTS or np.unique(index[keep]).size < 2:
            raise ClockError(f'only {int(keep.sum())} quarter boundaries lie on one gait clock; at least '
                             f'{MIN_EVENTS} are needed')
        slope, intercept = np.polyfit(index[keep], t[keep], 1)
        residual = t - (intercept + slope * index)
        spread = 1.4826 * float(np.median(np.abs(residual[keep] - np.median(residual[keep]))))
        limit = max(REJECT_SIGMAS * spread, 0.75 * quantum, 1e-6)
        new = np.abs(residual - np.median(residual[keep])) <= limit
        if np.array_equal(new, keep):
            break
        keep = new
    x, y = index[keep].astype(float), t[keep]
    fit = stats.linregress(x, y)
    between = quantum > 0.0 and _between_ticks(x, y, fit.slope, fit.intercept, quantum)
    if between:   # each message is the first tick at or after its boundary: on average half a tick late
        y = y - quantum / 2.0
        fit = stats.linregress(x, y)
    n = int(x.size)
    sxx = float(np.sum((x - x.mean()) ** 2))
    resid_sd = float(np.sqrt(np.sum((y - fit.intercept - fit.slope * x) ** 2) / max(n - 2, 1)))
    sigma = max(resid_sd, quantum / math.sqrt(12.0))
    slope_se = max(float(fit.stderr), sigma / math.sqrt(sxx))
    tq = float(stats.t.ppf(0.5 + confidence / 2.0, n - 2))
    slope = float(fit.slope)
    if slope <= 0.0:
        raise ClockError(f'the quarter boundaries do not advance steadily (fitted quarter {slope:.4g} s)')
    slopes = (slope - tq * slope_se, slope + tq * slope_se)
    if quantum > 0.0:
        bounds = tick_slopes(index[keep].astype(float), t[keep], quantum)
        if bounds is not None:
            slopes = (min(slopes[0], bounds[0]), max(slopes[1], bounds[1]))
    if slopes[0] <= 0.0:
        raise ClockError('the quarter boundaries do not fix the clock (too few, or too short a recording)')
    fitted_period = 4.0 * slope
    rate = period / fitted_period
    interval = (period / (4.0 * slopes[1]), period / (4.0 * slopes[0]))
    ref = float(t[keep][0]) if start is None else float(start)
    q_ref = (ref - float(fit.intercept)) / slope
    nearest = float(np.clip(round(q_ref), x.min(), x.max()))
    value_se = sigma * math.sqrt(1.0 / n + (nearest - x.mean()) ** 2 / sxx)
    return ClockEstimate(robot=robot, source=source, events=n, dropped=int(t.size - n), rate=rate,
                         rate_interval=interval, period=fitted_period, phase=float((q_ref / 4.0) % 1.0),
                         phase_halfwidth=(tq * value_se + (quantum / 2.0 if between else 0.0)) / fitted_period,
                         start=ref,
                         first_event=float(y[0]), residual_sd=resid_sd)


def estimate_clock(stamp: FloatArray, angles: FloatArray, kind: Source = 'commands', period: float = GAIT_PERIOD,
                   start: float | None = None, velocity: FloatArray | None = None,
                   robot: int | None = None) -> ClockEstimate:
    """A robot's gait clock from its joint commands (``angles`` = targets) or joint states, (T, 2) arrays."""
    stamp = np.asarray(stamp, dtype=float)
    angles = np.asarray(angles, dtype=float)
    if angles.ndim != 2 or angles.shape[1] != 2 or angles.shape[0] != stamp.shape[0]:
        raise ClockError(f'arm angles must be (T, 2) for arm1, arm2 at T stamps, got {angles.shape} '
                         f'for {stamp.shape[0]} stamps')
    if stamp.size < 2 or np.any(np.diff(stamp) < 0.0):
        raise ClockError('the stamps must be at least two and must not go backwards')
    if kind == 'commands':
        times, quarters = command_events(stamp, angles)
    elif kind == 'states':   # a stroke starts at the control tick that carries the new corner: the same rounding
        times, quarters = state_events(stamp, angles, velocity)
    else:
        raise ClockError(f'kind must be commands or states, got {kind!r}')
    quantum = float(np.median(np.diff(stamp)))
    return fit_clock(times, quarters, period, start, quantum, robot, kind)


def format_clocks(estimates: Sequence[ClockEstimate], period: float = GAIT_PERIOD,
                  start: float | None = None, where: str = '') -> str:
    """The table of ``smarticle-bag clocks``: per robot its rate, 95 % interval, offset and phase."""
    ref = (f'{start:.3f} s' + (f', {where}' if where else '')) if start is not None else \
        'each robot\'s first boundary'
    lines = [f'gait clocks from the quarter boundaries (nominal period {period:g} s; phase at {ref}, in periods)',
             f'{"robot":>5}  {"source":<8}  {"events":>6}  {"rate":>9}  {"95 % interval":<21}  '
             f'{"offset":>9}  {"phase":>6}  {"+-":>6}  {"resid ms":>8}']
    for e in estimates:
        robot = '-' if e.robot is None else str(e.robot)
        lo, hi = e.rate_interval
        lines.append(f'{robot:>5}  {e.source:<8}  {e.events:>6}  {e.rate:9.6f}  [{lo:.6f}, {hi:.6f}]  '
                     f'{e.rate_offset:+9.2e}  {e.phase:6.4f}  {e.phase_halfwidth:6.4f}  {1e3 * e.residual_sd:8.2f}'
                     + (f'  ({e.dropped} off the line dropped)' if e.dropped else ''))
    lines.append('rate = nominal period / fitted period (a gait node\'s clock_rate_offset is rate - 1); phase = '
                 'the gait time the fit gives at the reference, modulo one period')
    return '\n'.join(lines)
