"""Tracking of smarticles: ArUco tags to planar poses, the glider analysis, MSD, the camera calibration."""

from __future__ import annotations

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'GliderClass': 'gliders', 'GliderConfig': 'gliders', 'Glider': 'gliders', 'GliderAnalysis': 'gliders',
    'analyse_gliders': 'gliders', 'glider_table': 'gliders', 'format_glider_table': 'gliders',
    'plot_glider_analysis': 'glider_plots',
    'TrackerConfig': 'tracker', 'TagTracker': 'tracker',
    'msd': 'msd', 'fit_msd_exponent': 'msd',
    'Calibration': 'homography', 'calibrate': 'homography', 'load_calibration': 'homography',
    'TrackingError': 'errors', 'GliderError': 'errors', 'GliderInputError': 'errors', 'GliderConfigError': 'errors',
    'MsdFitError': 'errors', 'TrackerError': 'errors', 'TrackerConfigError': 'errors',
    'TrackerInputError': 'errors', 'CameraCalibrationError': 'errors', 'FrameEncodingError': 'errors',
    'FrameSizeError': 'errors',
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
