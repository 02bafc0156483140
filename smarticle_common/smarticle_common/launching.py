"""Start the stack's executables as separate processes and stop them together (a small stand-in for
``ros2 launch``, which is not available from PyPI). Used by the demo, the benchmarks and the tests.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import IO


def executable(name: str) -> str:
    """Return the path of an installed console script (node or CLI) of the project (or ``name`` if a path)."""
    if os.path.isabs(name) and os.access(name, os.X_OK):
        return name
    path = Path(sys.executable).parent / name
    if path.exists():
        return str(path)
    found = shutil.which(name)
    if found is None:
        raise FileNotFoundError(f'console script {name!r} is not installed; run ./test.sh or '
                                'tools/bootstrap.sh to set up .venv')
    return found


class DomainReservation:
    """A DDS domain id held for this process through an exclusive lock file (released on close or exit)."""

    def __init__(self, first: int = 1, last: int = 101, lock_dir: str | None = None) -> None:
        import fcntl
        import tempfile

        directory = Path(lock_dir or tempfile.gettempdir())
        start = os.getpid() % (last - first + 1)
        for offset in range(last - first + 1):
            domain = first + (start + offset) % (last - first + 1)
            handle = open(directory / f'smarticle-ros-domain-{domain}.lock', 'w')
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            self.domain_id, self._handle = domain, handle
            return
        raise RuntimeError(f'every ROS domain id from {first} to {last} is in use by another run')

    def close(self) -> None:
        """Release the domain id."""
        self._handle.close()


def isolated_ros_env(domain_id: int | None = None) -> dict[str, str]:
    """Environment for a self-contained run: localhost-only discovery and its own DDS domain."""
    env = dict(os.environ)
    if domain_id is None:
        domain_id = int(env.get('ROS_DOMAIN_ID', 1 + os.getpid() % 100))
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['PYTHONUNBUFFERED'] = '1'
    return env


class ProcessGroup:
    """Executables started in their own sessions, each logging to a file; ``stop_all`` ends them all."""

    def __init__(self, log_dir: Path, env: dict[str, str] | None = None) -> None:
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.env = env
        self.procs: list[tuple[subprocess.Popen[bytes], Path, IO[bytes]]] = []

    def start(self, name: str, *args: str, env: dict[str, str] | None = None) -> subprocess.Popen[bytes]:
        """Start executable ``name`` with ``args``; its output goes to ``<log_dir>/<name>-<i>.log``."""
        log = self.log_dir / f'{Path(name).name}-{len(self.procs)}.log'
        handle = open(log, 'wb')
        merged = {**(self.env or os.environ), **(env or {})}
        proc = subprocess.Popen([executable(name), *args], stdout=handle, stderr=subprocess.STDOUT,
                                env=merged, start_new_session=True)
        self.procs.append((proc, log, handle))
        return proc

    def output(self, proc: subprocess.Popen[bytes]) -> str:
        """Return what ``proc`` has printed so far."""
        for candidate, log, _ in self.procs:
            if candidate is proc:
                return log.read_text(errors='replace')
        raise KeyError('process not started by this group')

    def stop_all(self, grace: float = 5.0) -> None:
        """SIGINT every running process, SIGKILL what is left after ``grace`` seconds, close the logs."""
        for proc, _, _ in self.procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        deadline = time.monotonic() + grace
        for proc, _, handle in self.procs:
            try:
                proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            handle.close()
        self.procs.clear()

    def __enter__(self) -> ProcessGroup:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop_all()
