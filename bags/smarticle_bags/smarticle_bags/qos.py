"""Offered QoS profiles as rosbag2 stores them (metadata version 9), and their rclpy equivalents.

The pure part (``QosRecord`` and its YAML form) imports nothing from ROS; ``from_rclpy`` and
``playback_profile`` import rclpy only when called, from the nodes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import yaml

#: RMW_DURATION_INFINITE as rosbag2 writes it: (sec, nsec) of 2**63 - 1 nanoseconds.
INFINITE = (9223372036, 854775807)
_INFINITE_NS = 2**63 - 1


@dataclass(frozen=True)
class QosRecord:
    """One offered QoS profile, policies spelled as rosbag2 v9 spells them (``keep_last``, ...)."""

    history: str = 'unknown'
    depth: int = 0
    reliability: str = 'reliable'
    durability: str = 'volatile'
    deadline: tuple[int, int] = INFINITE
    lifespan: tuple[int, int] = INFINITE
    liveliness: str = 'automatic'
    liveliness_lease_duration: tuple[int, int] = INFINITE
    avoid_ros_namespace_conventions: bool = False

    def to_dict(self) -> dict[str, Any]:
        """Return the rosbag2 v9 mapping of this profile."""
        out = asdict(self)
        for key in ('deadline', 'lifespan', 'liveliness_lease_duration'):
            sec, nsec = getattr(self, key)
            out[key] = {'sec': int(sec), 'nsec': int(nsec)}
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> QosRecord:
        """Parse a rosbag2 v8 (integer enums) or v9 (names) QoS mapping."""
        names = {
            'history': ('system_default', 'keep_last', 'keep_all', 'unknown'),
            'reliability': ('system_default', 'reliable', 'best_effort', 'unknown', 'best_available'),
            'durability': ('system_default', 'transient_local', 'volatile', 'unknown', 'best_available'),
            'liveliness': ('system_default', 'automatic', 'manual_by_node', 'manual_by_topic', 'unknown',
                           'best_available'),
        }
        values: dict[str, Any] = {}
        for key, table in names.items():
            raw = data.get(key, 'unknown')
            if isinstance(raw, int) and 0 <= raw < len(table):
                raw = table[raw]
            values[key] = str(raw).lower()
        for key in ('deadline', 'lifespan', 'liveliness_lease_duration'):
            item = data.get(key) or {}
            values[key] = (int(item.get('sec', INFINITE[0])), int(item.get('nsec', INFINITE[1])))
        return cls(depth=int(data.get('depth', 0)),
                   avoid_ros_namespace_conventions=bool(data.get('avoid_ros_namespace_conventions', False)),
                   **values)


#: libyaml's safe loader where PyYAML has it (the same results, many times faster).
_LOADER: Any = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)


def dump_profiles(profiles: list[QosRecord]) -> str:
    """Return the YAML text rosbag2 puts into the mcap channel metadata ``offered_qos_profiles``."""
    if not profiles:
        return ''
    return yaml.safe_dump([p.to_dict() for p in profiles], sort_keys=False).strip()


def load_profiles(value: Any) -> list[QosRecord]:
    """Parse offered QoS profiles from metadata.yaml (a list, or the v8 YAML string) or channel metadata."""
    if not value:
        return []
    if isinstance(value, str):
        try:
            value = yaml.load(value, Loader=_LOADER)
        except yaml.YAMLError:
            return []
    if not isinstance(value, list):
        return []
    records = []
    for item in value:
        try:
            records.append(QosRecord.from_dict(item))
        except (TypeError, ValueError, KeyError, AttributeError):
            continue  # a damaged profile (e.g. from a damaged channel record) is left out
    return records


def _split_ns(ns: int) -> tuple[int, int]:
    """Return (sec, nsec) of a duration in nanoseconds, 0 and infinity as rosbag2 writes them."""
    if ns <= 0 or ns >= _INFINITE_NS:
        return INFINITE
    return ns // 1_000_000_000, ns % 1_000_000_000


def from_rclpy(profile: Any) -> QosRecord:
    """Convert an rclpy QoSProfile (e.g. a publisher's offered QoS) to a QosRecord."""
    def name(policy: Any) -> str:
        return str(getattr(policy, 'name', policy)).lower()

    return QosRecord(
        history=name(profile.history), depth=int(profile.depth), reliability=name(profile.reliability),
        durability=name(profile.durability), deadline=_split_ns(profile.deadline.nanoseconds),
        lifespan=_split_ns(profile.lifespan.nanoseconds), liveliness=name(profile.liveliness),
        liveliness_lease_duration=_split_ns(profile.liveliness_lease_duration.nanoseconds),
        avoid_ros_namespace_conventions=bool(profile.avoid_ros_namespace_conventions))


def subscription_profile(offered: list[QosRecord]) -> Any:
    """Return the rclpy QoSProfile a recorder should use to receive from all ``offered`` publishers."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    reliable = bool(offered) and all(p.reliability == 'reliable' for p in offered)
    latched = bool(offered) and all(p.durability == 'transient_local' for p in offered)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)


def playback_profile(offered: list[QosRecord]) -> Any:
    """Return the rclpy QoSProfile a player offers: the recorded one when all publishers agreed."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    best_effort = bool(offered) and all(p.reliability == 'best_effort' for p in offered)
    latched = bool(offered) and all(p.durability == 'transient_local' for p in offered)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max([10] + [p.depth for p in offered]),
                      reliability=(ReliabilityPolicy.BEST_EFFORT if best_effort
                                   else ReliabilityPolicy.RELIABLE),
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)
