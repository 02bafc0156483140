"""Shared fixtures: an isolated DDS domain per test run and real node processes."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Callable, Iterator

import pytest
from smarticle_common.launching import DomainReservation, ProcessGroup, executable

__all__ = ['executable', 'spin_until']

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = pytest.StashKey[DomainReservation]()


def pytest_configure(config: pytest.Config) -> None:
    """Give this test run its own DDS domain on localhost before anything starts rclpy."""
    if 'ROS_DOMAIN_ID' not in os.environ:  # a domain no concurrent test run holds
        config.stash[DOMAIN] = DomainReservation()
        os.environ['ROS_DOMAIN_ID'] = str(config.stash[DOMAIN].domain_id)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    os.environ['PYTHONUNBUFFERED'] = '1'


class NodeProcesses(ProcessGroup):
    """The project's ProcessGroup with this test run's environment."""


@pytest.fixture
def nodes(tmp_path: Path) -> Iterator[NodeProcesses]:
    """Start real node processes for a test; all are stopped afterwards (logs in tmp_path)."""
    procs = NodeProcesses(tmp_path)
    try:
        yield procs
    finally:
        procs.stop_all()


@pytest.fixture
def ros_node() -> Iterator[Callable[[str], object]]:
    """Create rclpy test nodes in this run's domain; rclpy is shut down afterwards."""
    import rclpy

    rclpy.init()
    made: list[object] = []

    def make(name: str) -> object:
        node = rclpy.create_node(name)
        made.append(node)
        return node

    try:
        yield make
    finally:
        for node in made:
            node.destroy_node()  # type: ignore[attr-defined]
        rclpy.try_shutdown()


def spin_until(node: object, predicate: Callable[[], bool], timeout: float) -> bool:
    """Spin ``node`` until ``predicate()`` is true or ``timeout`` seconds pass; return the predicate."""
    import rclpy

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        rclpy.spin_once(node, timeout_sec=0.05)
    return predicate()
