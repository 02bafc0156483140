"""The servo-board interface the bridge core talks to, and the factory that picks a backend.

The bridge speaks to a board only through ``ServoBoard`` (pulse widths in microseconds, pulse rates
in us/s, analog counts), so another controller (e.g. a Dynamixel Protocol 2.0 bus, whose position
ticks would play the role of the pulse) is one new class here and one name in ``BOARD_KINDS``; the
node and the core stay as they are.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from smarticle_driver.errors import BridgeConfigError
from smarticle_driver.maestro import ByteLink, MaestroBoard


class ServoBoard(Protocol):
    """A servo controller that also samples analog inputs."""

    analog_full_scale: int
    analog_volts: float

    def set_target(self, channel: int, pulse_us: float) -> float:
        """Command a pulse width (us); return the value actually sent after quantisation."""

    def set_speed(self, channel: int, us_per_s: float) -> float:
        """Limit the pulse rate (us/s, inf = unlimited); return the rate the board will use."""

    def read_analog(self, channels: Sequence[int]) -> list[int]:
        """Return the analog counts of ``channels`` (0..analog_full_scale)."""

    def read_pulse(self, channel: int) -> float:
        """Return a servo channel's current pulse width in us (0 = no pulses)."""

    def get_errors(self) -> list[str]:
        """Read and clear the board's error flags; return their names."""


#: Known board kinds (the ``board`` parameter of the servo bridge).
BOARD_KINDS: tuple[str, ...] = ('maestro',)


def make_board(kind: str, link: ByteLink) -> ServoBoard:
    """Return the board backend ``kind`` speaking over ``link``."""
    if kind == 'maestro':
        return MaestroBoard(link)
    raise BridgeConfigError(f'unknown board kind {kind!r}; known: {", ".join(BOARD_KINDS)}')
