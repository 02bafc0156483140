"""Exceptions of smarticle_feedback."""

from __future__ import annotations


class FeedbackError(Exception):
    """Base class of the feedback controller's errors."""


class FeedbackConfigError(FeedbackError, ValueError):
    """An impact window, debounce count or timing setting that makes no sense."""


class FsrSampleError(FeedbackError, ValueError):
    """An FSR sample that cannot be used at all (wrong faces, time going backwards); ``kind`` names its counter."""

    def __init__(self, message: str, kind: str) -> None:
        super().__init__(message)
        self.kind = kind


class CalibrationInputError(FeedbackError, ValueError):
    """A recording that cannot calibrate the impact window (no FSR data, no collisions)."""
