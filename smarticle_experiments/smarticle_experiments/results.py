"""Typed trial results: what a trial kind returns, with units in the field names.

A kind returns a frozen dataclass derived from ``TrialResult``; the engine stores ``as_dict()`` (the
JSON record's ``result``) and the report reads it back typed with ``read_result(kind, stored)``, nested
glider records included (``GliderRecord``). Optional fields (default None) are left out of the stored dict
while None, so a kind that gains a field keeps the stored bytes of the trials that do not ask for it; the
fields are in the stored order, so ``as_dict()`` is the stored dict key for key.

Units: ``_bl`` body lengths, ``_w`` W (= BL for the smarticle),
``_deg`` degrees, ``_um`` micrometres, ``_periods`` gait periods; ``trouble`` is the SimTrouble message
that ended the trial early ('' if none).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar, TypeVar

from .errors import ResultError

R = TypeVar('R', bound='StoredRecord')


def _stored(value: Any) -> Any:
    """A field's value in the stored (JSON-ready) form: nested records as their dicts, containers copied."""
    if isinstance(value, StoredRecord):
        return value.as_dict()
    if isinstance(value, (list, tuple)):
        return [_stored(v) for v in value]
    if isinstance(value, dict):
        return {k: _stored(v) for k, v in value.items()}
    return copy.copy(value)


