"""Command-line habits shared by every console script of the stack (no rclpy import).

* ``add_version(parser, distribution)``: a ``--version`` option that prints ``<prog> <version>``
  from the installed distribution's metadata (``0+unknown`` when it is not installed);
* ``closed_pipe_safe(main)``: a decorator for a ``main`` that must end quietly when its output pipe is
  closed early (``smarticle-experiments list | head -1``), with the shell's exit code 141 for SIGPIPE;
* ``parse_seeds(text)``: the one seed syntax of the stack: ``7``, ``0..19`` (both ends included),
  ``0,3,5`` or a mix ``0..4,10``; ``SeedSyntaxError`` (a ``ValueError``) names the bad piece.
"""

from __future__ import annotations

import functools
import os
import sys
from argparse import ArgumentParser, ArgumentTypeError
from collections.abc import Callable
from importlib import metadata
from typing import TypeVar

from .errors import CommonError

__all__ = ['SeedSyntaxError', 'add_version', 'closed_pipe_safe', 'parse_seeds', 'seeds_argument', 'version_of']

#: Exit code of a process ended by SIGPIPE, as a shell reports it (128 + 13).
EXIT_CLOSED_PIPE = 141
#: Exit code of a process ended by Ctrl-C (SIGINT), as a shell reports it (128 + 2).
EXIT_INTERRUPTED = 130

R = TypeVar('R')


class SeedSyntaxError(CommonError):
    """A seed list that does not follow the stack's seed syntax (``7``, ``0..19``, ``0,3,5``)."""


def version_of(distribution: str) -> str:
    """The installed version of ``distribution`` (e.g. ``smarticle_sim``), or ``0+unknown``."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return '0+unknown'


def add_version(parser: ArgumentParser, distribution: str) -> None:
    """Add ``--version`` to ``parser``: prints ``<prog> <version of distribution>`` and exits 0."""
    parser.add_argument('--version', action='version', version=f'%(prog)s {version_of(distribution)}')


def closed_pipe_safe(main: Callable[..., R]) -> Callable[..., R | int]:
    """Wrap a console ``main`` so that a reader closing the pipe early ends it quietly (exit code 141), and
    Ctrl-C one that has not handled it itself with one line on stderr (``PROG: interrupted``, exit code 130).

    Python raises ``BrokenPipeError`` on the next write or at the final flush; both are caught, and
    stdout is pointed at ``/dev/null`` so the interpreter's own flush at exit does not print a traceback.
    """
    @functools.wraps(main)
    def wrapped(*args: object, **kwargs: object) -> R | int:
        try:
            result = main(*args, **kwargs)
            sys.stdout.flush()
            return result
        except BrokenPipeError:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            return EXIT_CLOSED_PIPE
        except KeyboardInterrupt:
            sys.stderr.write(f'{os.path.basename(sys.argv[0]) or "python"}: interrupted\n')
            return EXIT_INTERRUPTED
    return wrapped


def parse_seeds(text: str) -> list[int]:
    """Seeds from the stack's seed syntax, in the order given, without repeats.

    ``'7'`` -> [7]; ``'0..3'`` -> [0, 1, 2, 3] (both ends included); ``'0,3,5'`` -> [0, 3, 5];
    pieces mix: ``'0..2,10'`` -> [0, 1, 2, 10]. Seeds are non-negative integers.
    """
    seeds: list[int] = []
    pieces = [p.strip() for p in str(text).split(',')]
    if not pieces or any(not p for p in pieces):
        raise SeedSyntaxError(f'seeds {text!r}: expected e.g. 7, 0..19 or 0,3,5 (an empty piece was given)')
    for piece in pieces:
        try:
            if '..' in piece:
                lo_text, hi_text = piece.split('..', 1)
                lo, hi = int(lo_text), int(hi_text)
                if hi < lo:
                    raise SeedSyntaxError(f'seeds {text!r}: range {piece!r} runs backwards')
                chunk = list(range(lo, hi + 1))
            else:
                chunk = [int(piece)]
        except ValueError as err:
            if isinstance(err, SeedSyntaxError):
                raise
            raise SeedSyntaxError(f'seeds {text!r}: {piece!r} is not a seed or a range a..b') from None
        for seed in chunk:
            if seed < 0:
                raise SeedSyntaxError(f'seeds {text!r}: seeds are non-negative, got {seed}')
            if seed not in seeds:
                seeds.append(seed)
    return seeds


def seeds_argument(text: str) -> list[int]:
    """``parse_seeds`` as an argparse ``type=`` (a bad list becomes argparse's usage error)."""
    try:
        return parse_seeds(text)
    except SeedSyntaxError as err:
        raise ArgumentTypeError(str(err)) from None
