"""The parameters the simulated trial kinds share: the engine, a robot preset with overrides, a gait, the glider
rules.

Each is a frozen ``kind.KindParams`` dataclass (a kind's parameters derive from one); constructing one
validates it: the engine and its settings, the SimConfig it makes (``configs.make_config``) and its gait.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

from smarticle_common.gait import GaitConfig
from smarticle_sim.engine import EngineFactory
from smarticle_sim.engines import engine_factory
from smarticle_sim.errors import SimError
from smarticle_sim.mujoco_engine import MujocoSettings
from smarticle_sim.settings import SimConfig

from .configs import DIAGNOSTIC_FIELDS, NOISE_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS, make_config, make_gait
from .kind import OMIT_DEFAULT, KindParams, optional

#: The engines a simulated kind can run on (``smarticle_sim.engines``).
SIM_ENGINES: tuple[str, ...] = ('bullet', 'mujoco')
#: MujocoSettings field names (a spec's ``mujoco: {...}`` or grid keys ``mujoco.X``).
MUJOCO_FIELDS: frozenset[str] = frozenset(f.name for f in fields(MujocoSettings))


@dataclass(frozen=True)
class EngineParams(KindParams):
    """The engine a simulated trial runs on, Bullet or MuJoCo (``mujoco`` sets ``MujocoSettings`` fields).

    Both are left out of the stored mapping while they hold their defaults (Bullet, no MuJoCo settings), so a
    Bullet trial's key is the one it had before kinds took an engine, and a MuJoCo trial never shares a key with
    a Bullet one.
    """

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {'mujoco': MUJOCO_FIELDS}
    #: The engines these parameters can name.
    ENGINES: ClassVar[tuple[str, ...]] = SIM_ENGINES

    engine: str = field(default='bullet', metadata=OMIT_DEFAULT)
    mujoco: Mapping[str, Any] = field(default_factory=dict, metadata=OMIT_DEFAULT)

    def mujoco_settings(self) -> MujocoSettings | None:
        """MuJoCo's settings of a MuJoCo trial (None: a Bullet trial)."""
        return MujocoSettings(**dict(self.mujoco or {})) if self.engine == 'mujoco' else None

    def engine_factory(self) -> EngineFactory:
        """The factory of the trial's engine (``smarticle_sim.engines.engine_factory``)."""
        return engine_factory(str(self.engine), self.mujoco_settings())

    def engine_time_step(self, physics: Mapping[str, Any] | None) -> float | None:
        """The time step the trial's engine steps at if the spec sets one (None: the engine's shipped step):
        MuJoCo's from ``mujoco``, Bullet's from the PhysicsConfig overrides ``physics``."""
        if self.engine == 'mujoco':
            return dict(self.mujoco or {}).get('time_step')
        return dict(physics or {}).get('time_step')

    def check(self) -> None:
        """A known engine; MuJoCo settings only for MuJoCo, and valid ones."""
        if self.engine not in self.ENGINES:
            raise ValueError(f'engine must be one of {", ".join(self.ENGINES)}, got {self.engine!r}')
        if self.mujoco and self.engine != 'mujoco':
            raise ValueError(f'mujoco settings ({", ".join(sorted(self.mujoco))}) need engine: mujoco, '
                             f'the trial runs on {self.engine}')
        try:
            self.mujoco_settings()
        except SimError as exc:
            raise ValueError(str(exc)) from None
        except TypeError as exc:
            raise ValueError(f'mujoco: {exc}') from None


@dataclass(frozen=True)
class SimParams(EngineParams):
    """A robot preset with PhysicsConfig / RobotSpec overrides and noise sources, a square gait, a run length."""

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {'physics': PHYSICS_FIELDS, 'robot': ROBOT_FIELDS,
                                                      'noise': NOISE_FIELDS, 'diagnostics': DIAGNOSTIC_FIELDS,
                                                      **EngineParams.GROUPS}

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
                           dict(self.noise or {}), dict(self.diagnostics or {}), str(self.engine))

    def gait(self, config: SimConfig) -> GaitConfig:
        """The trial's square gait on ``config``'s robot."""
        return make_gait(config, self.alpha_max_deg, self.servo_speed)

    def time_step(self) -> float | None:
        """The time step of the trial's engine the spec sets (None: the engine's shipped one)."""
        return self.engine_time_step(self.physics)

    def check(self) -> None:
        """A valid engine, SimConfig and gait."""
        super().check()
        self.gait(self.config())


@dataclass(frozen=True)
class GliderParams(SimParams):
    """``SimParams`` and the glider analysis's rules (docs/gliders.md)."""

    min_periods: int = 30            # shortest glider (bound periods in a row)
    r_bind_bl: float = 1.6           # bound: r under this in any frame of a period (BL)
    isolation_w: float = 2.0         # isolated: no third robot within this of either robot (W)
    positive_periods: int = 100      # P1 counts trials with an isolated glider of at least this
    trajectory: bool = True          # store the body centres once per period
