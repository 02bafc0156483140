"""A two-minute soak of the composed lock-step stack (bench_soak.py's one hour, shortened): 7 robots, feedback,
the glider monitor and the recorder; nothing lost, an intact bag, the batch core's final poses bit for bit."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.benchmarks.bench_soak import soak

pytestmark = [pytest.mark.integration, pytest.mark.slow]

#: Two simulated minutes: a whole number of publish periods (0.05 s).
DURATION = 120.0


def test_two_minute_soak_loses_nothing_and_ends_on_the_batch_cores_poses(tmp_path: Path) -> None:
    """Every /clock and /smarticles/poses message the sim published is in the bag, the bag passes its check,
    and the stack's final poses are the batch core's for the same seed; memory is sampled for every process."""
    result = soak(DURATION, robots=7, sample=2.0, out=tmp_path)
    assert not result.problems and result.exit_code == 0, result.problems
    ticks = round(DURATION / 0.05)
    assert result.published['/smarticles/poses'] == ticks + 1, result.published   # t = 0 and every period after
    assert result.lost == {'/clock': 0, '/smarticles/poses': 0}, (result.published, result.recorded)
    assert result.bag_ok, result.bag_check
    assert result.digest == result.batch_digest, 'the final poses differ from the batch core\'s'
    assert any(name.startswith('smarticle-compose') for name in result.rss), sorted(result.rss)
    assert any(name.startswith('recorder') for name in result.rss), sorted(result.rss)
    assert result.ok
