"""Start the stack's executables as separate processes and stop them together (a small stand-in for
``ros2 launch``, which is not available from PyPI). Used by the demo, the benchmarks and the tests.

Also what a launcher reads back from the processes' output: the one-line reason a process failed
(``failure_reason``) and the nodes' exit summaries (``summary_line`` writes one, ``gather_summaries``
merges them per robot).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Mapping
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

    def log_of(self, proc: subprocess.Popen[bytes]) -> Path:
        """The log file of ``proc`` (KeyError if this group did not start it)."""
        for candidate, log, _ in self.procs:
            if candidate is proc:
                return log
        raise KeyError('process not started by this group')

    def output(self, proc: subprocess.Popen[bytes]) -> str:
        """Return what ``proc`` has printed so far."""
        return self.log_of(proc).read_text(errors='replace')

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


# ---------------------------------------------------------------------------------------------- what a log says
#: A line of rclpy's console log: ``[LEVEL] [stamp] [logger]: message``.
_LOG_LINE = re.compile(r'^\[(DEBUG|INFO|WARN|WARNING|ERROR|FATAL)\] \[[\d.]+\] \[([^\]]*)\]: (.*)$')
#: rcl's source locations inside an error message (``, at /project/src/parse.c:782``): noise to a user.
_RCL_WHERE = re.compile(r',? at /\S+:\d+')
#: rcl's log lines can follow a traceback's last line without a line break.
_GLUED_LOG = re.compile(r'\[(ERROR|FATAL|WARN|INFO)\] \[[\d.]+\].*$')
#: The marker of a node's exit summary line (``summary_line``).
SUMMARY = 'summary: '


def _one_line(text: str) -> str:
    """``text`` as one line: rcl's source locations dropped, whitespace collapsed."""
    return ' '.join(_RCL_WHERE.sub('', text).split())


def failure_reason(output: str) -> str | None:
    """The error a failed process printed, as one line: the last traceback's message and last frame, else
    its last ERROR or FATAL log line, else its last line (None without output)."""
    lines = output.splitlines()
    start = max((i for i, line in enumerate(lines) if line.startswith('Traceback (most recent call last)')),
                default=None)
    if start is not None:
        frame, message = '', ''
        for line in lines[start + 1:]:
            if line.startswith('  File "'):
                frame, message = line.strip(), ''
            elif line.strip() and not line.startswith(' ') and not message:
                message = _GLUED_LOG.sub('', line)
        if message:
            return _one_line(f'{message} ({frame})' if frame else message)
    for line in reversed(lines):
        match = _LOG_LINE.match(line.strip())
        if match and match.group(1) in ('ERROR', 'FATAL'):
            return _one_line(f'[{match.group(2)}] {match.group(3)}')
    last = next((line for line in reversed(lines) if line.strip()), None)
    return None if last is None else _one_line(last)


def summary_line(robot: int, counts: Mapping[str, object]) -> str:
    """A node's exit summary of one robot, for the launcher to gather: ``summary: robot 3: commands 96, halts 2``
    (the launcher merges the lines of one robot from every node)."""
    return f'{SUMMARY}robot {robot}: ' + ', '.join(f'{key} {value}' for key, value in counts.items())


def report_line(text: str) -> str:
    """A node's exit report of the run, for the launcher to print as is (the glider report)."""
    return f'{SUMMARY}{text}'


def gather_summaries(outputs: list[str]) -> tuple[dict[int, dict[str, str]], list[str]]:
    """The exit summaries in the processes' ``outputs``: each robot's counts merged (a count that two nodes
    give keeps the larger), and the other summary lines in order."""
    robots: dict[int, dict[str, str]] = {}
    others: list[str] = []
    for output in outputs:
        for line in output.splitlines():
            match = _LOG_LINE.match(line.strip())
            if match is None or not match.group(3).startswith(SUMMARY):
                continue
            text = match.group(3)[len(SUMMARY):]
            robot = re.match(r'robot (\d+): (.*)$', text)
            if robot is None:
                others.append(text)
                continue
            counts = robots.setdefault(int(robot.group(1)), {})
            for item in robot.group(2).split(', '):
                key, _, value = item.rpartition(' ')
                old = counts.get(key)
                if key and (old is None or (old.isdigit() and value.isdigit() and int(value) > int(old))):
                    counts[key] = value
    return dict(sorted(robots.items())), others
