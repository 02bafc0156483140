"""The engine interface: what the one ``Runner`` needs of a physics engine (dm_control's abstract ``Physics``).

A run's physics is a world of smarticles on a plate built from a ``SimConfig`` and a ``Scene``. The runner
(``runner.Runner``), its controllers (gait, feedback, contact watchers) and the batch trial
(``batch.run_trial``) talk to it only through ``Engine``: step it, read its time and ground truth
(poses, arm angles, ``PhysicsState``), send servo commands, read contacts and the normal force on each FSR
face (``FSR_FACES`` order), set the plate's friction field, check for trouble, close it. Two engines
implement it: PyBullet (``physics.Physics``, the simulation of this project) and MuJoCo
(``mujoco_engine.MujocoPhysics``, the cross-check); ``engines.engine_factory`` picks one by name.

A *step* is the engine's unit of time behind a control tick (``steps_per_tick`` of them); step hooks of the
runner (FSR peak hold, contact watchers) see every one. The FSR reading averages ``fsr_steps`` steps.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from smarticle_common.topics import FSR_FACES

from .errors import SceneError
from .noise import FrictionField
from .scenes import Scene
from .settings import SimConfig

#: The engines by name (``engines.engine_factory``).
ENGINE_NAMES: tuple[str, ...] = ('bullet', 'mujoco')


@dataclass(frozen=True)
class PhysicsState:
    """Ground truth of all robots at one instant (arrays indexed by robot id)."""

    time: float
    poses: np.ndarray           # (N, 3): x (m), y (m), heading of the body normal (rad, [-pi, pi))
    positions: np.ndarray       # (N, 3): body centre x, y, z (m)
    tilt: np.ndarray            # (N,): angle between the body z axis and the vertical (rad)
    speed: np.ndarray           # (N,): body centre speed (m/s)
    arm_angles: np.ndarray      # (N, 2): alpha1, alpha2 (rad)
    arm_velocities: np.ndarray  # (N, 2): d alpha / dt (rad/s)


class Engine(Protocol):
    """A world of smarticles that the ``Runner`` steps: the methods every engine implements."""

    config: SimConfig
    scene: Scene
    #: The plate's friction field (``NoiseConfig.friction_sd`` > 0), or None: uniform friction.
    friction_field: FrictionField | None
    #: The largest body tilt (rad) and deepest contact overlap (m) seen at the trouble checks so far.
    peak_tilt: float
    peak_overlap: float

    @property
    def n_robots(self) -> int:
        """Number of robots."""

    @property
    def time(self) -> float:
        """Simulated time since the world was built (s)."""

    @property
    def steps_per_tick(self) -> int:
        """Steps per control tick."""

    @property
    def fsr_steps(self) -> int:
        """Steps the FSR reading averages over (``PhysicsConfig.fsr_window``)."""

    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps."""

    def ticks_for(self, seconds: float) -> int:
        """Number of control ticks in ``seconds`` of sim time (rounded)."""

    def state(self) -> PhysicsState:
        """Ground truth of all robots now."""

    def poses(self) -> np.ndarray:
        """(N, 3) x, y (m) and heading of the body normal (rad)."""

    def arm_angles(self) -> np.ndarray:
        """(N, 2) arm angles alpha1, alpha2 (rad)."""

    def body_xy(self) -> np.ndarray:
        """(N, 2) body centre x, y (m)."""

    def send(self, k: int, targets: tuple[float, float], speed: float) -> None:
        """Send robot ``k``'s servo targets (rad) and speed limit (rad/s), unchecked."""

    def command(self, robot: int, targets: tuple[float, float], speed: float | None = None) -> None:
        """Command ``robot``'s servos, checked."""

    def fsr(self, robots: Sequence[int] | None = None) -> np.ndarray:
        """(len(robots), 4) normal force (N) on each FSR face now."""

    def fsr_of(self, robots: list[int]) -> np.ndarray:
        """``fsr`` of robots already checked (called every step by ``FsrReading``)."""

    def robot_contacts(self) -> np.ndarray:
        """(N, N) symmetric bool: True where two robots touch now."""

    def touching(self, max_distance: float = 0.0) -> set[tuple[int, int]]:
        """Pairs (i, j), i < j, of robots with a contact point at distance <= ``max_distance`` (m) now."""

    def max_penetration(self) -> tuple[int, float]:
        """(robot, depth in m) of the deepest contact overlap now; (-1, 0.0) without contacts."""

    def update_plate_friction(self) -> int:
        """Set each body's friction from the friction field; return the bodies changed."""

    def check_trouble(self) -> None:
        """Raise SimTrouble if a robot is not finite, off the plate, flipped, too fast or tunnelling."""

    def check_robot(self, robot: int) -> int:
        """Return ``robot`` as an index or raise SceneError."""

    def robot_list(self, robots: Sequence[int] | None) -> list[int]:
        """All robots, or the given ones checked."""

    def run_meta(self) -> dict[str, Any]:
        """What a recording's meta says of the engine (empty for Bullet, the default engine)."""

    def close(self) -> None:
        """Release the engine (idempotent)."""



class FsrReading:
    """The sim's FSR reading of some robots, step by step: each face's force averaged over the physics steps
    of ``PhysicsConfig.fsr_window`` (``fsr_steps``), so an impulsive kick reads the same at every time step.

    Call ``step()`` once after every physics step; with ``fsr_steps`` = 1 it is ``Physics.fsr`` itself.
    ``take_peak()`` gives each face's largest reading since the previous take: the FSR sample of a control
    tick (collision kicks are shorter than a tick), on the batch feedback path and in the sim bridge alike.
    """

    def __init__(self, physics: Engine, robots: Sequence[int] | None = None) -> None:
        self.physics = physics
        self.robots = physics.robot_list(robots)
        self.steps = physics.fsr_steps
        self._history = np.zeros((self.steps, len(self.robots), len(FSR_FACES)))
        self._next = 0
        self._peak: np.ndarray | None = None

    def step(self) -> np.ndarray:
        """(len(robots), 4) reading after the step just taken: the mean force of the last ``steps`` steps."""
        forces = self.physics.fsr_of(self.robots)   # the robots were checked once, in the constructor
        if self.steps > 1:
            self._history[self._next] = forces
            self._next = (self._next + 1) % self.steps
            forces = self._history.sum(axis=0) / self.steps
        self._peak = forces if self._peak is None else np.maximum(self._peak, forces)
        return forces

    def take_peak(self) -> np.ndarray | None:
        """Each face's largest reading since the previous call (None: no step since), and start over."""
        peak, self._peak = self._peak, None
        return peak


def robot_index(robot: int, n_robots: int) -> int:
    """``robot`` as an index of a world of ``n_robots`` robots, or SceneError (``Engine.check_robot``)."""
    if isinstance(robot, bool) or not isinstance(robot, (int, np.integer)) or not 0 <= robot < n_robots:
        raise SceneError(f'unknown robot {robot!r}: this world has robots 0..{n_robots - 1}')
    return int(robot)


#: Builds an engine of a scene (``physics.Physics`` itself is one).
EngineFactory = Callable[[SimConfig, Scene], Engine]
