"""A trial's SimConfig and gait from a spec's settings (every trial kind uses it), through the one builder.

``make_config(preset, physics, robot, noise, diagnostics, engine)`` is ``smarticle_sim.config_builder.
build_config`` with a spec's names and errors: a name that is no field raises SpecError naming it and the
known ones.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from smarticle_common.gait import GaitConfig
from smarticle_sim.config_builder import (DIAGNOSTIC_FIELDS, NOISE_FIELDS, PHYSICS_FIELDS, ROBOT_FIELDS,
                                          UnknownSettingError, build_config, check_names)
from smarticle_sim.settings import NoiseConfig, SimConfig

from .errors import SpecError

__all__ = ['DIAGNOSTIC_FIELDS', 'NOISE_FIELDS', 'PHYSICS_FIELDS', 'ROBOT_FIELDS', 'config_of', 'make_config',
           'make_gait', 'noise_mapping']


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
    try:
        check_names('noise', value)
    except UnknownSettingError as err:
        raise SpecError(str(err)) from None
    return dict(value)


def make_config(preset: str, physics: Mapping[str, Any], robot: Mapping[str, Any],
                noise: Mapping[str, Any] | None = None, diagnostics: Mapping[str, Any] | None = None,
                engine: str = 'bullet') -> SimConfig:
    """``build_config`` of a spec's settings: ``preset`` with PhysicsConfig / RobotSpec overrides, the noise
    sources of ``noise`` (NoiseConfig fields; every source not named is off) and ``diagnostics``, for
    ``engine``, all validated."""
    try:
        return build_config(preset, physics, robot, noise_mapping(noise), diagnostics, engine)
    except UnknownSettingError as err:
        raise SpecError(str(err)) from None


def make_gait(config: SimConfig, alpha_max_deg: float, servo_speed: float | None = None,
              phase: float = 0.0) -> GaitConfig:
    """The square gait at ``alpha_max_deg`` (servo speed: given, else the robot's)."""
    return GaitConfig.from_degrees(float(alpha_max_deg), servo_speed=servo_speed or config.robot.servo_speed,
                                   phase=phase)


def config_of(p: Mapping[str, Any]) -> SimConfig:
    """SimConfig of a trial's parameters."""
    return make_config(str(p['preset']), dict(p.get('physics') or {}), dict(p.get('robot') or {}),
                       dict(p.get('noise') or {}), dict(p.get('diagnostics') or {}))
