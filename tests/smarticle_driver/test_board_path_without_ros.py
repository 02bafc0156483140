"""The board path as docs/quickstart.md runs it, from a shell with no ROS install: the board emulator,
``smarticle-launch ... board.launch.xml`` with a calibration folder, ``smarticle-start``, and the arms move.

Every step is a console script of .venv/bin started with an environment that has no ROS set-up in it
(no ``AMENT_PREFIX_PATH``, no ``ros2`` on PATH); the board's view is the emulator's record of Set Target
commands, read back through the robot's own calibration.
"""

from __future__ import annotations

import csv
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from smarticle_common.gait import CORNER_SIGNS
from smarticle_driver.board_calibration import load_servo_calibration
from tests.helpers.fake_board import wait_until

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
#: The robot's own servo calibration: neither the package's (1500 us, 600 us/rad) nor mirrored like it.
ROBOT0_SERVOS = '''servos:
  arm1: {center_us: 1420.0, us_per_rad: 560.0, min_us: 500.0, max_us: 2500.0}
  arm2: {center_us: 1580.0, us_per_rad: -580.0, min_us: 500.0, max_us: 2500.0}
'''
ALPHA_DEG = 90.0      # config/stack.yaml


def shell_env() -> dict[str, str]:
    """A fresh login shell's environment after ``source tools/bootstrap.sh``, on a machine without ROS: PATH
    with .venv/bin first and no ROS set-up (no AMENT_PREFIX_PATH, LD_LIBRARY_PATH, PYTHONPATH); the test run's
    own DDS domain kept, so the test stays apart from concurrent runs."""
    keep = ('HOME', 'USER', 'LANG', 'LC_ALL', 'TMPDIR', 'ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')
    env = {k: os.environ[k] for k in keep if k in os.environ}
    env.update(PATH=f'{BIN}:/usr/local/bin:/usr/bin:/bin', VIRTUAL_ENV=str(BIN.parent), PYTHONUNBUFFERED='1')
    return env


@pytest.fixture
def shell(tmp_path: Path) -> Iterator[list[subprocess.Popen[bytes]]]:
    """Background commands of the shell, ended with SIGINT (then SIGKILL) at the end of the test."""
    started: list[subprocess.Popen[bytes]] = []
    yield started
    for proc in reversed(started):
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


def background(shell: list[subprocess.Popen[bytes]], cwd: Path, log: str, *command: str) -> subprocess.Popen[bytes]:
    """Start ``command`` as ``command > log 2>&1 &`` would."""
    with open(cwd / log, 'wb') as out:
        proc = subprocess.Popen(list(command), cwd=cwd, env=shell_env(), stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True)
    shell.append(proc)
    return proc


def logs(folder: Path) -> str:
    """What the launch and its nodes printed (for assertion messages)."""
    return '\n'.join(f'== {p.name}\n' + p.read_text(errors='replace')[-3000:]
                     for p in sorted(folder.glob('*.log')) + sorted(folder.glob('out/launch/*/*.log')))


def recorded(path: Path) -> list[tuple[float, int, float]]:
    """The emulator's record: (time, channel, pulse us) of every Set Target."""
    if not path.exists():
        return []
    with open(path, newline='') as handle:
        return [(float(row[0]), int(row[1]), float(row[2])) for row in csv.reader(handle)
                if row and not row[0].startswith(('#', 't'))]


def corners_of(records: list[tuple[float, int, float]], calibration: Path) -> list[int]:
    """The gait corners the board was sent to, in order, read through ``calibration`` (-1: not a corner)."""
    servos = load_servo_calibration(calibration)
    angles: dict[int, float] = {}
    seen: list[int] = []
    for _, channel, pulse in records:
        angles[channel] = math.degrees(servos[('arm1', 'arm2')[channel]].pulse_to_angle(pulse))
        if len(angles) < 2:
            continue
        corner = next((i for i, (s1, s2) in enumerate(CORNER_SIGNS) if abs(angles[0] - s1 * ALPHA_DEG) < 1.0
                       and abs(angles[1] - s2 * ALPHA_DEG) < 1.0), -1)
        if not seen or seen[-1] != corner:
            seen.append(corner)
    return seen


@pytest.mark.integration
def test_emulator_board_launch_and_smarticle_start_move_the_arms_without_ros(tmp_path: Path, shell: list) -> None:
    assert shutil.which('ros2', path=shell_env()['PATH']) is None, 'this test needs a shell without the ROS CLI'
    robot = tmp_path / 'robot0'                       # what smarticle-board-calibrate --out robot0/ writes
    robot.mkdir()
    (robot / 'servo_calibration.yaml').write_text(ROBOT0_SERVOS)
    shutil.copy(ROOT / 'smarticle_driver' / 'config' / 'fsr_calibration.yaml', robot / 'fsr_calibration.yaml')
    port, record = tmp_path / 'maestro0', tmp_path / 'targets.csv'

    board = background(shell, tmp_path, 'board.log', 'smarticle-fake-board', '--port', str(port), '--control',
                       str(tmp_path / 'maestro0.ctl'), '--record', str(record), '--no-stdin')
    assert wait_until(port.exists, 15.0), (tmp_path / 'board.log').read_text()
    launch = background(shell, tmp_path, 'launch.log', 'smarticle-launch', 'smarticle_bringup', 'board.launch.xml',
                        'robot:=0', f'port:={port}', 'calibration:=robot0/')
    # the bridge holds the start pose (c0) on the board while the gait waits for the start
    assert wait_until(lambda: corners_of(recorded(record), robot / 'servo_calibration.yaml') == [0], 30.0), (
        logs(tmp_path), recorded(record))
    time.sleep(1.0)
    assert corners_of(recorded(record), robot / 'servo_calibration.yaml') == [0], 'the arms moved before the start'

    start = subprocess.run(['smarticle-start', '--timeout', '30'], cwd=tmp_path, env=shell_env(),
                           capture_output=True, text=True, timeout=60)
    assert start.returncode == 0, start.stderr
    assert '/smarticle_0/gait' in start.stdout and start.stdout.count('\n') == 1, start.stdout

    # the arms go round the square on the board: c0 -> c1 -> c2 -> c3 -> c0 in the robot's own pulses
    def went_round() -> bool:
        return len(corners_of(recorded(record), robot / 'servo_calibration.yaml')) >= 6
    assert wait_until(went_round, 15.0), (logs(tmp_path), recorded(record))
    corners = corners_of(recorded(record), robot / 'servo_calibration.yaml')
    assert -1 not in corners and all((b - a) % 4 == 1 for a, b in zip(corners, corners[1:], strict=False)), corners
    # read through the package's calibration instead, the same pulses are no gait corners
    assert -1 in corners_of(recorded(record), ROOT / 'smarticle_driver' / 'config' / 'servo_calibration.yaml')

    os.killpg(launch.pid, signal.SIGINT)                 # Ctrl-C ends the launch and its nodes
    assert launch.wait(timeout=15.0) == 0, logs(tmp_path)
    assert board.poll() is None
