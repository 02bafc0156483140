"""Impact-halt feedback from the FSRs: the controller core, its parameters, collision records and calibration."""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'FeedbackConfig': 'controller', 'ImpactController': 'controller', 'ImpactWindow': 'controller',
    'check_sample': 'controller',
    'CollisionRecord': 'collisions', 'find_events': 'collisions', 'signature': 'collisions',
    'FeedbackError': 'errors', 'FeedbackConfigError': 'errors', 'FsrSampleError': 'errors',
    'CalibrationInputError': 'errors',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
