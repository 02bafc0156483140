"""Playback timing without ROS: options, the time window of a bag to play, and a pausable rate clock.

All times are integer nanoseconds. Wall time is any monotonic clock; bag time is the log time of
the recorded messages. ``PlaybackClock`` maps one to the other at ``rate`` and can be paused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import OptionError

NS = 1_000_000_000


@dataclass(frozen=True)
class PlaybackOptions:
    """What ``smarticle-bag play`` does: rate, loop, window, pause, /clock and start delay."""

    rate: float = 1.0
    loop: bool = False
    start_offset: float = 0.0
    playback_duration: float = 0.0
    start_paused: bool = False
    clock: float = 0.0
    delay: float = 0.0

    def __post_init__(self) -> None:
        """Reject a rate <= 0, negative times and non-finite values with a clear message."""
        for name in ('rate', 'start_offset', 'playback_duration', 'clock', 'delay'):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise OptionError(f'{name} must be a finite number, got {value}')
        if self.rate <= 0.0:
            raise OptionError(f'rate must be > 0 (1.0 = recorded speed), got {self.rate:g}')
        if self.start_offset < 0.0:
            raise OptionError(f'start offset must be >= 0 s, got {self.start_offset:g}')
        if self.playback_duration < 0.0:
            raise OptionError(
                f'playback duration must be >= 0 s (0 = to the end), got {self.playback_duration:g}')
        if self.clock < 0.0:
            raise OptionError(f'clock rate must be >= 0 Hz (0 = no /clock), got {self.clock:g}')
        if self.delay < 0.0:
            raise OptionError(f'delay must be >= 0 s, got {self.delay:g}')


def window(bag_start: int, bag_end: int, options: PlaybackOptions) -> tuple[int, int]:
    """Return the (first, last) bag times to play; raise OptionError if the offset is past the end."""
    first = bag_start + round(options.start_offset * NS)
    if first > bag_end:
        raise OptionError(f'start offset {options.start_offset:g} s is past the end of the bag '
                          f'({(bag_end - bag_start) / NS:.3f} s long)')
    last = bag_end
    if options.playback_duration > 0.0:
        last = min(bag_end, first + round(options.playback_duration * NS))
    return first, last


class PlaybackClock:
    """Bag time as a function of wall time: ``bag = anchor_bag + (wall - anchor_wall) * rate``, pausable."""

    def __init__(self, rate: float) -> None:
        if rate <= 0.0:
            raise OptionError(f'rate must be > 0, got {rate:g}')
        self.rate = rate
        self._anchor_wall = 0
        self._anchor_bag = 0
        self._paused_at: int | None = None

    def start(self, wall: int, bag: int, paused: bool = False) -> None:
        """Make bag time ``bag`` correspond to wall time ``wall``; optionally start paused."""
        self._anchor_wall, self._anchor_bag = wall, bag
        self._paused_at = wall if paused else None

    @property
    def paused(self) -> bool:
        """True while paused."""
        return self._paused_at is not None

    def now(self, wall: int) -> int:
        """Return the bag time at wall time ``wall`` (frozen while paused)."""
        at = self._paused_at if self._paused_at is not None else wall
        return self._anchor_bag + round((at - self._anchor_wall) * self.rate)

    def pause(self, wall: int) -> None:
        """Freeze bag time at its value at ``wall``."""
        if self._paused_at is None:
            self._paused_at = wall

    def resume(self, wall: int) -> None:
        """Continue from the frozen bag time."""
        if self._paused_at is not None:
            self._anchor_bag = self.now(self._paused_at)
            self._anchor_wall = wall
            self._paused_at = None

    def wall_of(self, bag: int) -> int | None:
        """Return the wall time at which bag time ``bag`` is reached (None while paused)."""
        if self._paused_at is not None:
            return None
        return self._anchor_wall + math.ceil((bag - self._anchor_bag) / self.rate)
