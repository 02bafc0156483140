"""Impact-halt feedback from the FSRs: the controller core, its parameters, collision records and calibration."""

from __future__ import annotations

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'FeedbackConfig': 'controller', 'ImpactController': 'controller', 'ImpactWindow': 'controller',
    'check_sample': 'controller',
    'CollisionRecord': 'collisions', 'find_events': 'collisions', 'signature': 'collisions',
    'FeedbackError': 'errors', 'FeedbackConfigError': 'errors', 'FsrSampleError': 'errors',
    'CalibrationInputError': 'errors',
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
