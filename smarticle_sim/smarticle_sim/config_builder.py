"""The one builder of a run's SimConfig: a robot preset, overrides, noise and the engine that runs it.

``build_config(preset, physics, robot, noise, diagnostics, engine)`` is how every caller makes a SimConfig:
the sim CLI, the sim bridge, the experiments (``configs.make_config``), the demo and the Chrono reference.
The names are the same everywhere: ``physics`` overrides ``PhysicsConfig`` fields, ``robot`` the preset's
``RobotSpec`` fields, ``noise`` sets ``NoiseConfig`` fields, ``diagnostics`` the knobs measured and not taken
(``diagnostics.Diagnostics``) and ``engine`` names the engine (``bullet``, ``mujoco`` or ``chrono``), which
refuses the diagnostics and noise it does not build. A name that is no field raises ConfigError naming it and
the known ones; a bad value raises the field's own ConfigError.

``preset`` is a robot preset's name or the path of a preset file (YAML, written by ``smarticle-calibrate``):
``preset:`` a base preset's name, ``physics:`` and ``robot:`` overrides of the same names, and any other
top-level mapping (``calibration:``, the file's provenance) ignored. The overrides given to ``build_config``
apply on top of the file's.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from smarticle_common.errors import RobotSpecError
from smarticle_common.facts import PRESETS, RobotSpec, robot_preset

from .diagnostics import Diagnostics
from .engine import ENGINE_NAMES
from .errors import ConfigError
from .settings import NoiseConfig, PhysicsConfig, SimConfig

#: The field names each group of ``build_config`` accepts (a spec's ``physics:``, ``robot:``, ``noise:`` and
#: ``diagnostics:`` mappings use the same).
PHYSICS_FIELDS: frozenset[str] = frozenset(f.name for f in fields(PhysicsConfig))
ROBOT_FIELDS: frozenset[str] = frozenset(f.name for f in fields(RobotSpec)) - {'name'}
NOISE_FIELDS: frozenset[str] = frozenset(f.name for f in fields(NoiseConfig))
DIAGNOSTIC_FIELDS: frozenset[str] = frozenset(f.name for f in fields(Diagnostics))
#: The engines a SimConfig can be built for: the engine interface's and the Chrono reference.
CONFIG_ENGINES: tuple[str, ...] = (*ENGINE_NAMES, 'chrono')

_GROUPS = {'physics': ('PhysicsConfig', PHYSICS_FIELDS), 'robot': ('RobotSpec', ROBOT_FIELDS),
           'noise': ('NoiseConfig', NOISE_FIELDS), 'diagnostics': ('Diagnostics', DIAGNOSTIC_FIELDS)}


class UnknownSettingError(ConfigError):
    """A name given to ``build_config`` that is no field of its group."""


def check_names(group: str, names: Mapping[str, Any] | None) -> None:
    """Raise UnknownSettingError if a name of ``names`` is no field of ``group`` (physics, robot, noise or
    diagnostics); the message names it and the known ones."""
    cls_name, known = _GROUPS[group]
    unknown = sorted(set(names or ()) - known)
    if unknown:
        raise UnknownSettingError(f'{group}.{unknown[0]} is not a {cls_name} field; '
                                  f'known: {", ".join(sorted(known))}')


def noise_config(noise: NoiseConfig | Mapping[str, Any] | str | None) -> NoiseConfig:
    """The NoiseConfig of ``noise``: 'paper' (the cited figures), 'none' / None (off), a NoiseConfig, or a
    mapping of NoiseConfig fields (the sources not named are off)."""
    if isinstance(noise, NoiseConfig):
        return noise
    if noise is None or noise == 'none':
        return NoiseConfig.none()
    if noise == 'paper':
        return NoiseConfig.paper()
    if not isinstance(noise, Mapping):
        raise ConfigError(f"noise must be 'paper', 'none' or a mapping of NoiseConfig fields, got {noise!r}")
    check_names('noise', noise)
    return replace(NoiseConfig.none(), **noise)


#: The keys of a preset file that set something (others, such as ``calibration:``, are its provenance).
PRESET_FILE_KEYS: tuple[str, ...] = ('preset', 'physics', 'robot')


def is_preset_file(preset: str | Path) -> bool:
    """True if ``preset`` names a preset file (a path ending in .yaml or .yml), not a preset name."""
    return Path(str(preset)).suffix.lower() in ('.yaml', '.yml')


def read_preset_file(path: str | Path) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """(base preset name, physics overrides, robot overrides) of a preset file; ConfigError on bad input."""
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding='utf-8'))
    except OSError as err:
        raise ConfigError(f'preset file {path}: cannot be read ({err.strerror or err})') from None
    except yaml.YAMLError as err:
        raise ConfigError(f'preset file {path}: not YAML ({str(err).splitlines()[0]})') from None
    if not isinstance(data, Mapping):
        raise ConfigError(f'preset file {path}: must be a mapping with preset, physics and robot keys')
    base = data.get('preset', 'small')
    if not isinstance(base, str) or is_preset_file(base):
        raise ConfigError(f'preset file {path}: preset must be a robot preset name, got {base!r}')
    groups = []
    for key in ('physics', 'robot'):
        group = data.get(key) or {}
        if not isinstance(group, Mapping):
            raise ConfigError(f'preset file {path}: {key} must be a mapping of field: value')
        try:
            check_names(key, group)
        except ConfigError as err:
            raise ConfigError(f'preset file {path}: {err}') from None
        groups.append(dict(group))
    return base, groups[0], groups[1]


def build_config(preset: str = 'small', physics: Mapping[str, Any] | None = None,
                 robot: Mapping[str, Any] | None = None,
                 noise: NoiseConfig | Mapping[str, Any] | str | None = None,
                 diagnostics: Mapping[str, Any] | None = None, engine: str = 'bullet') -> SimConfig:
    """The SimConfig of robot ``preset`` with PhysicsConfig / RobotSpec overrides, the noise of ``noise``
    (``noise_config``) and ``diagnostics`` (Diagnostics fields), checked for ``engine``. ``preset`` may be
    a preset file (``read_preset_file``): its overrides apply first, ``physics`` and ``robot`` on top."""
    if is_preset_file(preset):
        preset, file_physics, file_robot = read_preset_file(preset)
        physics = {**file_physics, **dict(physics or {})}
        robot = {**file_robot, **dict(robot or {})}
    check_names('physics', physics)
    check_names('robot', robot)
    check_names('diagnostics', diagnostics)
    if engine not in CONFIG_ENGINES:
        raise ConfigError(f'unknown engine {engine!r}: one of {", ".join(CONFIG_ENGINES)}')
    if str(preset) not in PRESETS:
        raise ConfigError(f'robot preset {str(preset)!r} is unknown: one of {", ".join(sorted(PRESETS))}, or a '
                          'preset file (a .yaml or .yml path)')
    try:
        spec = replace(robot_preset(str(preset)), **dict(robot or {}))
    except RobotSpecError as err:
        raise ConfigError(str(err)) from None
    extra = Diagnostics(**dict(diagnostics or {}))
    extra.check_engine(engine)
    noise_settings = noise_config(noise)
    if engine == 'chrono' and noise_settings.enabled:
        raise ConfigError('noise: the Chrono reference has no noise sources')
    return SimConfig(spec, replace(PhysicsConfig(), **dict(physics or {})), noise_settings, extra)
