"""Typed trial results: what a trial kind returns, with units in the field names.

A kind returns a frozen dataclass derived from ``TrialResult``; the engine stores ``as_dict()`` (the
JSON record's ``result``) and the report reads it back with ``from_dict``. Optional fields (default
None) are left out of the stored dict while None, so a kind that gains a field keeps the stored bytes of
the trials that do not ask for it. Units: ``_bl`` body lengths, ``_w`` W (= BL for the smarticle),
``_deg`` degrees, ``_um`` micrometres, ``_periods`` gait periods; ``trouble`` is the SimTrouble message
that ended the trial early ('' if none).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any, TypeVar

R = TypeVar('R', bound='TrialResult')


@dataclass(frozen=True)
class TrialResult:
    """Base of the typed results: JSON-ready dict out (``as_dict``), typed record in (``from_dict``)."""

    def as_dict(self) -> dict[str, Any]:
        """The stored form: every field, optional ones (default None) only when set."""
        optional = {f.name for f in fields(self) if f.default is None}
        return {k: v for k, v in asdict(self).items() if not (k in optional and v is None)}

    @classmethod
    def from_dict(cls: type[R], data: Mapping[str, Any]) -> R:
        """The typed record of a stored result (unknown keys ignored, missing optional fields None)."""
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in names})


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
    #: One record per glider (i, j, class, start and lifetime in periods, r_bl, theta_deg, phi_deg, distance_w,
    #: path_w, v_com_w_per_period, beta, isolated, com_path_w; contact_fraction when contacts are watched).
    gliders: list[dict[str, Any]]
    trajectory_bl: list[Any]        # body centres once per period (BL), [] without ``trajectory``
    trajectory_dt: float            # s between the trajectory's samples (one gait period)


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
    gliders: list[dict[str, Any]]   # always []
