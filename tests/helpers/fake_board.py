"""Helpers of the servo-bridge tests: a running board emulator and polling with a deadline."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from smarticle_driver.emulator import MaestroEmulator
from smarticle_driver.maestro import MaestroBoard
from smarticle_driver.serial_link import SerialLink


@contextmanager
def running_emulator(path: Path) -> Iterator[MaestroEmulator]:
    """Run a Maestro emulator on a pty published at ``path`` for the duration of the block."""
    emulator = MaestroEmulator(path)
    emulator.start()
    try:
        yield emulator
    finally:
        emulator.stop()


def open_board(path: Path, **kwargs: float) -> tuple[SerialLink, MaestroBoard]:
    """Open a real pyserial link to ``path`` and wrap it in a Maestro board."""
    link = SerialLink(str(path), reply_timeout=kwargs.pop('reply_timeout', 0.05), **kwargs)
    assert link.poll(), link.last_error
    return link, MaestroBoard(link)


def wait_until(predicate: Callable[[], bool], timeout: float, step: float = 0.01) -> bool:
    """Poll ``predicate`` until it holds or ``timeout`` seconds pass; return its last value."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return predicate()
