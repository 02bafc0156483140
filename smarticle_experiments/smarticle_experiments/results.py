"""Typed trial results: what a trial kind returns, with units in the field names.

A kind returns a frozen dataclass derived from ``TrialResult``; the engine stores ``as_dict()`` (the
JSON record's ``result``) and the report reads it back typed with ``kinds.read_result(kind, stored)`` (the
kind names its result type), nested bound-pair records included (``GliderRecord``). Optional fields (default
None) are left out of the stored dict while None, so a kind that gains a field keeps the stored bytes of the
trials that do not ask for it; the fields are in the stored order, so ``as_dict()`` is the stored dict key
for key.

Units: ``_bl`` body lengths, ``_w`` W (= BL for the smarticle),
``_deg`` degrees, ``_um`` micrometres, ``_periods`` gait periods; ``trouble`` is the SimTrouble message
that ended the trial early ('' if none).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar, TypeVar


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
    """One bound pair of the glider analysis (``trials.glider_record``; bound >= K periods in a row): lengths in
    BL (= W), angles in degrees. It is a glider only if ``distance_w`` over ``lifetime_periods`` meets the glider
    rule (``smarticle_tracking.gliders.pair_kind``; the report counts them). The class name and the field names
    are the stored ones."""

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
    distance_w: float | None        # net displacement of the pair's centre over its life (the glider rule's travel)
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

    lifetime_periods: int           # bound run from period 0 (glider analysis, K = 1): glider or not
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
    """A dense open-loop trial of the feedback robot: every C2 bound pair's (bound >= K periods, travel not
    checked) pair coordinates at its period boundaries (``c2_harvest.sample_record`` rows: seed, i, j, period,
    r_bl, theta_deg, phi_deg, touched and the pair's full state)."""

    samples: list[dict[str, Any]]
    gliders: int                    # C2 bound pairs that gave samples (stored name)
    trouble: str


@dataclass(frozen=True)
class DenseResult(TrialResult):
    """Robots densely packed (P1-P3): the bound pairs of the glider analysis and per-trial figures (the stored
    names say "glider" for every bound pair; the report tells the gliders among them by their travel)."""

    periods_run: float              # gait periods the trial ran (fewer if it ended in trouble)
    trouble: str
    peak_tilt_deg: float | None     # largest body tilt at the trouble checks (None if not measured)
    peak_overlap_mm: float | None   # deepest contact overlap at the trouble checks
    n_gliders: int                  # bound pairs
    positive: bool                  # a pair bound >= positive_periods
    positive_isolated: bool         # ... that is isolated (no third robot within isolation_w W)
    longest_periods: int            # the longest bound pair's lifetime (0 without one)
    longest_class: str              # its class ('' without one)
    longest_distance_w: float | None
    #: One record per bound pair (stored dicts are read into ``GliderRecord``).
    gliders: list[GliderRecord]
    trajectory_bl: list[Any]        # body centres once per period (BL), [] without ``trajectory``
    trajectory_dt: float            # s between the trajectory's samples (one gait period)

    def __post_init__(self) -> None:
        object.__setattr__(self, 'gliders', _gliders(self.gliders))


@dataclass(frozen=True)
class PairResult(DenseResult):
    """Two robots from pair coordinates (P4, P5): binding at the end, travel, and the pair's bound pairs."""

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


# ------------------------------------------------------------------ the physics study's kinds (physics_study)
# Their field names are the study's table columns of old (kept: the stored bytes stay the same); the
# comments give the units.


@dataclass(frozen=True)
class StudyInadmissibleResult(TrialResult):
    """A study pair start whose robots overlap (``study_collision``, ``study_pair``): not run."""

    admissible: bool                # always False
    why: str                        # the scene's refusal
    trouble: str


@dataclass(frozen=True)
class StudyCollisionResult(TrialResult):
    """``study_collision``: a pair's collisions with every contact impulse measured (``summarise_trace``)."""

    admissible: bool                # always True
    collisions: int                 # collision events (runs of contact steps, gaps of <= 3 steps merged)
    r0: float                       # centre distance at the start (BL)
    r_end: float                    # ... at the end (BL)
    J_normal: float                 # robot-robot normal impulse along the pair axis, + = apart (N s)
    J_friction: float               # robot-robot friction impulse along the axis (N s)
    J_plate: float                  # body-plate friction impulse along the axis (N s)
    dr_contact_BL: float            # change of r while in contact, summed over the collisions (BL)
    dr_coast_BL: float              # change of r in the contact-free time after them (BL)
    vsep_max: float                 # largest separation speed at a collision's end (m/s)
    coast_ms_med: float             # median time until the bodies stop after a collision (ms)
    touch_last10: bool              # any contact in the last 10 periods
    depth_max_mm: float             # deepest robot-robot overlap (mm)
    trouble: str


@dataclass(frozen=True)
class StudyDriftResult(TrialResult):
    """``study_drift``: a lone robot's drift per cycle and tilt, tick by tick (``drift_run``)."""

    heading: float                  # start heading (deg)
    alpha: float                    # gait amplitude alpha_max (deg)
    periods: int                    # periods measured (after the skipped ones)
    net_um: float                   # net displacement per cycle (um)
    step_um: float                  # mean displacement per cycle (um)
    step_se_um: float               # its standard error (um)
    dir_deg: float                  # direction of the net displacement (deg)
    tilt_max_deg: float             # largest body tilt at a control tick (deg)
    tilt_rms_deg: float             # rms body tilt (deg)
    wall_per_sim_s: float           # wall-clock s per simulated s
    trouble: str


@dataclass(frozen=True)
class StudyPairResult(TrialResult):
    """``study_pair``: a pair's contact per period, its longest touching run, r, phi and travel (``pair_run``)."""

    admissible: bool                # always True
    theta0: float                   # start pair angles (deg)
    phi0: float
    p1: float                       # gait phases of the two robots (periods)
    p2: float
    periods: int                    # periods asked for
    ran: int                        # periods run (fewer after trouble)
    touch: int                      # periods with robot-robot contact
    bound_run: int                  # longest run of touching periods (one-period gaps allowed)
    bound_to_end: bool              # that run lasts to the end
    touch_last10: bool              # any contact in the last 10 periods
    r_end: float                    # r at the end (BL; NaN without a period)
    r_mean_late: float              # mean r over the second half (BL)
    phi_late: float                 # circular mean phi over the second half (deg)
    travel_W: float                 # net travel of the pair's centre (W)
    late_travel_W: float            # ... over the second half (W)
    wall_per_sim_s: float           # wall-clock s per simulated s
    trouble: str


@dataclass(frozen=True)
class StudyDenseResult(TrialResult):
    """``study_dense``: dense stability and, for 7 robots, the gliders (``dense_run``)."""

    seed: int
    n: int                          # robots
    jitter: float                   # gait phase offsets within +- jitter (periods)
    periods: int
    sim_s: float                    # simulated time reached (s)
    wall_s: float                   # wall-clock time (s)
    x_real_time: float              # sim_s / wall_s
    deepest_mm: float               # deepest robot-robot overlap at the samples (mm)
    trouble: str
    #: For 7 robots that ran more than a period: bound pairs of >= 30 and >= 100 periods, isolated ones of >= 100
    #: (travel not checked; the names are the study's columns of old).
    gliders_30: int | None = None
    gliders_100: int | None = None
    isolated_100: int | None = None
    best_dist_W: float | None = None   # longest travel of a bound pair of >= 100 periods (W)
    c1_lives: str | None = None     # C1 bound pairs' lifetimes (periods), space-separated
    c2_lives: str | None = None     # C2 bound pairs' lifetimes (periods), space-separated


@dataclass(frozen=True)
class StudyImpactResult(TrialResult):
    """``study_impact``: effective restitution (separation / approach speed) of head-on impacts."""

    mean: float                     # over the meeting phases (dimensionless)
    sd: float
    min: float
    max: float
    overlap_mm: float               # deepest overlap (mm)
    restitution_by_phase: list[float]
    trouble: str
