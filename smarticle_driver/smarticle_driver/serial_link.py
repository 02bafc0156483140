"""A serial port that survives being unplugged: reopens with exponential back-off, checks replies.

``SerialLink`` never blocks on a missing port: while it is down every call raises PortUnavailable at
once, and ``poll()`` (called from the node's timer) tries to reopen it when the back-off has run out.
Each transaction discards (and counts) stale input first, so a garbage byte or a truncated reply
spoils one sample, never the byte alignment of the next one.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from enum import Enum
from typing import NoReturn

import serial

from smarticle_driver.errors import GarbageReply, PortUnavailable, ShortReply

try:
    import termios
    _PORT_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, OSError, termios.error)
except ImportError:  # pragma: no cover - non-POSIX
    _PORT_ERRORS = (serial.SerialException, OSError)


class LinkState(Enum):
    """Whether the port is open, or closed and waiting for the next reopen attempt."""

    OPEN = 'open'
    DOWN = 'down'


class SerialLink:
    """A reconnecting pyserial port for request/reply protocols."""

    def __init__(self, port: str, baud: int = 115200, reply_timeout: float = 0.02,
                 backoff_initial: float = 0.1, backoff_max: float = 2.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not (reply_timeout > 0.0 and 0.0 < backoff_initial <= backoff_max):
            raise ValueError('need reply_timeout > 0 and 0 < backoff_initial <= backoff_max, got '
                             f'{reply_timeout}, {backoff_initial}, {backoff_max}')
        self.port = port
        self.baud = baud
        self.reply_timeout = reply_timeout
        self.backoff_initial = backoff_initial
        self.backoff_max = backoff_max
        self.clock = clock
        self.state = LinkState.DOWN
        self.last_error = 'not opened yet'
        self.opens = 0
        self.disconnects = 0
        self.failed_opens = 0
        self.discarded_bytes = 0
        self._serial: serial.Serial | None = None
        self._backoff = backoff_initial
        self._next_attempt = clock()

    @property
    def is_open(self) -> bool:
        """True while the port is open."""
        return self.state is LinkState.OPEN

    def seconds_to_retry(self) -> float:
        """Seconds until the next reopen attempt (0 when open or due)."""
        return 0.0 if self.is_open else max(self._next_attempt - self.clock(), 0.0)

    def poll(self) -> bool:
        """Reopen the port if it is down and the back-off has run out; return True if it just opened."""
        if self.is_open or self.clock() < self._next_attempt:
            return False
        try:
            self._serial = serial.Serial(self.port, self.baud, timeout=self.reply_timeout,
                                         write_timeout=max(self.reply_timeout, 0.1))
            self._serial.reset_input_buffer()
        except _PORT_ERRORS as err:
            self._serial = None
            self.failed_opens += 1
            self.last_error = f'cannot open {self.port}: {err}'
            self._next_attempt = self.clock() + self._backoff
            self._backoff = min(self._backoff * 2.0, self.backoff_max)
            return False
        self.state = LinkState.OPEN
        self.opens += 1
        self._backoff = self.backoff_initial
        self.last_error = ''
        return True

    def write(self, data: bytes) -> None:
        """Send ``data``; raise PortUnavailable (and start reconnecting) if the port is gone."""
        port = self._require()
        try:
            port.write(data)
        except _PORT_ERRORS as err:
            self._drop(f'write to {self.port} failed: {err}')

    def transact(self, data: bytes, reply_length: int) -> bytes:
        """Send ``data`` and return exactly ``reply_length`` bytes; ShortReply/GarbageReply otherwise."""
        port = self._require()
        try:
            stale = port.in_waiting
            if stale:
                self.discarded_bytes += stale
                port.reset_input_buffer()
            port.write(data)
            reply = port.read(reply_length)
            extra = port.in_waiting
            if extra:
                self.discarded_bytes += extra
                port.reset_input_buffer()
        except _PORT_ERRORS as err:
            self._drop(f'{self.port} failed during a transaction: {err}')
        if len(reply) < reply_length:
            raise ShortReply(f'expected {reply_length} reply bytes within {self.reply_timeout:g} s, got '
                             f'{len(reply)}: {reply.hex() or "nothing"}')
        if extra:
            raise GarbageReply(f'{extra} unexpected byte(s) after a {reply_length}-byte reply: '
                               'sample dropped')
        return reply

    def close(self) -> None:
        """Close the port (it stays down until ``poll`` reopens it)."""
        if self._serial is not None:
            try:
                self._serial.close()
            except _PORT_ERRORS:
                pass
        self._serial = None
        self.state = LinkState.DOWN

    def _require(self) -> serial.Serial:
        if self._serial is None or not self.is_open:
            raise PortUnavailable(f'{self.port} is not open ({self.last_error})')
        return self._serial

    def _drop(self, reason: str) -> NoReturn:
        """Close a failed port, schedule the first reopen attempt and raise PortUnavailable."""
        self.close()
        self.disconnects += 1
        self.last_error = reason
        self._backoff = self.backoff_initial
        self._next_attempt = self.clock() + self._backoff
        raise PortUnavailable(reason)
