"""Frozen, validated settings of the smarticle simulation: physics knobs and the robot they simulate.

Lengths in metres, masses in kilograms, angles in radians, times in seconds (SI inside). The robots
themselves (``RobotSpec``, the presets ``SMALL`` and ``FEEDBACK``) are facts of ``smarticle_common.facts``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from smarticle_common.errors import SpecError
from smarticle_common.facts import SMALL, RobotSpec, require_non_negative, require_positive, robot_preset

from .errors import ConfigError


@dataclass(frozen=True)
class PhysicsConfig:
    """PyBullet settings: stepping, solver, contact and servo-loop knobs, trouble bounds."""

    time_step: float = 1.0 / 240.0
    control_tick: float = 1.0 / 60.0            # must be a whole number of time steps
    solver_iterations: int = 10
    contact_breaking_threshold: float = 0.002   # m; Bullet's default 0.02 is far larger than the robots' gaps
    gravity: float = 9.81
    friction_body_plate: float = 0.35           # body on aluminium
    friction_robot_robot: float = 0.30          # printed plastic on plastic (arm-body; all pairs if the next is None)
    #: Arm-arm friction. None: every robot-robot pair uses friction_robot_robot. A number: arm-arm uses it,
    #: arm-body keeps friction_robot_robot, and body-body becomes friction_robot_robot**2 / friction_arm_arm
    #: (Bullet multiplies the two links' coefficients, so three pairs have only two free values). The high
    #: default stands in for the arm edges and horns that hook on the real robots (flat boxes here): it is
    #: what makes a C1 pair hold together near phi = 180 deg and glide (docs/sim_calibration.md, fourth pass).
    friction_arm_arm: float | None = 1.5
    restitution: float = 0.0
    position_gain: float = 0.3                  # servo loop: velocity = gain * error / time_step, clamped
    plate_size: float = 0.60                    # square plate side (m), centred on the origin
    plate_thickness: float = 0.01
    arm_plate_collision: bool = False           # arms have clearance; the pair is filtered out
    max_tilt: float = math.radians(25.0)        # trouble: body z axis tilted beyond this
    max_speed: float = 2.0                      # trouble: body speed (m/s)
    #: Bullet's contact error reduction: the fraction of an overlap pushed out per step. With Bullet's
    #: default (0.2) servo-driven arms wedge 4-12 mm into dense clusters for up to 0.7 s; 0.6 keeps the 99th
    #: percentile of the deepest overlap near 1 mm (docs/sim_calibration.md, fourth pass).
    contact_erp: float = 0.6
    max_penetration: float = 0.004              # trouble: contact overlap (m) ...
    penetration_checks: int = 3                 # ... at this many trouble checks in a row (a spike is not a tunnel)
    trouble_every: int = 6                      # check for trouble every n control ticks
    # --- issue #11 knobs (docs/physics_study.md); each default keeps the behaviour above unchanged ---
    #: Servo loop bandwidth (1/s). None: the loop gain is ``position_gain`` per step, so the servo's final
    #: approach (time constant time_step / position_gain) shrinks with the step. A number: the gain per step
    #: is min(1, servo_bandwidth * time_step), the same approach at every step (0.3 / (1/240 s) = 72 /s).
    servo_bandwidth: float | None = None
    #: Bullet's restitutionVelocityThreshold (m/s): contacts approaching slower get no restitution. None:
    #: Bullet's default (0.2 m/s); most arm impacts here are faster, so restitution acts either way.
    restitution_velocity_threshold: float | None = None
    #: Body-plate restitution. None: the same as ``restitution`` (robot-robot).
    restitution_body_plate: float | None = None
    #: Bullet's continuous collision detection: swept-sphere radius (m) on every robot link; 0 = off.
    ccd_swept_sphere_radius: float = 0.0
    #: Factor on the body's roll and pitch inertia (mass, yaw inertia and contacts unchanged): robots that
    #: stay flat on the plate, as the real ones do. 1 = the box's own inertia.
    tilt_inertia_scale: float = 1.0

    def __post_init__(self) -> None:
        require_positive(self, 'time_step', 'control_tick', 'plate_size', 'plate_thickness', 'max_tilt',
                  'max_speed', 'max_penetration', 'position_gain', 'contact_breaking_threshold', 'contact_erp',
                         error=ConfigError)
        require_non_negative(self, 'gravity', 'friction_body_plate', 'friction_robot_robot', 'restitution',
                             error=ConfigError)
        if self.contact_erp > 1.0:
            raise ConfigError(f'PhysicsConfig.contact_erp must be in (0, 1], got {self.contact_erp}')
        for name in ('solver_iterations', 'trouble_every', 'penetration_checks'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f'PhysicsConfig.{name} must be an integer >= 1, got {value!r}')
        if self.friction_arm_arm is not None:
            require_positive(self, 'friction_arm_arm', error=ConfigError)
        for name in ('servo_bandwidth',):
            if getattr(self, name) is not None:
                require_positive(self, name, error=ConfigError)
        for name in ('restitution_velocity_threshold', 'restitution_body_plate'):
            if getattr(self, name) is not None:
                require_non_negative(self, name, error=ConfigError)
        require_non_negative(self, 'ccd_swept_sphere_radius', error=ConfigError)
        require_positive(self, 'tilt_inertia_scale', error=ConfigError)
        if self.restitution_body_plate is not None and self.restitution_body_plate > 1.0:
            raise ConfigError(f'PhysicsConfig.restitution_body_plate must be in [0, 1], '
                              f'got {self.restitution_body_plate}')
        if self.link_frictions()[2] > 10.0:
            raise ConfigError(f'PhysicsConfig.friction_arm_arm: {self.friction_arm_arm} with friction_robot_robot '
                              f'{self.friction_robot_robot} leaves too little body friction to reach '
                              f'friction_body_plate {self.friction_body_plate} (plate value above 10)')
        if self.restitution > 1.0:
            raise ConfigError(f'PhysicsConfig.restitution must be in [0, 1], got {self.restitution}')
        if self.position_gain > 1.0:
            raise ConfigError(f'PhysicsConfig.position_gain must be in (0, 1], got {self.position_gain}')
        steps_per_tick(self.control_tick, self.time_step)

    @property
    def steps_per_tick(self) -> int:
        """Physics steps in one control tick."""
        return steps_per_tick(self.control_tick, self.time_step)

    def servo_gain(self) -> float:
        """The servo loop's position gain per step given to Bullet (see ``servo_bandwidth``)."""
        if self.servo_bandwidth is None:
            return self.position_gain
        return min(1.0, self.servo_bandwidth * self.time_step)

    def link_frictions(self) -> tuple[float, float, float]:
        """Return the (arm link, body link, plate) lateral friction values given to Bullet.

        Bullet's contact friction is the product of the two colliding links' values, so these give
        arm-arm = friction_arm_arm (or friction_robot_robot), arm-body = friction_robot_robot and
        body-plate = friction_body_plate. Arms never touch the plate (arm_plate_collision False).
        """
        arm_arm = self.friction_robot_robot if self.friction_arm_arm is None else self.friction_arm_arm
        arm = math.sqrt(arm_arm)
        body = self.friction_robot_robot / arm if arm > 0.0 else 0.0
        plate = self.friction_body_plate / body if body > 0.0 else 0.0
        return arm, body, plate


