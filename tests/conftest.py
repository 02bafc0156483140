"""Shared fixtures: an isolated DDS domain per test run and real node processes (helpers: tests/helpers/).

Tiers: a test that uses the ``nodes``, ``ros_node`` or ``sim_world`` (smarticle_sim.testing) fixture starts
real nodes or talks over DDS and is marked ``integration`` automatically; ``./test.sh -m "not integration"``
runs the fast tier."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Iterator

import pytest
from smarticle_common.launching import DomainReservation

from tests.helpers.ros import NodeProcesses

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


def pytest_unconfigure(config: pytest.Config) -> None:
    """Release this run's DDS domain (its lock file) at the end of the run."""
    reservation = config.stash.get(DOMAIN, None)
    if reservation is not None:
        reservation.close()


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


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test that starts real nodes or joins DDS (``nodes``, ``ros_node``, ``sim_world``) as integration."""
    for item in items:
        if {'nodes', 'ros_node', 'sim_world'} & set(getattr(item, 'fixturenames', ())):
            item.add_marker(pytest.mark.integration)
