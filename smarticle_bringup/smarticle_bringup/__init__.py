"""How the smarticle stack is started: the sim-in-the-loop demo and the tools that join packages.

This package sits on top of the others (it imports the sim, tracking, feedback and bags packages and
nothing imports it): ``demo`` runs the whole stack in separate processes; ``sim_camera`` calibrates the
overhead tracker against the simulated camera.
"""

from __future__ import annotations

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'BringupError': 'errors',
    'LaunchFileError': 'launch_files',
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
