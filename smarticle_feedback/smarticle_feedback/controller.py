"""The impact-threshold feedback policy (paper, "Feedback stabilization using tactile sensing"): pure Python.

A robot halts its arms when one of its enabled FSR faces reads a force inside that face's calibrated
impact window ``[f_min, f_max]`` (newtons) for ``debounce`` consecutive samples; the gait resumes from
the held pose at the next gait period, and the controller asks for at most one halt per gait period.

Period boundaries. Once the controller knows the gait start time ``t0`` (``start``; the node takes it
from ``/smarticles/start``), gait period ``q`` covers gait time ``tau = (t - t0) / T + phase`` in
``[q, q + 1)``, the same ``tau`` as ``smarticle_common.gait``; one halt per ``q``. Before a start is known
the controller falls back to a refractory time of one period ``T`` between halts. Samples before ``t0``
never halt (the gait is not running). The debounce count restarts at every period boundary and after a
halt, so a force that persists through the hold needs ``debounce`` fresh samples in the next period.

Bad samples. ``check_sample`` turns (names, forces) into four forces in ``FSR_FACES`` order: a sample
with the wrong number or unknown names of faces raises ``FsrSampleError`` (the node drops it and counts
it); a NaN, infinite or negative force on one face is reported as a warning and that face reads as
"no impact" for the sample (its debounce count restarts). Times are seconds of one clock (the FSR
sample stamps) and must not go backwards (``FsrSampleError``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

from smarticle_common.facts import GAIT_PERIOD
from smarticle_common.topics import FSR_FACES

from .errors import FeedbackConfigError, FsrSampleError

N_FACES = len(FSR_FACES)


@dataclass(frozen=True)
class ImpactWindow:
    """Impact window of one FSR face: forces in ``[f_min, f_max]`` newtons count as an impact."""

    f_min: float
    f_max: float
    enabled: bool = True

    def __post_init__(self) -> None:
        for name in ('f_min', 'f_max'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value < 0.0:
                raise FeedbackConfigError(f'impact window {name} must be a finite force >= 0 N, got {value!r}')
        if self.f_min > self.f_max:
            raise FeedbackConfigError(f'impact window f_min ({self.f_min:g} N) is above f_max '
                                      f'({self.f_max:g} N): swap them or recalibrate')

    def contains(self, force: float) -> bool:
        """True if ``force`` (N) lies inside the window (and the face is enabled)."""
        return self.enabled and self.f_min <= force <= self.f_max


@dataclass(frozen=True)
class FeedbackConfig:
    """Settings of the impact controller: one window per face (``FSR_FACES`` order), debounce, timing."""

    windows: tuple[ImpactWindow, ...]
    debounce: int = 1               # consecutive in-window samples of one face that make an impact
    period: float = GAIT_PERIOD     # gait period T (s): one halt per period
    phase: float = 0.0              # the robot's gait phase (fraction of a period), as in GaitConfig

    def __post_init__(self) -> None:
        if len(self.windows) != N_FACES or not all(isinstance(w, ImpactWindow) for w in self.windows):
            raise FeedbackConfigError(f'need one ImpactWindow per FSR face {FSR_FACES}, got {self.windows!r}')
        if isinstance(self.debounce, bool) or not isinstance(self.debounce, int) or self.debounce < 1:
            raise FeedbackConfigError(f'debounce must be a whole number of samples >= 1, got {self.debounce!r}')
        if not (math.isfinite(self.period) and self.period > 0.0):
            raise FeedbackConfigError(f'period must be a positive number of seconds, got {self.period!r}')
        if not (math.isfinite(self.phase) and 0.0 <= self.phase < 1.0):
            raise FeedbackConfigError(f'phase must be a fraction of a period in [0, 1), got {self.phase!r}')

    @classmethod
    def uniform(cls, f_min: float, f_max: float, faces: Sequence[str] = FSR_FACES, debounce: int = 1,
                period: float = GAIT_PERIOD, phase: float = 0.0) -> FeedbackConfig:
        """The same window on every face, enabled only on ``faces``."""
        unknown = set(faces) - set(FSR_FACES)
        if unknown:
            raise FeedbackConfigError(f'unknown FSR face(s) {sorted(unknown)}; known: {FSR_FACES}')
        return cls(tuple(ImpactWindow(f_min, f_max, face in faces) for face in FSR_FACES),
                   debounce, period, phase)

    @property
    def enabled_faces(self) -> tuple[str, ...]:
        """Names of the faces that can trigger a halt."""
        return tuple(face for face, w in zip(FSR_FACES, self.windows, strict=False) if w.enabled)


class CheckedSample(NamedTuple):
    """Forces of one sample in ``FSR_FACES`` order (NaN where a face's value was unusable) and warnings."""

    forces: tuple[float, ...]
    warnings: tuple[str, ...]


def check_sample(names: Sequence[str], forces: Sequence[float]) -> CheckedSample:
    """Order and check one FSR sample; raise FsrSampleError if it is unusable as a whole.

    ``names`` may be empty (the forces are then taken in ``FSR_FACES`` order); otherwise it must name
    each of the four faces once. Non-finite or negative forces become NaN with a warning.
    """
    values = [float(v) for v in forces]
    if len(values) != N_FACES:
        raise FsrSampleError(f'FSR sample has {len(values)} forces, expected {N_FACES} ({", ".join(FSR_FACES)})',
                             'wrong_faces')
    if names:
        if sorted(names) != sorted(FSR_FACES):
            raise FsrSampleError(f'FSR sample names {list(names)} are not the faces {list(FSR_FACES)}',
                                 'wrong_faces')
        by_name = dict(zip(names, values, strict=False))
        values = [by_name[face] for face in FSR_FACES]
    warnings = []
    for i, value in enumerate(values):
        if not math.isfinite(value):
            warnings.append(f'{FSR_FACES[i]}: non-finite force {value!r} ignored')
            values[i] = math.nan
        elif value < 0.0:
            warnings.append(f'{FSR_FACES[i]}: negative force {value:g} N ignored')
            values[i] = math.nan
    return CheckedSample(tuple(values), tuple(warnings))


class Decision(NamedTuple):
    """What the controller decided for one sample."""

    halt: bool
    face: str | None          # the face whose impact triggered the halt
    period_index: int | None  # gait period of the sample (None before a start is known)


@dataclass
class FeedbackCounters:
    """What the controller has seen (reported on /diagnostics by the node)."""

    samples: int = 0
    halts: int = 0
    in_window: list[int] = field(default_factory=lambda: [0] * N_FACES)
    suppressed: int = 0       # impacts ignored because this period already had a halt
    bad_values: int = 0       # NaN / negative face values
    before_start: int = 0     # samples before the gait start time


class ImpactController:
    """Impact detection with debouncing and at most one halt per gait period, for one robot."""

    def __init__(self, config: FeedbackConfig) -> None:
        self.config = config
        self.start_time: float | None = None
        self.counters = FeedbackCounters()
        self._runs = [0] * N_FACES
        self._last_t = -math.inf
        self._last_halt_period: int | None = None
        self._last_halt_time = -math.inf
        self._run_period: int | None = None

    def start(self, t0: float) -> None:
        """Take the gait start time ``t0`` (s); a new start forgets earlier halts."""
        if not math.isfinite(t0):
            raise FeedbackConfigError(f'start time must be finite, got {t0!r}')
        self.start_time = float(t0)
        self._last_halt_period = None
        self._last_halt_time = -math.inf
        self._reset_runs(None)

    def set_windows(self, config: FeedbackConfig) -> None:
        """Use the impact windows (and debounce) of ``config`` from the next sample on; the rest must not change.

        The start time, halts and counters are kept; FeedbackConfigError if the period or phase differ
        (they align the controller with the gait and are fixed while it runs).
        """
        if (config.period, config.phase) != (self.config.period, self.config.phase):
            raise FeedbackConfigError('period and phase cannot change while the controller runs')
        self.config = config
        self._reset_runs(self._run_period)

    def period_index(self, t: float) -> int | None:
        """Gait period of time ``t`` (whole periods of gait time), or None without a start."""
        if self.start_time is None:
            return None
        tau = (t - self.start_time) / self.config.period + self.config.phase
        return math.floor(tau + 1e-9)

    def update(self, t: float, forces: Sequence[float]) -> Decision:
        """Feed one checked sample (time in s, four forces in ``FSR_FACES`` order, NaN = unusable)."""
        if not math.isfinite(t):
            raise FsrSampleError(f'FSR sample time must be finite, got {t!r}', 'bad_stamp')
        if t < self._last_t:
            raise FsrSampleError(f'FSR sample time went backwards: {t:.6f} s after {self._last_t:.6f} s',
                                 'time_backwards')
        if len(forces) != N_FACES:
            raise FsrSampleError(f'expected {N_FACES} forces, got {len(forces)}', 'wrong_faces')
        self._last_t = t
        c = self.counters
        c.samples += 1
        if self.start_time is not None and t < self.start_time:
            c.before_start += 1
            self._reset_runs(None)
            return Decision(False, None, None)
        period = self.period_index(t)
        if period != self._run_period:
            self._reset_runs(period)
        triggered: str | None = None
        for i, (force, window) in enumerate(zip(forces, self.config.windows, strict=False)):
            if math.isnan(force):
                c.bad_values += 1
                self._runs[i] = 0
                continue
            if window.contains(force):
                c.in_window[i] += 1
                self._runs[i] += 1
                if self._runs[i] >= self.config.debounce and triggered is None:
                    triggered = FSR_FACES[i]
            else:
                self._runs[i] = 0
        if triggered is None:
            return Decision(False, None, period)
        if not self._may_halt(t, period):
            c.suppressed += 1
            return Decision(False, None, period)
        c.halts += 1
        self._last_halt_period = period
        self._last_halt_time = t
        self._reset_runs(period)
        return Decision(True, triggered, period)

    def _may_halt(self, t: float, period: int | None) -> bool:
        """At most one halt per gait period (or per refractory period T without a known start)."""
        if period is None:
            return t - self._last_halt_time >= self.config.period - 1e-9
        return period != self._last_halt_period

    def _reset_runs(self, period: int | None) -> None:
        self._runs = [0] * N_FACES
        self._run_period = period
