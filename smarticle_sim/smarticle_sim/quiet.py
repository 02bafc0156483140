"""PyBullet without its chatter on standard output.

PyBullet's C library prints a build-time banner on standard error when it is imported, and 'argv[0]='
on standard output, through C's buffered stdio, when a client connects: noise above every command's output
and, in a pipe, text that surfaces at exit amid a command's tables. ``silenced_output`` points descriptors
1 and 2 at the null device for the span of the block and flushes C's buffers before pointing them back.
Errors still surface: an exception raised in the block propagates once the descriptors are restored.
This module is the one place that imports pybullet; the rest of the package takes it from here.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO


def _flush_c_stdio() -> None:
    """fflush(NULL): write out every C stdio buffer of this process (no-op where libc is not found)."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


@contextmanager
def _silenced(stream: TextIO) -> Iterator[None]:
    """Within the block, text written to ``stream``'s descriptor (by Python or by C) goes to the null device."""
    try:
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):   # replaced by a non-file (e.g. captured)
        yield
        return
    stream.flush()
    _flush_c_stdio()
    saved = os.dup(fd)
    try:
        with open(os.devnull, 'wb') as devnull:
            os.dup2(devnull.fileno(), fd)
            try:
                yield
            finally:
                _flush_c_stdio()
    finally:
        os.dup2(saved, fd)
        os.close(saved)


@contextmanager
def silenced_output() -> Iterator[None]:
    """Within the block, standard output and standard error (Python's and C's) go to the null device."""
    with _silenced(sys.stdout), _silenced(sys.stderr):
        yield


with silenced_output():
    import pybullet
    from pybullet_utils.bullet_client import BulletClient

__all__ = ['BulletClient', 'pybullet', 'silenced_output']
