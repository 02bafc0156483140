"""The ``accuracy`` kind: run time against error of one physics setting (a pair and a lone robot)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from smarticle_sim.batch import run_trial
from smarticle_common.facts import GAIT_PERIOD
from smarticle_sim.scenes import pair_scene
from smarticle_sim.settings import PhysicsConfig

from ..cost_model import BULLET_SPEED
from ..kind import KINDS
from ..params import SimParams
from ..results import AccuracyResult
from ..trials import rounded
from .single import SingleParams, single_trial


@dataclass(frozen=True)
class AccuracyParams(SimParams):
    """One (physics rate, control tick, solver iterations) setting on a pair start and a lone robot."""

    periods: float = 20.0
    single_periods: float = 10.0      # the lone robot's periods
    rate_hz: float = 240.0            # physics steps per second
    control_tick: float = 1.0 / 60.0  # s
    solver_iterations: int = 50
    r_bl: float = 1.4
    theta_deg: float = 60.0
    phi_deg: float = 180.0
    phase2: float = 0.5

    def physics_of_setting(self) -> dict[str, Any]:
        """The physics overrides with this setting's rate, control tick and solver iterations."""
        return {**dict(self.physics or {}), 'time_step': 1.0 / float(self.rate_hz),
                'control_tick': float(self.control_tick), 'solver_iterations': int(self.solver_iterations)}

    def check(self) -> None:
        """A valid config and gait, also at this setting."""
        super().check()
        self.setting().config()

    def setting(self) -> SingleParams:
        """The lone robot's parameters at this setting."""
        return SingleParams(preset=self.preset, physics=self.physics_of_setting(), robot=self.robot,
                            periods=self.single_periods, alpha_max_deg=self.alpha_max_deg,
                            servo_speed=self.servo_speed, noise=self.noise, sample_every=1)


def accuracy_cpu_seconds(p: AccuracyParams) -> float:
    """The pair's and the lone robot's robot-seconds at this setting's rate, by Bullet's speed."""
    step = PhysicsConfig().time_step * float(p.rate_hz)
    robot_s = (2.0 * float(p.periods) + float(p.single_periods)) * GAIT_PERIOD
    return robot_s * step / BULLET_SPEED


@KINDS.register('accuracy', AccuracyParams, 'run time against error of one physics setting (pair + lone robot)',
                result=AccuracyResult, sections=('accuracy',), cost=lambda p: accuracy_cpu_seconds(p))
def accuracy_trial(p: AccuracyParams, seed: int) -> AccuracyResult:
    """Run time against error: one (physics rate, solver iterations) setting on a pair and a lone robot.

    Returns the pair's body-centre positions after 1 and 10 periods (BL), its mean separation r (BL),
    the lone robot's drift per cycle (um) and the wall time per simulated second of the pair run; the
    errors against the sweep's finest setting are computed by the report.
    """
    lone = p.setting()
    config = lone.config()
    gait = p.gait(config)
    scene = pair_scene(config.robot, gait, float(p.r_bl), math.radians(p.theta_deg), math.radians(p.phi_deg),
                       (0.0, float(p.phase2)), seed=seed)
    every = max(1, round(0.05 / config.physics.control_tick))
    start = time.perf_counter()
    rec = run_trial(config, scene, float(p.periods), sample_every=every)
    wall = time.perf_counter() - start
    bl = config.robot.body_length
    out: dict[str, Any] = {'trouble': rec.trouble, 'wall_per_sim_s': wall / max(float(rec.time[-1]), 1e-12)}
    for mark in (1, 10):
        k = int(np.argmin(np.abs(rec.time - mark * gait.period)))
        out[f'xy{mark}_bl'] = rounded(rec.poses[k, :, :2] / bl, 7) if abs(rec.time[k] - mark * gait.period) < 0.06 \
            else None
    out['r_mean_bl'] = float(np.mean(np.hypot(*(rec.poses[:, 1, :2] - rec.poses[:, 0, :2]).T))) / bl
    single = single_trial(lone, seed)
    out['drift_um_per_cycle'] = single.drift_um_per_cycle
    if single.trouble:
        out['trouble'] = '; '.join(t for t in (out['trouble'], single.trouble) if t)
    return AccuracyResult(**out)
