"""The engines by name: ``engine_factory('bullet')`` or ``engine_factory('mujoco', settings)`` builds worlds
behind the one engine interface (``engine.Engine``) for ``Runner.with_gaits`` and ``batch.run_trial``."""

from __future__ import annotations

from .engine import ENGINE_NAMES, EngineFactory
from .errors import ConfigError
from .mujoco_engine import MujocoSettings, mujoco_engine
from .physics import Physics


def engine_factory(name: str, mujoco: MujocoSettings | None = None) -> EngineFactory:
    """The factory of engine ``name`` (``ENGINE_NAMES``); ``mujoco`` sets MuJoCo's side (MuJoCo only)."""
    if name == 'bullet':
        if mujoco is not None:
            raise ConfigError('MujocoSettings are for the mujoco engine, not bullet')
        return Physics
    if name == 'mujoco':
        return mujoco_engine(mujoco)
    raise ConfigError(f'unknown engine {name!r}: one of {", ".join(ENGINE_NAMES)}')
