"""The PyBullet simulation of smarticles: settings, scenes, the physics world, the one stepping loop (``Runner``)."""

from __future__ import annotations

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'SimConfig': 'settings', 'PhysicsConfig': 'settings', 'NoiseConfig': 'settings',
    'NotConvergedWarning': 'settings',
    'Scene': 'scenes', 'RobotPlacement': 'scenes', 'dense_scene': 'scenes', 'pair_scene': 'scenes',
    'random_scene': 'scenes',
    'Runner': 'runner', 'GaitController': 'runner', 'FeedbackController': 'runner',
    'Physics': 'physics', 'PhysicsState': 'physics',
    'run_trial': 'batch',
    'SimError': 'errors', 'ConfigError': 'errors', 'SceneError': 'errors', 'SimTrouble': 'errors',
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