@dataclass(frozen=True)
class StoredRecord:
    """A typed record with a stored (JSON) form: dict out (``as_dict``), typed record in (``from_dict``).

    ``STORED_NAMES`` maps a field to its stored key where the key cannot be a Python name (``class``).
    """

    STORED_NAMES: ClassVar[Mapping[str, str]] = {}

    def as_dict(self) -> dict[str, Any]:
        """The stored form: every field in order, optional ones (default None) only when set."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.default is None and value is None:
                continue
            out[self.STORED_NAMES.get(f.name, f.name)] = _stored(value)
        return out

    @classmethod
    def from_dict(cls: type[R], data: Mapping[str, Any]) -> R:
        """The typed record of a stored result (unknown keys ignored, missing optional fields None)."""
        names = {cls.STORED_NAMES.get(f.name, f.name): f.name for f in fields(cls)}
        return cls(**{names[k]: v for k, v in data.items() if k in names})


@dataclass(frozen=True)
class GliderRecord(StoredRecord):
    """One glider of the glider analysis (``trials.glider_record``): lengths in BL (= W), angles in degrees."""

    STORED_NAMES: ClassVar[Mapping[str, str]] = {'glider_class': 'class'}

    i: int                          # the pair's robots (indices in the scene)
    j: int
    glider_class: str               # 'C1', 'C2' or 'unclassified' (stored as ``class``)
    start_period: int               # first bound period
    lifetime_periods: int           # bound periods in a row
    ongoing: bool                   # still bound at the end of the trial (right-censored)
    r_bl: float | None              # mean centre distance (None if not finite)
    theta_deg: float | None         # circular mean pair angles
    phi_deg: float | None
    distance_w: float | None        # net displacement of the pair's centre over its life
    path_w: float | None            # path length of the pair's centre
    v_com_w_per_period: float | None  # speed of the pair's centre
    beta: float | None              # MSD exponent of its own path (None if it cannot be fitted)
    isolated: bool                  # no third robot within isolation_w W in >= 90 % of its periods
    isolation: float                # that share of its periods (0..1)
    com_path_w: list[Any]           # the pair's centre once per period (W; None for a missing sample)
    #: With ``contacts``: the share of its bound periods in which the two robots touched (0..1).
    contact_fraction: float | None = None


def _gliders(values: Any) -> list[GliderRecord]:
    """Glider records from stored dicts (or records)."""
    return [g if isinstance(g, GliderRecord) else GliderRecord.from_dict(g) for g in values]


@dataclass(frozen=True)
class TrialResult(StoredRecord):
    """Base of the typed results of the trial kinds."""


@dataclass(frozen=True)
class SingleResult(TrialResult):
    """A lone robot (P7): its drift per gait cycle."""

    heading_deg: float              # start heading drawn from the seed
    trouble: str
    cycles: int                     # whole gait periods measured
    drift_um_per_cycle: float       # net displacement / cycles
    step_um_per_cycle: float | None  # mean displacement per cycle (None without a cycle)


@dataclass(frozen=True)
class P6Result(TrialResult):
    """A C2 pair of the feedback robot (P6), open loop or with impact-halt feedback."""

    lifetime_periods: int           # bound run from period 0 (glider analysis, K = 1)
    censored: bool                  # still bound at the end of the trial
    halts: int                      # halts the feedback controllers decided (0 open loop)
    trouble: str
    r0_bl: float                    # start (pair coordinates after the seeded jitter)
    theta0_deg: float
    phi0_deg: float
    final_r_bl: float | None        # r at the end (None without a sample)
    #: With ``details``: the centre-of-mass travel over the bound run (W).
    travel_w: float | None = None
    #: With ``details``: the gait periods in which the robots touched at any physics step.
    contact_periods: list[int] | None = None


@dataclass(frozen=True)
class C2HarvestResult(TrialResult):
    """A dense open-loop trial of the feedback robot: every C2 glider's pair coordinates at its period
    boundaries (``c2_harvest.sample_record`` rows: seed, i, j, period, r_bl, theta_deg, phi_deg, touched and
    the pair's full state)."""

    samples: list[dict[str, Any]]
    gliders: int                    # C2 gliders that gave samples
    trouble: str


@dataclass(frozen=True)
class DenseResult(TrialResult):
    """Robots densely packed (P1-P3): the gliders of the glider analysis and per-trial figures."""

    periods_run: float              # gait periods the trial ran (fewer if it ended in trouble)
    trouble: str
    peak_tilt_deg: float | None     # largest body tilt at the trouble checks (None if not measured)
    peak_overlap_mm: float | None   # deepest contact overlap at the trouble checks
    n_gliders: int
    positive: bool                  # a glider of >= positive_periods
    positive_isolated: bool         # ... that is isolated (no third robot within isolation_w W)
    longest_periods: int            # the longest glider's lifetime (0 without a glider)
    longest_class: str              # its class ('' without a glider)
    longest_distance_w: float | None
    #: One record per glider (stored dicts are read into ``GliderRecord``).
    gliders: list[GliderRecord]
    trajectory_bl: list[Any]        # body centres once per period (BL), [] without ``trajectory``
    trajectory_dt: float            # s between the trajectory's samples (one gait period)

    def __post_init__(self) -> None:
        object.__setattr__(self, 'gliders', _gliders(self.gliders))


@dataclass(frozen=True)
class PairResult(DenseResult):
    """Two robots from pair coordinates (P4, P5): binding at the end, travel, and the pair's gliders."""

    r0_bl: float                    # start after the seeded jitter
    theta0_deg: float
    phi0_deg: float
    admissible: bool                # True: the start did not overlap
    bound_tail_periods: int         # periods at the end bound by r < r_bind_bl or contact
    bound_at_end: bool              # bound_tail_periods >= bound_tail
    colliding_tail_periods: int     # the same with contact alone
    colliding_at_end: bool
    out_of_reach_at_end: bool       # centres farther apart than twice the robot's reach
    late_w: float                   # centre-of-mass travel over the second half (W)
    r_end_bl: float
    phi_end_deg: float


@dataclass(frozen=True)
class InadmissiblePairResult(TrialResult):
    """A pair start whose robots overlap: not run (drawn black in the basin map, not a failure)."""

    r0_bl: float
    theta0_deg: float
    phi0_deg: float
    admissible: bool                # always False
    why: str                        # the scene's refusal
    trouble: str
    gliders: list[GliderRecord]     # always []

    def __post_init__(self) -> None:
        object.__setattr__(self, 'gliders', _gliders(self.gliders))


@dataclass(frozen=True)
class AccuracyResult(TrialResult):
    """One physics setting's run time and accuracy figures (``accuracy``): the errors against the sweep's
    finest setting are computed by the report."""

    trouble: str                    # the pair's and the lone robot's trouble, '; '-joined
    wall_per_sim_s: float           # wall-clock s per simulated s of the pair run
    xy1_bl: list[list[float | None]] | None   # the pair's body centres after 1 period (BL; None without a sample)
    xy10_bl: list[list[float | None]] | None  # ... after 10 periods
    r_mean_bl: float                # the pair's mean centre distance over the run
    drift_um_per_cycle: float       # the lone robot's drift per gait cycle


#: The typed result of each built-in kind (the pair kinds' inadmissible starts: ``InadmissiblePairResult``).
RESULT_TYPES: dict[str, type[TrialResult]] = {
    'dense': DenseResult, 'pair': PairResult, 'pair_mujoco': PairResult, 'single': SingleResult,
    'single_mujoco': SingleResult, 'p6': P6Result, 'c2_harvest': C2HarvestResult, 'accuracy': AccuracyResult,
}


def read_result(kind: str, data: Mapping[str, Any]) -> TrialResult | dict[str, Any]:
    """A stored result (the JSON record's ``result``) as its kind's typed record; a kind without a type
    (a user's ``module:function``) gives the dict back. Raises ResultError if the stored dict does not fit."""
    cls: type[TrialResult] | None = RESULT_TYPES.get(kind)
    if cls is PairResult and data.get('admissible') is False:
        cls = InadmissiblePairResult
    if cls is None:
        return dict(data)
    try:
        return cls.from_dict(data)
    except TypeError as exc:
        raise ResultError(f'a stored {kind} result does not fit {cls.__name__}: {exc}') from None
