"""Exceptions of the smarticle_tracking cores (all are ValueErrors: the input was wrong)."""

from __future__ import annotations


class TrackingError(ValueError):
    """Base class of every error raised by the smarticle_tracking cores."""


class GliderError(TrackingError):
    """Base class of the glider-analysis errors."""


class GliderInputError(GliderError):
    """Malformed data given to the glider analysis (shapes, times, NaN where not allowed)."""


class GliderConfigError(GliderError):
    """An invalid glider-analysis parameter."""


class MsdFitError(GliderError):
    """Too few usable MSD points to fit the exponent beta."""


class TrackerError(TrackingError):
    """Base class of the overhead-tracker errors."""


class TrackerConfigError(TrackerError):
    """An invalid tracker parameter (dictionary, tag ids, sizes)."""


class TrackerInputError(TrackerError):
    """A camera frame the tracker cannot use (encoding, size, shape)."""


class CameraCalibrationError(TrackerError):
    """A missing, unreadable or unusable plane-homography calibration."""


class FrameEncodingError(TrackerInputError):
    """An image encoding the tracker does not read, or a malformed image buffer."""


class FrameSizeError(TrackerInputError):
    """A frame whose size differs from the calibration's."""


class ClockError(TrackingError):
    """Arm data from which no gait clock can be estimated (too few quarter boundaries, no motion)."""
