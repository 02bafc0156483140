"""Spinning test nodes until something happens."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

from smarticle_common.launching import ProcessGroup, executable

__all__ = ['ROOT', 'NodeProcesses', 'call_service', 'executable', 'spin_until']

ROOT = Path(__file__).resolve().parents[2]


class NodeProcesses(ProcessGroup):
    """The project's ProcessGroup with this test run's environment (the ``nodes`` fixture)."""


def spin_until(node: object, predicate: Callable[[], bool], timeout: float) -> bool:
    """Spin ``node`` until ``predicate()`` is true or ``timeout`` seconds pass; return the predicate."""
    import rclpy

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        rclpy.spin_once(node, timeout_sec=0.05)
    return predicate()


def call_service(node: Any, srv_type: Any, service: str, request: Any, timeout: float = 15.0,
                 attempts: int = 1) -> Any:
    """Call ``service`` once it is up and return its answer; an idempotent request may be sent ``attempts``
    times. Over DDS a reply can be lost when the service's reply writer has not yet matched a new client's
    reader (``wait_for_service`` only sees the request path), so a query (get state, get / set the same
    parameter) is sent again rather than waited on; a request with effects (a lifecycle transition) is not."""
    client = node.create_client(srv_type, service)
    try:
        assert client.wait_for_service(timeout_sec=timeout), f'no service {service}'
        for _ in range(attempts):
            future = client.call_async(request)
            if spin_until(node, future.done, timeout / attempts):
                return future.result()
            client.remove_pending_request(future)
        raise AssertionError(f'{service}: no answer to {attempts} request(s) in {timeout} s')
    finally:
        node.destroy_client(client)
