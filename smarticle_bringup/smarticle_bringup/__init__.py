"""How the smarticle stack is started: the sim-in-the-loop demo and the tools that join packages.

This package sits on top of the others (it imports the sim, tracking, feedback and bags packages and
nothing imports it): ``demo`` runs the whole stack in separate processes; ``sim_camera`` calibrates the
overhead tracker against the simulated camera.
"""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'BringupError': 'errors',
    'LaunchFileError': 'launch_files',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
