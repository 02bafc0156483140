"""The ``single`` kind (P7): one robot alone, its drift per gait cycle, in Bullet or (a spec's ``engine: mujoco``)
MuJoCo. ``single_mujoco`` is the same trial with MuJoCo as its default engine, kept under its own name so that its
stored trials keep their keys."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from smarticle_sim.batch import run_trial
from smarticle_sim.mujoco_engine import run_mujoco
from smarticle_sim.scenes import RobotPlacement, Scene

from ..cost_model import sim_cpu_seconds
from ..kind import KINDS, OMIT_DEFAULT
from ..params import SIM_ENGINES, SimParams
from ..results import SingleResult


@dataclass(frozen=True)
class SingleParams(SimParams):
    """One robot, its heading drawn from the seed."""

    periods: float = 20.0
    sample_every: int = 1


@dataclass(frozen=True)
class SingleMujocoParams(SingleParams):
    """``SingleParams`` with MuJoCo as the default engine (``mujoco`` stored even when empty, as it always was)."""

    engine: str = field(default='mujoco', metadata=OMIT_DEFAULT)
    mujoco: Mapping[str, Any] = field(default_factory=dict)


@KINDS.register('single', SingleParams, 'one robot alone, drift per cycle (P7)', result=SingleResult,
                engines=SIM_ENGINES, sections=('drift',),
                cost=lambda p: sim_cpu_seconds(1, p.periods, p.engine, p.time_step()))
def single_trial(p: SingleParams, seed: int) -> SingleResult:
    """P7: one robot alone (heading drawn from the seed); drift per cycle in micrometres."""
    config = p.config()
    gait = p.gait(config)
    heading = float(np.random.default_rng(seed).uniform(-math.pi, math.pi))
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, heading, a, a, gait),), name='single', seed=seed)
    mujoco = p.mujoco_settings()
    if mujoco is not None:
        rec = run_mujoco(config, scene, float(p.periods), int(p.sample_every), mujoco)
    else:
        rec = run_trial(config, scene, float(p.periods), sample_every=int(p.sample_every))
    per = max(1, round(gait.period / (config.physics.control_tick * int(p.sample_every))))
    xy = rec.poses[::per, 0, :2]
    cycles = max(len(xy) - 1, 1)
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    return SingleResult(heading_deg=math.degrees(heading), trouble=rec.trouble, cycles=len(xy) - 1,
                        drift_um_per_cycle=float(np.linalg.norm(xy[-1] - xy[0]) / cycles * 1e6),
                        step_um_per_cycle=float(steps.mean() * 1e6) if steps.size else None)


@KINDS.register('single_mujoco', SingleMujocoParams,
                'the single kind in MuJoCo (the single kind with engine mujoco under its own name: its stored '
                'trials\' keys)', result=SingleResult, engines=('mujoco',), sections=('drift',),
                cost=lambda p: sim_cpu_seconds(1, p.periods, p.engine, p.time_step()))
def single_mujoco_trial(p: SingleMujocoParams, seed: int) -> SingleResult:
    """``single_trial`` in MuJoCo."""
    return single_trial(p, seed)
