"""A speed-limited servo: the position moves toward the target at a constant rate, in closed form.

The Maestro reports the pulse it *commands*, not the arm's measured angle, so the servo bridge
publishes ``joint_states`` from this model, and the board emulator uses the same model for its
channels. Units are whatever the caller uses (microseconds of pulse and us/s here); rate ``inf``
means unlimited (the position jumps to the target).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class SlewModel:
    """Position of one servo that moves toward ``target`` at ``rate`` per second from time ``t0``."""

    start: float = math.nan     # position at t0 (nan = unknown: the next target is reached at once)
    target: float = math.nan
    rate: float = math.inf
    t0: float = 0.0

    @property
    def known(self) -> bool:
        """True once a target has been set (before that the position is unknown)."""
        return not math.isnan(self.target)

    def position(self, now: float) -> float:
        """Return the position at time ``now`` (nan while unknown)."""
        if math.isnan(self.start) or math.isnan(self.target):
            return self.target
        delta = self.target - self.start
        reach = self.rate * max(now - self.t0, 0.0) if math.isfinite(self.rate) else math.inf
        if abs(delta) <= reach:
            return self.target
        return self.start + math.copysign(reach, delta)

    def velocity(self, now: float) -> float:
        """Return the rate of change at ``now`` (0 when at rest or unknown)."""
        if not self.known or math.isnan(self.start) or not math.isfinite(self.rate):
            return 0.0
        pos = self.position(now)
        if pos == self.target:
            return 0.0
        return math.copysign(self.rate, self.target - self.start)

    def end_time(self) -> float:
        """When the servo reaches its target (``t0`` if it is at rest, unknown or unlimited)."""
        if math.isnan(self.start) or math.isnan(self.target) or not math.isfinite(self.rate):
            return self.t0
        return self.t0 + abs(self.target - self.start) / self.rate

    def set_target(self, target: float, now: float) -> None:
        """Head for ``target`` from wherever the servo is at ``now``."""
        self.start = self.position(now)
        self.target = float(target)
        self.t0 = now

    def set_rate(self, rate: float, now: float) -> None:
        """Change the speed limit from ``now`` on (inf or <= 0 = unlimited)."""
        self.start = self.position(now)
        self.t0 = now
        self.rate = rate if rate > 0.0 else math.inf

    def forget(self) -> None:
        """Make the position unknown (e.g. the board lost power): the next target is reached at once."""
        self.start = math.nan
        self.target = math.nan
