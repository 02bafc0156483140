"""Exceptions of the common contract (all are ValueErrors: the input was wrong)."""

from __future__ import annotations


class CommonError(ValueError):
    """Base class of every error raised by smarticle_common."""


class RobotSpecError(CommonError):
    """An invalid robot spec (a size, mass or servo value that is not physical)."""


class PairInputError(CommonError):
    """Malformed poses or pairs given to the pair coordinates (shapes, robot indices)."""
