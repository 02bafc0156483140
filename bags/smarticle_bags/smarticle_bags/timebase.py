"""The time base of a bag's log times: the sim's ``/clock`` or the wall clock. No ROS import.

A recorder with ``use_sim_time`` (``smarticle-bag record --use-sim-time``, a sim launch's ``record:=true``)
stamps each message's log time with the latest ``/clock`` it received, as ``ros2 bag record
--use-sim-time`` does, so a bag of 60 s of simulated robots lasts 60 s and plays in 60 s at rate 1
however fast the sim ran. Messages that arrive before the first ``/clock`` (a latched start, say) are
held and written at the first clock's time. The recorder states its time base in ``metadata.yaml``
(``custom_data``, key ``TIME_BASE_KEY``); ``smarticle-bag info`` prints it, and for a bag that does not
say (rosbag2's, older ones) infers it from the log times.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from .metadata import BagInfo

NS = 1_000_000_000

#: ``metadata.yaml`` ``custom_data`` key holding the time base of the log times.
TIME_BASE_KEY = 'log_time_base'

#: A wall-clock recording is never stamped before 2000-01-01: earlier log times count from a sim's start.
SIM_TIME_BEFORE = 946_684_800 * NS

#: What a recorder holds while it waits for the first /clock; beyond it, messages are dropped (and counted).
MAX_HELD_BYTES = 64 * 1024 * 1024


class TimeBase(Enum):
    """Where a bag's log times come from."""

    SIM = 'sim'     # the /clock of a simulation (use_sim_time)
    WALL = 'wall'   # the recorder's system clock (receive time)
    TRACKER = 'tracker'   # another tracker's own times, imported from its CSV (``smarticle-bag import``)


def custom_data(base: TimeBase) -> dict[str, str]:
    """Return the ``custom_data`` entries a recorder writes for ``base``."""
    return {TIME_BASE_KEY: base.value}


def time_base(info: BagInfo) -> tuple[TimeBase, bool]:
    """Return the time base of a bag and whether its metadata states it (False: inferred from the log times)."""
    stated = (info.custom_data or {}).get(TIME_BASE_KEY)
    for base in TimeBase:
        if stated == base.value:
            return base, True
    if info.message_count and info.starting_time < SIM_TIME_BEFORE:
        return TimeBase.SIM, False
    return TimeBase.WALL, False


def describe(info: BagInfo) -> str:
    """Return the ``Log time:`` text of ``smarticle-bag info``: the time base and where that is known from."""
    base, stated = time_base(info)
    if base is TimeBase.TRACKER:
        return 'tracker time (imported from a CSV\'s time column: smarticle-bag import)'
    if base is TimeBase.SIM:
        if stated:
            return 'sim time (/clock, recorded with use_sim_time)'
        return f'sim time (inferred: the log times start {info.starting_time / NS:.3f} s after the epoch)'
    if stated:
        return 'wall time (the recorder\'s receive time)'
    return 'wall time (assumed: the bag does not say)'


@dataclass
class SimLogClock:
    """Log times from ``/clock``: the latest clock received; messages before the first one are held.

    ``stamp`` returns the messages to write now, each with its log time; ``on_clock`` returns the held
    ones at the first clock's time. Held messages beyond ``max_held_bytes`` are dropped and counted.
    """

    max_held_bytes: int = MAX_HELD_BYTES
    now: int | None = None
    held: list[tuple[str, bytes]] = field(default_factory=list)
    held_bytes: int = 0
    dropped: int = 0

    @property
    def started(self) -> bool:
        """True once a /clock has arrived."""
        return self.now is not None

    def on_clock(self, ns: int) -> list[tuple[str, bytes, int]]:
        """Take a /clock time (ns); return the held messages, stamped with it, at the first one."""
        self.now = ns
        if not self.held:
            return []
        released = [(topic, data, ns) for topic, data in self.held]
        self.held, self.held_bytes = [], 0
        return released

    def stamp(self, topic: str, data: bytes) -> list[tuple[str, bytes, int]]:
        """Return ``[(topic, data, log time)]`` to write now, or [] while no /clock has arrived (held)."""
        if self.now is not None:
            return [(topic, data, self.now)]
        if self.held_bytes + len(data) > self.max_held_bytes:
            self.dropped += 1
        else:
            self.held.append((topic, data))
            self.held_bytes += len(data)
        return []
