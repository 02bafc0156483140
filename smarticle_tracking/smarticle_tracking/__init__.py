"""Tracking of smarticles: ArUco tags to planar poses, the glider analysis, MSD, the camera calibration, gait clocks."""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'GliderClass': 'gliders', 'PairKind': 'gliders', 'GliderConfig': 'gliders', 'Glider': 'gliders',
    'GliderAnalysis': 'gliders', 'analyse_gliders': 'gliders', 'glider_table': 'gliders',
    'format_glider_table': 'gliders',
    'plot_glider_analysis': 'glider_plots',
    'TrackerConfig': 'tracker', 'TagTracker': 'tracker',
    'msd': 'msd', 'fit_msd_exponent': 'msd',
    'Calibration': 'homography', 'calibrate': 'homography', 'load_calibration': 'homography',
    'TrackingError': 'errors', 'GliderError': 'errors', 'GliderInputError': 'errors', 'GliderConfigError': 'errors',
    'MsdFitError': 'errors', 'TrackerError': 'errors', 'TrackerConfigError': 'errors',
    'TrackerInputError': 'errors', 'CameraCalibrationError': 'errors', 'FrameEncodingError': 'errors',
    'FrameSizeError': 'errors', 'ClockError': 'errors',
    'ClockEstimate': 'clocks', 'estimate_clock': 'clocks', 'fit_clock': 'clocks',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
