"""The ``single`` kind (P7): one robot alone, its drift per gait cycle. ``single_mujoco`` is the same trial
stepped by MuJoCo (a cross-engine check)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from smarticle_sim.batch import run_trial
from smarticle_sim.mujoco_engine import MujocoSettings, run_mujoco
from smarticle_sim.scenes import RobotPlacement, Scene

from ..cost_model import sim_cpu_seconds
from ..kind import KINDS
from ..params import SimParams
from ..results import SingleResult
from .pair import MujocoParams


@dataclass(frozen=True)
class SingleParams(SimParams):
    """One robot, its heading drawn from the seed."""

    periods: float = 20.0
    sample_every: int = 1


@dataclass(frozen=True)
class SingleMujocoParams(SingleParams, MujocoParams):
    """``SingleParams`` stepped by MuJoCo."""


@KINDS.register('single', SingleParams, 'one robot alone, drift per cycle (P7)', result=SingleResult,
                sections=('drift',), cost=lambda p: sim_cpu_seconds(1, p.periods, time_step=p.time_step()))
def single_trial(p: SingleParams, seed: int) -> SingleResult:
    """P7: one robot alone (heading drawn from the seed); drift per cycle in micrometres."""
    return _single(p, seed, None)


@KINDS.register('single_mujoco', SingleMujocoParams, 'the single kind stepped by MuJoCo (cross-engine check)',
                result=SingleResult, engines=('mujoco',), sections=('drift',),
                cost=lambda p: sim_cpu_seconds(1, p.periods, 'mujoco', p.time_step()))
def single_mujoco_trial(p: SingleMujocoParams, seed: int) -> SingleResult:
    """The single kind's trial stepped by MuJoCo (``mujoco`` sets ``MujocoSettings`` fields)."""
    return _single(p, seed, MujocoSettings(**dict(p.mujoco or {})))


def _single(p: SingleParams, seed: int, mujoco: MujocoSettings | None) -> SingleResult:
    """The single kind in Bullet (``mujoco`` None) or MuJoCo."""
    config = p.config()
    gait = p.gait(config)
    heading = float(np.random.default_rng(seed).uniform(-math.pi, math.pi))
    a = gait.alpha_max
    scene = Scene((RobotPlacement(0.0, 0.0, heading, a, a, gait),), name='single', seed=seed)
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