def steps_per_tick(control_tick: float, time_step: float) -> int:
    """Return control_tick / time_step, or raise ConfigError (a ValueError) if not a whole number >= 1."""
    ratio = control_tick / time_step
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-6 * max(1.0, ratio):
        raise ConfigError(f'PhysicsConfig.control_tick: {control_tick!r} s is not a whole number of '
                          f'time steps of {time_step!r} s ({ratio:.6g} steps)')
    return n


@dataclass(frozen=True)
class SimConfig:
    """Everything a Physics needs besides the scene: the robot spec and the physics settings."""

    robot: RobotSpec = SMALL
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)

    @classmethod
    def from_preset(cls, preset: str = 'small', **physics: Any) -> SimConfig:
        """Build a config from a robot preset name and PhysicsConfig overrides."""
        known = {f.name for f in fields(PhysicsConfig)}
        unknown = sorted(set(physics) - known)
        if unknown:
            raise ConfigError(f'unknown PhysicsConfig field(s) {", ".join(unknown)}; '
                              f'known: {", ".join(sorted(known))}')
        try:
            robot = robot_preset(preset)
        except SpecError as err:
            raise ConfigError(str(err)) from None
        return cls(robot, PhysicsConfig(**physics))

    def with_physics(self, **changes: Any) -> SimConfig:
        """Return a copy with some PhysicsConfig fields changed (validated)."""
        return replace(self, physics=replace(self.physics, **changes))
