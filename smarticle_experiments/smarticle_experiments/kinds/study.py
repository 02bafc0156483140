"""The physics study's kinds (``smarticle-experiments physics-study``; ``smarticle_experiments.physics_study``
runs them): a pair's collisions, a lone robot's drift, a pair over many periods, dense stability and head-on
impacts, each at flat ``settings`` (PhysicsConfig / RobotSpec fields, ``gait_speed``, ``x_`` knobs) and
under a ``label`` for its tables."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..cost_model import IMPACT_TRIAL_S, sim_cpu_seconds
from ..kind import KINDS, KindParams
from ..physics_study import (StudyRow, dt_inv, study_collision_trial, study_config, study_dense_trial,
                             study_drift_trial, study_impact_trial, study_pair_trial)
from ..results import (StudyCollisionResult, StudyDenseResult, StudyDriftResult, StudyImpactResult,
                       StudyInadmissibleResult, StudyPairResult)


@dataclass(frozen=True)
class StudyParams(KindParams):
    """Flat ``settings`` (``physics_study.split_settings``) and the setting's ``label`` in the tables."""

    settings: Mapping[str, Any] = field(default_factory=dict)
    label: str = 'shipped'

    def time_step(self) -> float | None:
        """The time step the settings set (None: the shipped one)."""
        return dict(self.settings or {}).get('time_step')

    def check(self) -> None:
        """Known settings that make a valid config."""
        study_config(dict(self.settings or {}))


@dataclass(frozen=True)
class CollisionParams(StudyParams):
    """A pair start, both robots at gait phase ``phase``."""

    r_bl: float = 1.3
    theta_deg: float = 150.0
    phi_deg: float = 180.0
    phase: float = 0.0
    periods: float = 20.0


@dataclass(frozen=True)
class DriftParams(StudyParams):
    """A lone robot at ``heading_deg``; the first ``skip`` periods not measured."""

    heading_deg: float = 90.0
    alpha_max_deg: float = 90.0
    periods: float = 20.0
    skip: int = 2


@dataclass(frozen=True)
class StudyPairParams(StudyParams):
    """A pair start at gait phases (``phase1``, ``phase2``)."""

    r_bl: float = 1.3
    theta_deg: float = 330.0
    phi_deg: float = 180.0
    phase1: float = 0.0
    phase2: float = 0.05
    periods: float = 100.0


@dataclass(frozen=True)
class StudyDenseParams(StudyParams):
    """``robots`` robots densely packed, gait phases within +- ``jitter`` periods."""

    robots: int = 7
    jitter: float = 0.0
    periods: float = 300.0
    sample_every: int = 6


@dataclass(frozen=True)
class ImpactParams(StudyParams):
    """Head-on impacts of two bodies at ``speed_m_s``, meeting at ``phases`` points over one step."""

    speed_m_s: float = 0.3
    phases: int = 16


@KINDS.register('study_collision', CollisionParams,
                'physics study: a pair with every contact impulse measured (collision mechanism)',
                result=StudyCollisionResult, inadmissible=StudyInadmissibleResult,
                cost=lambda p: sim_cpu_seconds(2, p.periods, time_step=p.time_step()))
def study_collision(p: CollisionParams, seed: int) -> StudyCollisionResult | StudyInadmissibleResult:
    """``physics_study.study_collision_trial``."""
    return study_collision_trial(p.as_dict(), seed)


@KINDS.register('study_drift', DriftParams, 'physics study: a lone robot\'s drift per cycle and tilt, tick by tick',
                result=StudyDriftResult, cost=lambda p: sim_cpu_seconds(1, p.periods, time_step=p.time_step()))
def study_drift(p: DriftParams, seed: int) -> StudyDriftResult:
    """``physics_study.study_drift_trial``."""
    return study_drift_trial(p.as_dict(), seed)


@KINDS.register('study_pair', StudyPairParams,
                'physics study: a pair\'s contact per period, touching run, r and travel',
                result=StudyPairResult, inadmissible=StudyInadmissibleResult,
                cost=lambda p: sim_cpu_seconds(2, p.periods, time_step=p.time_step()))
def study_pair(p: StudyPairParams, seed: int) -> StudyPairResult | StudyInadmissibleResult:
    """``physics_study.study_pair_trial``."""
    return study_pair_trial(p.as_dict(), seed)


@KINDS.register('study_dense', StudyDenseParams, 'physics study: dense stability (trouble, overlap) and gliders',
                result=StudyDenseResult,
                cost=lambda p: sim_cpu_seconds(int(p.robots), p.periods, time_step=p.time_step()))
def study_dense(p: StudyDenseParams, seed: int) -> StudyDenseResult:
    """``physics_study.study_dense_trial``."""
    return study_dense_trial(p.as_dict(), seed)


@KINDS.register('study_impact', ImpactParams, 'physics study: effective restitution of head-on impacts',
                result=StudyImpactResult, cost=lambda p: IMPACT_TRIAL_S * float(p.phases) / 16.0)
def study_impact(p: ImpactParams, seed: int) -> StudyImpactResult:
    """``physics_study.study_impact_trial``."""
    return study_impact_trial(p.as_dict(), seed)


def study_row(record: Mapping[str, Any]) -> StudyRow[Any]:
    """The row of a stored physics-study record (``status: ok``): its result read back typed."""
    params = record['params']
    return StudyRow(params, int(record['seed']), dt_inv(params.get('settings') or {}),
                    KINDS[str(record['kind'])].read(record['result']))
