"""The ``p6`` kind (P6): a C2 pair of the feedback robot, open loop or with impact-halt feedback
(``smarticle_experiments.p6`` runs it), in Bullet or (a spec's ``engine: mujoco``) MuJoCo."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

from smarticle_sim.settings import NoiseConfig

from ..configs import NOISE_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS, make_config, make_gait, noise_mapping
from ..cost_model import sim_cpu_seconds
from ..kind import KINDS, optional
from ..params import SIM_ENGINES, EngineParams
from ..p6 import START_NAMES, Condition, run_pair_trial, start_base, windows_config
from ..results import P6Result
from ..trials import finite


@dataclass(frozen=True)
class P6Params(EngineParams):
    """A C2 pair of the feedback robot (its preset with ``physics`` / ``robot`` overrides) from the start
    ``start``, open loop or with feedback (``windows``: feedback parameters replacing the shipped impact
    windows; ``details``: the bound run's travel and the periods with contact, a step hook)."""

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {'physics': PHYSICS_FIELDS, 'robot': ROBOT_FIELDS,
                                                      'noise': NOISE_FIELDS, **EngineParams.GROUPS}

    periods: float = 100.0
    alpha_max_deg: float = 90.0
    feedback: bool = False
    start: str = 'harvested'                                    # one of p6.START_NAMES
    physics: Mapping[str, Any] = field(default_factory=dict)
    robot: Mapping[str, Any] = field(default_factory=dict)
    windows: Mapping[str, Any] = field(default_factory=dict)
    details: bool = False
    noise: Mapping[str, Any] | None = optional()

    def check(self) -> None:
        """A known engine, start, noise, config, gait and windows."""
        super().check()
        if self.start not in START_NAMES:
            raise ValueError(f'params.start must be one of {", ".join(START_NAMES)}, got {self.start!r}')
        replace(NoiseConfig.none(), **noise_mapping(self.noise))
        config = make_config('feedback', dict(self.physics or {}), dict(self.robot or {}))
        make_gait(config, self.alpha_max_deg)
        if self.windows:
            windows_config(self.windows)


@KINDS.register('p6', P6Params, 'C2 pair of the feedback robot, open loop or feedback (P6; smarticle_experiments.p6)',
                result=P6Result, engines=SIM_ENGINES, sections=('p6',),
                cost=lambda p: sim_cpu_seconds(2, p.periods, p.engine, p.engine_time_step(p.physics)))
def p6_trial(p: P6Params, seed: int) -> P6Result:
    """P6: a C2 pair of the feedback robot, open loop or with impact-halt feedback (the feedback package's trial)."""
    noise = replace(NoiseConfig.none(), **noise_mapping(p.noise)) if p.noise else None
    details = bool(p.details)
    trial = run_pair_trial(Condition(float(p.alpha_max_deg), bool(p.feedback)), seed, float(p.periods),
                           feedback=windows_config(p.windows) if p.windows else None,
                           base=start_base(str(p.start)), noise=noise, count_contacts=details,
                           robot_changes=dict(p.robot or {}), physics_changes=dict(p.physics or {}),
                           engine=p.engine_factory())
    return P6Result(lifetime_periods=int(trial.lifetime_periods), censored=bool(trial.censored),
                    halts=len(trial.halts), trouble=trial.trouble, r0_bl=trial.start[0], theta0_deg=trial.start[1],
                    phi0_deg=trial.start[2], final_r_bl=finite(float(trial.r[-1])) if len(trial.r) else None,
                    travel_w=trial.travel_w if details else None,
                    contact_periods=[int(q) for q in trial.contact_periods] if details else None)
