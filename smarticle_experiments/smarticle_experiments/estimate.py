"""How long a spec's trials take, from a stated cost model (``list`` prints it, ``run`` says it before it starts).

A trial costs about its robots x its simulated seconds / the engine's speed in CPU seconds, the speed being
robot-seconds simulated per CPU second at the engine's shipped time step, measured on the 2-core development
machine (docs/experiments.md, "Run time estimates"):

* Bullet (every kind but the MuJoCo and Chrono ones): ``BULLET_SPEED`` = 55 (a pair 47, a lone robot 57,
  7 dense robots 61, a P6 pair of feedback robots 65; P1's 7 robots x 480 s take about 60 s, P4's pairs
  4.4 s of CPU each);
* MuJoCo at 1/9600 s: ``MUJOCO_SPEED`` = 11;
* a finer time step than the shipped one costs in proportion (1/1920 s: twice 1/960 s), a coarser one
  saves in proportion; solver iterations and recording options are not in the model.

A spec's trials share the cores, one trial per core at a time: its run time is about the sum over its
trials / cores, and never less than its longest trial. Chrono kinds and a user's ``module:function`` kinds
have no estimate (None).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from smarticle_common.facts import GAIT_PERIOD
from smarticle_sim.mujoco_engine import MujocoSettings
from smarticle_sim.settings import PhysicsConfig

from .spec import ExperimentSpec, apply_point

#: Robot-seconds simulated per CPU second by Bullet at the shipped time step (see the module docstring).
BULLET_SPEED = 55.0
#: Robot-seconds simulated per CPU second by MuJoCo at its shipped time step (1/9600 s).
MUJOCO_SPEED = 11.0
#: CPU seconds of one ``study_impact`` trial of 16 meeting points (two bodies, a fraction of a second each).
IMPACT_TRIAL_S = 0.1
#: The cores ``list`` and ``run`` quote the estimate for: the development machine's (docs/experiments.md).
REFERENCE_CORES = 2

_ONE_ROBOT = frozenset({'single', 'single_mujoco', 'study_drift'})
_TWO_ROBOTS = frozenset({'pair', 'pair_mujoco', 'p6', 'study_pair', 'study_collision'})
_N_ROBOTS = frozenset({'dense', 'c2_harvest', 'study_dense'})


def _step_factor(params: Mapping[str, Any], default: float, mujoco: bool) -> float:
    """The shipped time step over the trial's (a finer step costs more, in proportion)."""
    settings = params.get('mujoco' if mujoco else 'physics') or {}
    step = settings.get('time_step', (params.get('settings') or {}).get('time_step', default))
    return default / float(step) if step else 1.0


def trial_cpu_seconds(kind: str, params: Mapping[str, Any]) -> float | None:
    """The CPU seconds one trial of ``kind`` with the merged ``params`` takes by the cost model (None: no estimate)."""
    if kind == 'study_impact':
        return IMPACT_TRIAL_S * float(params.get('phases', 16)) / 16.0
    if kind == 'accuracy':
        step = PhysicsConfig().time_step * float(params['rate_hz'])
        robot_s = (2.0 * float(params['periods']) + float(params['single_periods'])) * GAIT_PERIOD
        return robot_s * step / BULLET_SPEED
    if kind in _ONE_ROBOT:
        robots = 1
    elif kind in _TWO_ROBOTS:
        robots = 2
    elif kind in _N_ROBOTS:
        robots = int(params['robots'])
    else:
        return None
    mujoco = kind.endswith('_mujoco')
    default = MujocoSettings().time_step if mujoco else PhysicsConfig().time_step
    robot_s = robots * float(params['periods']) * GAIT_PERIOD
    return robot_s * _step_factor(params, default, mujoco) / (MUJOCO_SPEED if mujoco else BULLET_SPEED)


def spec_cpu_seconds(spec: ExperimentSpec) -> tuple[float, float] | None:
    """The CPU seconds of all of ``spec``'s trials and of its longest one, or None if a trial has no estimate."""
    total, longest = 0.0, 0.0
    for point in spec.points():
        cost = trial_cpu_seconds(spec.kind, apply_point(spec.base, point))
        if cost is None:
            return None
        total += cost * len(spec.seeds)
        longest = max(longest, cost)
    return total, longest


def run_seconds(spec: ExperimentSpec, cores: int = REFERENCE_CORES, trials: int | None = None) -> float | None:
    """The wall seconds ``spec`` takes on ``cores`` cores by the cost model (``trials`` of its trials, default
    all; their share of the whole), or None."""
    cost = spec_cpu_seconds(spec)
    if cost is None:
        return None
    total, longest = cost
    everything = len(spec.points()) * len(spec.seeds)
    share = 1.0 if trials is None else trials / everything
    return 0.0 if share == 0 else max(total * share / max(cores, 1), longest)


def duration_text(seconds: float | None) -> str:
    """A run time as people say it: '40 s', '12 min', '1.3 h', '2.1 days'; 'unknown' for None."""
    if seconds is None:
        return 'unknown'
    if seconds < 60:
        return f'{max(seconds, 1):.0f} s'
    if seconds < 3600:
        return f'{seconds / 60:.0f} min'
    if seconds < 48 * 3600:
        return f'{seconds / 3600:.1f} h'
    return f'{seconds / 86400:.1f} days'
