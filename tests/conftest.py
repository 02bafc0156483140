"""Shared fixtures: an isolated DDS domain per test run and real node processes."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Iterator

import pytest

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def pytest_configure(config: pytest.Config) -> None:
    """Give this test run its own DDS domain on localhost before anything starts rclpy."""
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + os.getpid() % 100))
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    os.environ['PYTHONUNBUFFERED'] = '1'


def executable(name: str) -> str:
    """Return the path of an installed console script (node or CLI) of the project."""
    path = BIN / name
    if path.exists():
        return str(path)
    found = shutil.which(name)
    if found is None:
        raise FileNotFoundError(f'console script {name!r} not installed; run ./test.sh to set up .venv')
    return found


class NodeProcesses:
    """Starts project executables as subprocesses and stops them all at the end of a test."""

    def __init__(self, log_dir: Path) -> None:
        self.log_dir = log_dir
        self.procs: list[tuple[subprocess.Popen[bytes], Path]] = []

    def start(self, name: str, *args: str, env: dict[str, str] | None = None) -> subprocess.Popen[bytes]:
        """Start executable ``name`` with ``args``; its output goes to a log file in tmp_path."""
        log = self.log_dir / f'{name}-{len(self.procs)}.log'
        handle = open(log, 'wb')
        proc = subprocess.Popen([executable(name), *args], stdout=handle, stderr=subprocess.STDOUT,
                                env={**os.environ, **(env or {})}, start_new_session=True)
        self.procs.append((proc, log))
        return proc

    def output(self, proc: subprocess.Popen[bytes]) -> str:
        """Return what ``proc`` has printed so far."""
        for candidate, log in self.procs:
            if candidate is proc:
                return log.read_text(errors='replace')
        raise KeyError('not started here')

    def stop_all(self) -> None:
        """SIGINT every process, then kill what is left after a few seconds."""
        for proc, _ in self.procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        deadline = time.monotonic() + 5.0
        for proc, _ in self.procs:
            try:
                proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


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
