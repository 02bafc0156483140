"""The parameters the simulated trial kinds share: a robot preset with overrides, a gait, the glider rules.

Each is a frozen ``kind.KindParams`` dataclass (a kind's parameters derive from one); constructing one
validates it: the SimConfig it makes (``configs.make_config``) and its gait.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from smarticle_common.gait import GaitConfig
from smarticle_sim.settings import SimConfig

from .configs import DIAGNOSTIC_FIELDS, NOISE_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS, make_config, make_gait
from .kind import KindParams, optional


@dataclass(frozen=True)
class SimParams(KindParams):
    """A robot preset with PhysicsConfig / RobotSpec overrides and noise sources, a square gait, a run length."""

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {'physics': PHYSICS_FIELDS, 'robot': ROBOT_FIELDS,
                                                      'noise': NOISE_FIELDS, 'diagnostics': DIAGNOSTIC_FIELDS}

    preset: str = 'small'                                           # robot preset (smarticle_sim.settings)
    physics: Mapping[str, Any] = field(default_factory=dict)        # PhysicsConfig field overrides
    robot: Mapping[str, Any] = field(default_factory=dict)          # RobotSpec field overrides
    periods: float = 300.0                                          # gait periods per trial
    alpha_max_deg: float = 90.0                                     # gait amplitude
    servo_speed: float | None = None                                # gait servo speed (rad/s; None: the robot's)
    #: NoiseConfig fields (the sources not named are off); None: no noise (left out of the stored mapping).
    noise: Mapping[str, Any] | None = optional()
    #: Diagnostics fields, knobs measured and not taken (smarticle_sim.diagnostics); None: the shipped model.
    diagnostics: Mapping[str, Any] | None = optional()

    def config(self) -> SimConfig:
        """The trial's SimConfig."""
        return make_config(str(self.preset), dict(self.physics or {}), dict(self.robot or {}),
                           dict(self.noise or {}), dict(self.diagnostics or {}))

    def gait(self, config: SimConfig) -> GaitConfig:
        """The trial's square gait on ``config``'s robot."""
        return make_gait(config, self.alpha_max_deg, self.servo_speed)

    def time_step(self) -> float | None:
        """The physics time step the spec sets (None: the shipped one)."""
        return dict(self.physics or {}).get('time_step')

    def check(self) -> None:
        """A valid SimConfig and gait."""
        self.gait(self.config())


@dataclass(frozen=True)
class GliderParams(SimParams):
    """``SimParams`` and the glider analysis's rules (docs/gliders.md)."""

    min_periods: int = 30            # shortest glider (bound periods in a row)
    r_bind_bl: float = 1.6           # bound: r under this in any frame of a period (BL)
    isolation_w: float = 2.0         # isolated: no third robot within this of either robot (W)
    positive_periods: int = 100      # P1 counts trials with an isolated glider of at least this
    trajectory: bool = True          # store the body centres once per period
