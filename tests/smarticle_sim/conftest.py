"""Fixtures of the smarticle_sim core tests: the small robot, a gait, simple scenes."""

from __future__ import annotations

import pytest
from smarticle_common.gait import GaitConfig

from smarticle_sim.settings import SimConfig


@pytest.fixture
def config() -> SimConfig:
    """Default settings with the paper's small robot."""
    return SimConfig()


@pytest.fixture
def gait90() -> GaitConfig:
    """The paper's square gait at alpha_max = 90 degrees."""
    return GaitConfig.from_degrees(90.0)

