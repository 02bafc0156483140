"""Exceptions of smarticle_bringup; each message names what was wrong and what to do."""

from __future__ import annotations


class BringupError(Exception):
    """Base class of every smarticle_bringup error."""
