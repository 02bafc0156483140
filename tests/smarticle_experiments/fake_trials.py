"""User-defined trial kinds for the engine tests (``kind: tests.smarticle_experiments.fake_trials:NAME``)."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from typing import Any


def sleepy(params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """Sleep ``params['sleep']`` seconds (a slow trial without CPU load); report the worker's pid."""
    time.sleep(float(params.get('sleep', 1.0)))
    return {'pid': os.getpid(), 'value': seed * 10, 'trouble': ''}


def flaky(params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """Raise for the seeds in ``params['fail']``, else return a number."""
    if seed in params.get('fail', []):
        raise RuntimeError(f'seed {seed} fails on purpose')
    return {'value': seed, 'trouble': ''}
