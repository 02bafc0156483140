"""The Chrono kinds, the authors' engine as a reference (``smarticle_sim.chrono_reference``, where it is built):
``pair_chrono`` (two robots from pair coordinates) and ``single_chrono`` (one robot's drift per cycle). Their
parameters are the driver's (``PAIR_CHRONO_DEFAULTS``, ``SINGLE_CHRONO_DEFAULTS``); they return its dicts."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from smarticle_sim.chrono_reference import (CHRONO_FIELDS, ChronoSettings, ChronoUnavailable, driver_path,
                                            pair_chrono_trial, single_chrono_trial)
from smarticle_sim.errors import SimError

from ..configs import DIAGNOSTIC_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS
from ..kind import KINDS, OMIT_DEFAULT
from ..params import SimParams


def chrono_missing() -> str | None:
    """Why the Chrono driver cannot run here (tools/chrono_reference/build_chrono.sh builds it), or None."""
    try:
        driver_path()
    except ChronoUnavailable as exc:
        return str(exc)
    return None


@dataclass(frozen=True)
class ChronoParams(SimParams):
    """A robot preset with overrides and a gait in Chrono: ``chrono`` sets ``ChronoSettings`` fields; no noise."""

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {'physics': PHYSICS_FIELDS, 'robot': ROBOT_FIELDS,
                                                      'diagnostics': DIAGNOSTIC_FIELDS, 'chrono': CHRONO_FIELDS}
    ENGINES: ClassVar[tuple[str, ...]] = ('chrono',)

    engine: str = field(default='chrono', metadata=OMIT_DEFAULT)
    chrono: Mapping[str, Any] = field(default_factory=dict)
    periods: float = 20.0
    sample_every: int = 3

    def check(self) -> None:
        """A valid config, gait and ChronoSettings; no noise sources (the driver has none)."""
        if self.noise is not None:
            raise ValueError('noise: the Chrono kinds have no noise sources')
        super().check()
        try:
            ChronoSettings(**dict(self.chrono or {}))
        except SimError as exc:
            raise ValueError(str(exc)) from None


@dataclass(frozen=True)
class PairChronoParams(ChronoParams):
    """Two robots from pair coordinates in Chrono (``hold_first``: robot 1's body held in place)."""

    r_bl: float = 1.3
    theta_deg: float = 330.0
    phi_deg: float = 180.0
    phase2: float = 0.0
    periods: float = 40.0
    hold_first: bool = False
    r_bind_bl: float = 1.6
    bound_tail: int = 10


@KINDS.register('pair_chrono', PairChronoParams,
                'two robots from pair coordinates in Chrono, the authors\' engine (cross-engine check; '
                'smarticle_sim.chrono_reference, needs the Chrono build)', engines=('chrono',),
                unavailable=chrono_missing)
def pair_chrono(p: PairChronoParams, seed: int) -> dict[str, Any]:
    """``chrono_reference.pair_chrono_trial`` of these parameters."""
    return pair_chrono_trial(p.as_dict(), seed)


@KINDS.register('single_chrono', ChronoParams, 'one robot alone in Chrono, drift per cycle (cross-engine check; '
                'needs the Chrono build)', engines=('chrono',), unavailable=chrono_missing)
def single_chrono(p: ChronoParams, seed: int) -> dict[str, Any]:
    """``chrono_reference.single_chrono_trial`` of these parameters."""
    return single_chrono_trial(p.as_dict(), seed)
