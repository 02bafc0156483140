"""In-process delivery between the nodes a composing host runs: a hosted publisher hands its message straight to
the hosted subscribers' callbacks, as rclcpp's intra-process communication does (rclpy has none).

``connect(nodes)`` wraps, once the nodes are built, every hosted publisher of a volatile topic: while every
subscriber of its topic is hosted (the publisher's matched subscriptions are the hosted ones), ``publish`` calls
the hosted callbacks in this thread and the middleware carries nothing (no serialisation, no wait set, no
take), and with no subscriber at all nothing is done (the middleware would send to nobody); as soon as someone
outside the process subscribes (a recorder, a test, a separate process), the middleware carries the topic to
everyone, hosted subscribers included, exactly as before. A publisher looks at its topic's subscribers at most
every ``GRAPH_LOOK`` wall seconds (a look costs microseconds, and a tick publishes dozens of messages), so a
subscriber outside is served from at most that long after it matched. Nothing a node does changes: it publishes
and its callbacks run as they would on the executor, one at a time in publication order (a message published
inside a callback is delivered after that callback returns, first published first delivered).

Left to the middleware: transient-local (latched) topics, whose late subscribers need the history;
subscriptions whose callbacks take the message info; publications and subscriptions made after ``connect``.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSCompatibility, qos_check_compatible

#: Wall seconds between two looks of a wrapped publisher at its topic's subscriber count.
GRAPH_LOOK = 0.05


@dataclass
class DeliveryCounts:
    """Messages handed over in-process, sent through the middleware (by topic), and heard by nobody."""

    local: int = 0
    middleware: int = 0
    unheard: int = 0
    by_topic: dict[str, int] = field(default_factory=dict)


class LocalDelivery:
    """The in-process hand-over of one host: the FIFO of pending deliveries and the wrapped topics."""

    def __init__(self) -> None:
        self.pending: deque[tuple[Callable[[Any], None], Any]] = deque()
        self.delivering = False
        self.counts = DeliveryCounts()
        #: topic -> the hosted subscriptions served in-process.
        self.topics: dict[str, list[Any]] = {}

    def deliver(self, subscriptions: list[Any], msg: Any) -> None:
        """Run the callbacks of ``subscriptions`` with ``msg`` now, or after the callback running now."""
        self.pending.extend((sub.callback, msg) for sub in subscriptions)
        if self.delivering:
            return
        self.delivering = True
        try:
            while self.pending:
                callback, message = self.pending.popleft()
                callback(message)
        finally:
            self.delivering = False
            self.pending.clear()   # a callback raised: what it left undelivered goes with the error

    def wrap(self, publisher: Any, subscriptions: list[Any]) -> None:
        """Make ``publisher`` deliver in-process while ``subscriptions`` are all its topic has."""
        through_middleware = publisher.publish
        hosted = len(subscriptions)
        topic = publisher.topic_name
        counts = self.counts
        look = [0.0, False]   # (wall time of the next look at the subscribers, someone outside listens)

        def publish(msg: Any) -> None:
            if not isinstance(msg, publisher.msg_type):   # bytes or a wrong type: the middleware's own handling
                through_middleware(msg)
                return
            now = time.monotonic()
            if now >= look[0]:
                look[:] = now + GRAPH_LOOK, publisher.get_subscription_count() > hosted
            if look[1]:   # someone outside listens: the middleware, to all
                counts.middleware += 1
                counts.by_topic[topic] = counts.by_topic.get(topic, 0) + 1
                through_middleware(msg)
                return
            if not hosted:   # nobody listens at all: the middleware would send nothing either
                counts.unheard += 1
                return
            counts.local += 1
            self.deliver(subscriptions, msg)

        publisher.publish = publish


def _volatile(qos: Any) -> bool:
    """True for a QoS whose late joiners need no history (local delivery keeps none)."""
    return qos.durability != DurabilityPolicy.TRANSIENT_LOCAL


def connect(nodes: Iterable[Any]) -> LocalDelivery:
    """Wrap every hosted publisher of a volatile topic that hosted nodes subscribe to; return the delivery."""
    nodes = list(nodes)
    delivery = LocalDelivery()
    by_topic: dict[str, list[Any]] = {}
    refused: set[str] = set()
    for node in nodes:
        for sub in node.subscriptions:
            topic = sub.topic_name
            if sub.raw or not _volatile(sub.qos_profile) or sub._callback_type.name != 'MessageOnly':
                refused.add(topic)
            by_topic.setdefault(topic, []).append(sub)
    for node in nodes:
        for pub in node.publishers:
            topic = pub.topic_name
            if topic in refused or not _volatile(pub.qos_profile):
                continue
            # the subscriptions the middleware would match (an incompatible QoS gets nothing either way)
            subs = [sub for sub in by_topic.get(topic, ())
                    if qos_check_compatible(pub.qos_profile, sub.qos_profile)[0] != QoSCompatibility.ERROR]
            if any(sub.msg_type is not pub.msg_type for sub in subs):
                continue
            delivery.wrap(pub, subs)
            if subs:
                delivery.topics[topic] = subs
    return delivery


def share_clock(nodes: Iterable[Any]) -> int:
    """Let the hosted nodes on ``use_sim_time`` share one ``/clock`` subscription; return the nodes joined.

    Every rclpy node on sim time has a time source with its own ``/clock`` subscription whose callback sets
    the node's clock: in one process each ``/clock`` message would be taken and converted once per node. Here
    the first such node's time source keeps its subscription and sets every other node's clock too (one
    callback, the same time on every clock at once); the others' subscriptions are removed. The hosted nodes'
    ``use_sim_time`` is then theirs at start-up: turning it off at run time on the first one stops every shared
    clock. Call it before ``connect``, which then finds one hosted time-source ``/clock`` subscriber.
    """
    shared = None
    joined = 0
    for node in nodes:
        source = getattr(node, '_time_source', None)   # rclpy's TimeSource of the node (no public accessor)
        if source is None or not source.ros_time_is_active or source._clock_sub is None:
            continue
        if shared is None:
            shared = source
            continue
        node.destroy_subscription(source._clock_sub)
        source._clock_sub = None
        shared.attach_clock(node.get_clock())
        joined += 1
    return joined


def hosted_topics(delivery: LocalDelivery) -> str:
    """One line: the topics delivered in-process and their hosted subscribers."""
    if not delivery.topics:
        return 'no topic delivered in-process'
    return 'delivered in-process: ' + ', '.join(f'{t} ({len(s)})' for t, s in sorted(delivery.topics.items()))
