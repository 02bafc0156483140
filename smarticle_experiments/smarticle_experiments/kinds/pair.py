"""The ``pair`` kind (P4 basin scan, P5 alpha_max sweep): two robots from pair coordinates; binding at the end,
travel and the pair's gliders, in Bullet or (a spec's ``engine: mujoco``) MuJoCo. ``pair_mujoco`` is the same
trial with MuJoCo as its default engine, kept under its own name so that its stored trials keep their keys."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from smarticle_sim.batch import run_trial
from smarticle_sim.chrono_reference import trailing_true
from smarticle_sim.errors import SceneError
from smarticle_sim.mujoco_engine import run_mujoco
from smarticle_sim.runner import ContactPeriods
from smarticle_sim.scenes import pair_scene

from ..cost_model import sim_cpu_seconds
from ..kind import KINDS, OMIT_DEFAULT
from ..params import SIM_ENGINES, GliderParams
from ..results import InadmissiblePairResult, PairResult
from ..trials import analyse_recording, pair_start

PAIR_SECTIONS: tuple[str, ...] = ('basin', 'alpha_sweep', 'step_convergence', 'pair_paths')


@dataclass(frozen=True)
class PairParams(GliderParams):
    """Two robots from pair coordinates (r BL, theta and phi deg) plus seeded jitter, robot 2 ``phase2`` ahead."""

    periods: float = 75.0
    min_periods: int = 10
    r_bl: float = 1.3
    theta_deg: float = 0.0
    phi_deg: float = 180.0
    phase2: float = 0.0                       # robot 2's gait phase (periods)
    start_jitter: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])   # uniform +- (r, theta, phi)
    sample_every: int = 2
    bound_tail: int = 5                       # bound at the end: this many bound periods at the end
    alpha2_delta_deg: float = 0.0             # robot 2's amplitude minus robot 1's
    hold_first: bool = False                  # robot 1's body held in place, its arms following the gait

    def check(self) -> None:
        """A valid engine, config and gait; no held robot in MuJoCo (it has none)."""
        super().check()
        if self.hold_first and self.engine == 'mujoco':
            raise ValueError('hold_first: MuJoCo has no held robot; run it in Bullet or with kind pair_chrono')


@dataclass(frozen=True)
class PairMujocoParams(PairParams):
    """``PairParams`` with MuJoCo as the default engine (``mujoco`` stored even when empty, as it always was)."""

    engine: str = field(default='mujoco', metadata=OMIT_DEFAULT)
    mujoco: Mapping[str, Any] = field(default_factory=dict)


@KINDS.register('pair', PairParams, 'two robots from pair coordinates (P4 basin scan, P5 alpha_max sweep)',
                result=PairResult, inadmissible=InadmissiblePairResult, engines=SIM_ENGINES, sections=PAIR_SECTIONS,
                cost=lambda p: sim_cpu_seconds(2, p.periods, p.engine, p.time_step()))
def pair_trial(p: PairParams, seed: int) -> PairResult | InadmissiblePairResult:
    """P4/P5: two robots from pair coordinates; binding at the end, travel, and the pair's gliders.
    ``hold_first``: robot 1's body held in place, its arms still following the gait (P4 read literally; Bullet).

    In MuJoCo (soft contacts, an isotropic friction cone; ``mujoco`` sets ``MujocoSettings`` fields) a period
    counts as colliding if the robots touched at any servo update in it; in Bullet, at any physics step."""
    config = p.config()
    gait = p.gait(config)
    r, theta, phi = pair_start(p.as_dict(), seed)
    start = {'r0_bl': r, 'theta0_deg': theta, 'phi0_deg': phi}
    try:
        scene = pair_scene(config.robot, gait, r, math.radians(theta), math.radians(phi),
                           (0.0, float(p.phase2)), seed=seed,
                           alpha_max2=gait.alpha_max + math.radians(float(p.alpha2_delta_deg)),
                           hold_first=bool(p.hold_first))
    except SceneError as exc:
        return InadmissiblePairResult(**start, admissible=False, why=str(exc), trouble='', gliders=[])
    per = max(1, round(gait.period / (config.physics.control_tick * int(p.sample_every))))
    mujoco = p.mujoco_settings()
    if mujoco is not None:
        rec = run_mujoco(config, scene, float(p.periods), int(p.sample_every), mujoco)
        touched = {q for q in range((len(rec.time) - 1) // per)
                   if rec.contacts[q * per + 1:(q + 1) * per + 1, 0, 1].any()}
    else:
        watch = ContactPeriods(gait.period)   # contact at every physics step: a kick lasts one to a few steps
        rec = run_trial(config, scene, float(p.periods), sample_every=int(p.sample_every), record_contacts=True,
                        controllers=lambda physics, gaits: [watch])
        touched = watch.periods.get((0, 1), set())

    out = analyse_recording(config, rec, gait.period, p)
    bl = config.robot.body_length
    touching = rec.contacts[:, 0, 1]
    r_all = np.hypot(*(rec.poses[:, 1, :2] - rec.poses[:, 0, :2]).T) / bl
    bound = [bool(touching[q * per:(q + 1) * per].any() or (r_all[q * per:(q + 1) * per] < p.r_bind_bl).any())
             for q in range(len(touching) // per)]
    colliding = [q in touched for q in range(len(bound))]
    tail, colliding_tail = trailing_true(bound), trailing_true(colliding)
    com = rec.poses[::per, :, :2].mean(axis=1) / bl
    phi_end = (rec.poses[-1, 1, 2] - rec.poses[-1, 0, 2]) % (2.0 * math.pi)
    out.update(start, admissible=True, bound_tail_periods=tail,
               bound_at_end=tail >= int(p.bound_tail),
               colliding_tail_periods=colliding_tail,
               colliding_at_end=colliding_tail >= int(p.bound_tail),
               out_of_reach_at_end=bool(r_all[-1] * bl > 2.0 * config.robot.reach),
               late_w=float(np.linalg.norm(com[-1] - com[len(com) // 2])) if len(com) else 0.0,
               r_end_bl=float(r_all[-1]), phi_end_deg=math.degrees(phi_end))
    return PairResult(**out)


@KINDS.register('pair_mujoco', PairMujocoParams,
                'the pair kind in MuJoCo (the pair kind with engine mujoco under its own name: its stored trials\' '
                'keys)', result=PairResult, inadmissible=InadmissiblePairResult, engines=('mujoco',),
                sections=PAIR_SECTIONS, cost=lambda p: sim_cpu_seconds(2, p.periods, p.engine, p.time_step()))
def pair_mujoco_trial(p: PairMujocoParams, seed: int) -> PairResult | InadmissiblePairResult:
    """``pair_trial`` in MuJoCo."""
    return pair_trial(p, seed)
