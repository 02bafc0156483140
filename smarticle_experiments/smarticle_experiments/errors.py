"""Exceptions of smarticle_experiments; each message names what was wrong and what to do."""

from __future__ import annotations


class ExperimentError(Exception):
    """Base class of every smarticle_experiments error."""


class SpecError(ExperimentError, ValueError):
    """An experiment spec that cannot be run: unknown key, bad count, empty grid; the message names the field."""


class SchedulerError(ExperimentError, ConnectionError):
    """The Dask scheduler named by ``--scheduler`` does not answer."""


class StoreError(ExperimentError, OSError):
    """The result store cannot be read or written."""


class ResultError(ExperimentError, ValueError):
    """A stored trial result that does not read back as its kind's typed record (``results.read_result``)."""
