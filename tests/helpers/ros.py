"""Spinning test nodes until something happens."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from smarticle_common.launching import ProcessGroup, executable

__all__ = ['ROOT', 'NodeProcesses', 'executable', 'spin_until']

ROOT = Path(__file__).resolve().parents[2]


class NodeProcesses(ProcessGroup):
    """The project's ProcessGroup with this test run's environment (the ``nodes`` fixture)."""


def spin_until(node: object, predicate: Callable[[], bool], timeout: float) -> bool:
    """Spin ``node`` until ``predicate()`` is true or ``timeout`` seconds pass; return the predicate."""
    import rclpy

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        rclpy.spin_once(node, timeout_sec=0.05)
    return predicate()
