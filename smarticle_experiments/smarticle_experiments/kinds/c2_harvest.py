"""The ``c2_harvest`` kind: dense open-loop runs of the feedback robot, every C2 glider sampled at its period
boundaries (``smarticle_experiments.c2_harvest`` runs it)."""

from __future__ import annotations

from dataclasses import dataclass

from ..c2_harvest import harvest_recording, sample_record
from ..cost_model import sim_cpu_seconds
from ..configs import make_config, make_gait
from ..kind import KINDS, KindParams
from ..results import C2HarvestResult


@dataclass(frozen=True)
class C2HarvestParams(KindParams):
    """``robots`` robots of ``preset`` densely packed, in phase; C2 gliders of at least ``min_periods``, sampled
    after ``settle`` periods."""

    periods: float = 150.0
    preset: str = 'feedback'
    alpha_max_deg: float = 90.0
    robots: int = 7
    min_periods: int = 30
    settle: int = 5
    sample_every: int = 4

    def check(self) -> None:
        """A valid preset and gait."""
        make_gait(make_config(str(self.preset), {}, {}), self.alpha_max_deg)


@KINDS.register('c2_harvest', C2HarvestParams,
                'dense open-loop feedback robots: where their C2 gliders sit (smarticle_experiments.c2_harvest)',
                result=C2HarvestResult, cost=lambda p: sim_cpu_seconds(int(p.robots), p.periods))
def c2_harvest_trial(p: C2HarvestParams, seed: int) -> C2HarvestResult:
    """A dense open-loop trial of the feedback robot (in phase, as the paper's collectives start): every C2
    glider of at least ``min_periods`` sampled at its period boundaries after ``settle`` periods, with the
    pair's full state (``c2_harvest.harvest_trial``)."""
    samples, trouble = harvest_recording(seed, float(p.periods), str(p.preset), float(p.alpha_max_deg),
                                         int(p.robots), int(p.min_periods), int(p.settle), int(p.sample_every))
    return C2HarvestResult(samples=[sample_record(s) for s in samples],
                           gliders=len({(s.seed, min(s.i, s.j), max(s.i, s.j)) for s in samples}), trouble=trouble)
