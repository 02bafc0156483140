"""The cost model of a trial: robot-seconds simulated per CPU second by each engine at its shipped time step,
measured on the 2-core development machine (docs/experiments.md, "Run time estimates"; ``estimate`` adds up a
spec's trials). Each kind states its trials' cost with these (``TrialKind.cost``).

* Bullet: ``BULLET_SPEED`` = 55 (a pair 47, a lone robot 57, 7 dense robots 61, a P6 pair of feedback robots
  65; P1's 7 robots x 480 s take about 60 s, P4's pairs 4.4 s of CPU each);
* MuJoCo at 1/9600 s: ``MUJOCO_SPEED`` = 11;
* a finer time step than the shipped one costs in proportion (1/1920 s: twice 1/960 s), a coarser one saves in
  proportion; solver iterations and recording options are not in the model.
"""

from __future__ import annotations

from smarticle_common.facts import GAIT_PERIOD
from smarticle_sim.mujoco_engine import MujocoSettings
from smarticle_sim.settings import PhysicsConfig

#: Robot-seconds simulated per CPU second by Bullet at the shipped time step (see the module docstring).
BULLET_SPEED = 55.0
#: Robot-seconds simulated per CPU second by MuJoCo at its shipped time step (1/9600 s).
MUJOCO_SPEED = 11.0
#: CPU seconds of one ``study_impact`` trial of 16 meeting points (two bodies, a fraction of a second each).
IMPACT_TRIAL_S = 0.1


def sim_cpu_seconds(robots: int, periods: float, engine: str = 'bullet', time_step: float | None = None) -> float:
    """CPU seconds of ``robots`` robots simulated for ``periods`` gait periods by ``engine`` ('bullet' or
    'mujoco') at ``time_step`` (None: the engine's shipped step)."""
    mujoco = engine == 'mujoco'
    default = MujocoSettings().time_step if mujoco else PhysicsConfig().time_step
    factor = default / float(time_step) if time_step else 1.0
    return robots * float(periods) * GAIT_PERIOD * factor / (MUJOCO_SPEED if mujoco else BULLET_SPEED)
