"""How long a spec's trials take, from a stated cost model (``list`` prints it, ``run`` says it before it starts).

A trial costs what its kind states (``TrialKind.cost``): about its robots x its simulated seconds / the
engine's speed in CPU seconds at the engine's shipped time step, a finer step in proportion
(``cost_model``: Bullet ``BULLET_SPEED`` = 55 robot-seconds per CPU second, MuJoCo at 1/9600 s
``MUJOCO_SPEED`` = 11; docs/experiments.md, "Run time estimates").

A spec's trials share the cores, one trial per core at a time: its run time is about the sum over its
trials / cores, and never less than its longest trial. Chrono kinds and a user's ``module:function`` kinds
have no estimate (None).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .cost_model import BULLET_SPEED, IMPACT_TRIAL_S, MUJOCO_SPEED
from .kinds import KINDS
from .spec import ExperimentSpec, apply_point

__all__ = ['BULLET_SPEED', 'IMPACT_TRIAL_S', 'MUJOCO_SPEED', 'REFERENCE_CORES', 'duration_text', 'run_seconds',
           'spec_cpu_seconds', 'trial_cpu_seconds']

#: The cores ``list`` and ``run`` quote the estimate for: the development machine's (docs/experiments.md).
REFERENCE_CORES = 2


def trial_cpu_seconds(kind: str, params: Mapping[str, Any]) -> float | None:
    """The CPU seconds one trial of ``kind`` with the merged ``params`` takes by the cost model (None: no estimate)."""
    known = KINDS.get(kind)
    return None if known is None else known.cpu_seconds(params)


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
