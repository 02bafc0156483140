"""The ``dense`` kind (P1, P2, P3): N robots densely packed, in phase (or jittered); their gliders; in Bullet or
(a spec's ``engine: mujoco``) MuJoCo."""

from __future__ import annotations

from dataclasses import dataclass

from smarticle_sim.batch import run_trial
from smarticle_sim.runner import ContactPeriods
from smarticle_sim.scenes import dense_scene

from ..cost_model import sim_cpu_seconds
from ..kind import KINDS
from ..params import SIM_ENGINES, GliderParams
from ..results import DenseResult
from ..trials import add_contact_fractions, analyse_recording


@dataclass(frozen=True)
class DenseParams(GliderParams):
    """``robots`` robots densely packed (seeded), gait phases within +- ``phase_jitter`` periods."""

    robots: int = 7
    phase_jitter: float = 0.0
    sample_every: int = 4            # control ticks between recorded samples
    contacts: bool = False           # each glider's share of bound periods with contact (a step hook)

    def check(self) -> None:
        """A valid config and gait, at least one robot."""
        super().check()
        if int(self.robots) < 1:
            raise ValueError(f'robots must be >= 1, got {self.robots!r}')


@KINDS.register('dense', DenseParams, 'N robots densely packed (P1, P2, P3)', result=DenseResult,
                engines=SIM_ENGINES, sections=('p1', 'trajectories', 'configurations', 'lifetimes', 'contacts'),
                cost=lambda p: sim_cpu_seconds(int(p.robots), p.periods, p.engine, p.time_step()))
def dense_trial(p: DenseParams, seed: int) -> DenseResult:
    """P1/P2/P3: N robots densely packed, in phase (or jittered), for ``periods`` periods; its gliders."""
    config = p.config()
    gait = p.gait(config)
    scene = dense_scene(config.robot, gait, n=int(p.robots), seed=seed, phase_jitter=float(p.phase_jitter))
    watch = ContactPeriods(gait.period) if p.contacts else None
    rec = run_trial(config, scene, float(p.periods), sample_every=int(p.sample_every), record_contacts=False,
                    controllers=None if watch is None else (lambda physics, gaits: [watch]),
                    engine=p.engine_factory())
    result = analyse_recording(config, rec, gait.period, p)
    if watch is not None:
        add_contact_fractions(result['gliders'], watch.periods)
    return DenseResult(**result)
