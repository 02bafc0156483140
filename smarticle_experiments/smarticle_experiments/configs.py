"""The one place a trial's SimConfig and gait are made from a spec's settings (every trial kind uses it).

``make_config(preset, physics, robot, noise)`` is the project's default SimConfig of a robot preset with
PhysicsConfig / RobotSpec field overrides and noise sources, validated; a name that is no field raises
SpecError naming it and the known ones.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any

from smarticle_common.gait import GaitConfig
from smarticle_sim.settings import NoiseConfig, PhysicsConfig, RobotSpec, SimConfig, robot_preset

from .errors import SpecError

#: PhysicsConfig and RobotSpec field names a spec may override (``physics:`` and ``robot:`` mappings).
PHYSICS_FIELDS: frozenset[str] = frozenset(f.name for f in fields(PhysicsConfig))
ROBOT_FIELDS: frozenset[str] = frozenset(f.name for f in fields(RobotSpec)) - {'name'}
#: NoiseConfig field names a spec may set (``noise:`` mapping; unset fields are off, ``NoiseConfig.none()``).
NOISE_FIELDS: frozenset[str] = frozenset(f.name for f in fields(NoiseConfig))


def noise_mapping(value: Any) -> dict[str, Any]:
    """A spec's ``noise:`` value as NoiseConfig overrides: 'paper' (the cited figures), 'none' / {} / None
    (off) or a mapping of NoiseConfig fields (the unset ones off). 'paper' is written out field by field,
    so the trial key records the values, not the name."""
    if value is None or value == 'none':
        return {}
    if value == 'paper':
        paper = NoiseConfig.paper()
        return {name: getattr(paper, name) for name in ('clock_rate_sd', 'servo_jitter', 'friction_sd',
                                                         'friction_length')}
    if not isinstance(value, Mapping):
        raise SpecError(f"noise must be 'paper', 'none' or a mapping of NoiseConfig fields, got {value!r}")
    unknown = sorted(set(value) - NOISE_FIELDS)
    if unknown:
        raise SpecError(f'noise.{unknown[0]} is not a NoiseConfig field; known: {", ".join(sorted(NOISE_FIELDS))}')
    return dict(value)


def make_config(preset: str, physics: Mapping[str, Any], robot: Mapping[str, Any],
                noise: Mapping[str, Any] | None = None) -> SimConfig:
    """The project's default SimConfig for ``preset`` with PhysicsConfig / RobotSpec overrides and the noise
    sources of ``noise`` (NoiseConfig fields; every source not named is off), all validated."""
    unknown = sorted(set(physics) - PHYSICS_FIELDS)
    if unknown:
        raise SpecError(f'physics.{unknown[0]} is not a PhysicsConfig field; '
                        f'known: {", ".join(sorted(PHYSICS_FIELDS))}')
    unknown = sorted(set(robot) - ROBOT_FIELDS)
    if unknown:
        raise SpecError(f'robot.{unknown[0]} is not a RobotSpec field; known: {", ".join(sorted(ROBOT_FIELDS))}')
    return SimConfig(replace(robot_preset(preset), **robot), replace(PhysicsConfig(), **physics),
                     replace(NoiseConfig.none(), **noise_mapping(noise)))


def make_gait(config: SimConfig, alpha_max_deg: float, servo_speed: float | None = None,
              phase: float = 0.0) -> GaitConfig:
    """The square gait at ``alpha_max_deg`` (servo speed: given, else the robot's)."""
    return GaitConfig.from_degrees(float(alpha_max_deg), servo_speed=servo_speed or config.robot.servo_speed,
                                   phase=phase)


def config_of(p: Mapping[str, Any]) -> SimConfig:
    """SimConfig of a trial's parameters."""
    return make_config(str(p['preset']), dict(p.get('physics') or {}), dict(p.get('robot') or {}),
                       dict(p.get('noise') or {}))


