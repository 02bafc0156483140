"""Checking joint commands: one code path for the hardware servo bridge and the simulation bridge.

A command is JointState-like (names, positions, velocities). ``check_command`` returns the usable
targets and speed limits per known joint plus a warning and a counter for everything it dropped or
changed: unknown joint names are ignored, non-finite targets dropped, out-of-range targets clamped,
bad speed limits (NaN, infinite, zero or negative) replaced by the fallback speed, and speed limits above
the servo's top speed (``max_speed``) clamped to it: a command can never ask for an unlimited servo.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field


@dataclass
class CheckedCommand:
    """A joint command after checking: usable targets and speeds by joint, and what was wrong."""

    targets: dict[str, float] = field(default_factory=dict)
    speeds: dict[str, float] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)

    def flag(self, counter: str, message: str) -> None:
        """Record a problem: bump ``counter`` and keep ``message``."""
        self.counts[counter] = self.counts.get(counter, 0) + 1
        self.warnings.append(message)


def check_command(names: Sequence[str], positions: Sequence[float], velocities: Sequence[float],
                  limits: dict[str, tuple[float, float]], fallback_speed: float,
                  max_speed: float | None = None) -> CheckedCommand:
    """Check one JointState-like command against the joints' angle ``limits`` (rad)."""
    out = CheckedCommand()
    if len(positions) != len(names):
        out.flag('rejected_commands', f'joint command ignored: {len(names)} names but {len(positions)} '
                                      'positions')
        return out
    if len(velocities) not in (0, len(names)):
        out.flag('rejected_commands', f'joint command ignored: {len(names)} names but {len(velocities)} '
                                      'velocities (give one per name, or none)')
        return out
    if len(set(names)) != len(names):
        out.flag('rejected_commands', f'joint command ignored: repeated joint names {list(names)}')
        return out
    for i, name in enumerate(names):
        if name not in limits:
            out.flag('unknown_joints', f'joint command: unknown joint {name!r} ignored (known: '
                                       f'{", ".join(limits)})')
            continue
        target = float(positions[i])
        if not math.isfinite(target):
            out.flag('nonfinite_targets', f'joint command: {name} target {target} is not finite; '
                                          'keeping the previous target')
            continue
        lo, hi = limits[name]
        if not lo <= target <= hi:
            clamped = min(max(target, lo), hi)
            out.flag('clamped_targets', f'joint command: {name} target {math.degrees(target):.1f} deg is '
                                        f'outside {math.degrees(lo):.1f}..{math.degrees(hi):.1f} deg; '
                                        f'clamped to {math.degrees(clamped):.1f}')
            target = clamped
        speed = float(velocities[i]) if velocities else fallback_speed
        if not (math.isfinite(speed) and speed > 0.0):
            out.flag('bad_speeds', f'joint command: {name} speed limit {speed} is not a positive number; '
                                   f'using {fallback_speed:.3g} rad/s')
            speed = fallback_speed
        if max_speed is not None and speed > max_speed:
            out.flag('clamped_speeds', f'joint command: {name} speed limit {speed:.3g} rad/s is above the '
                                       f"servo's {max_speed:.3g} rad/s; clamped to it")
            speed = max_speed
        out.targets[name] = target
        out.speeds[name] = speed
    return out
