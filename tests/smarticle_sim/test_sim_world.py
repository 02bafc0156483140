"""The sim_world fixture (smarticle_sim.testing): determinism, teardown after a failure, a missed tick, and
the bridge's bad-input counters, each over real processes and DDS."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from smarticle_sim.testing import GAIT, SimStopped, SimWorld

from tests.helpers.ros import ROOT

pytestmark = pytest.mark.integration

FAULTY = str(ROOT / 'tests' / 'helpers' / 'faulty_controller.py')


def poses_of(world: SimWorld) -> dict[int, np.ndarray]:
    return dict(world.data.poses)


def test_same_seed_same_poses_and_another_seed_other_poses(tmp_path: Path) -> None:
    runs = []
    for i, seed in enumerate((4, 4, 5)):
        with SimWorld(tmp_path / f'run{i}') as world:
            world.start(scene='random', robots=3, seed=seed, params={'start_at': 0.2})
            world.step_to(1.0)
            world.step_to(2.0)                      # stepping twice: the hold in between changes nothing
            assert world.poses().shape == (3, 3) and world.sim_time() == pytest.approx(2.0)
            runs.append(poses_of(world))
    common = sorted(set(runs[0]) & set(runs[1]))
    assert len(common) >= 0.8 * 2.0 / 0.05, 'too few pose messages arrived'
    for stamp in common:
        np.testing.assert_array_equal(runs[0][stamp], runs[1][stamp])
    last = max(set(runs[0]) & set(runs[2]))
    assert not np.array_equal(runs[0][last], runs[2][last]), 'another seed must give other poses'
    assert not np.array_equal(runs[0][last], runs[0][min(runs[0])]), 'the robots must have moved'


def inner_run(tmp_path: Path, body: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    """Run a test file using sim_world in a pytest of its own (the plugin comes from the entry point)."""
    folder = tmp_path / 'inner'
    folder.mkdir()
    (folder / 'test_inner.py').write_text(textwrap.dedent(body))
    env = {k: v for k, v in os.environ.items() if k != 'PYTEST_ADDOPTS'}
    result = subprocess.run([sys.executable, '-m', 'pytest', str(folder / 'test_inner.py'), '-q', '-p',
                             'no:cacheprovider', '--basetemp', str(tmp_path / 'inner_tmp')],
                            cwd=folder, env=env, capture_output=True, text=True, timeout=300)
    return result, folder


def test_the_fixture_tears_everything_down_after_a_failing_assertion(tmp_path: Path) -> None:
    result, folder = inner_run(tmp_path, f'''
        def test_fails(sim_world):
            sim_world.start(scene='pair', robots=2, seed=1)
            sim_world.step_to(0.5)
            pids = [p.pid for p in sim_world.started.values()]
            open({str(tmp_path / 'pids')!r}, 'w').write(' '.join(map(str, pids)))
            assert sim_world.poses().shape == (3, 3), 'deliberately wrong'
    ''')
    assert result.returncode == 1 and 'deliberately wrong' in result.stdout, result.stdout + result.stderr
    pids = [int(p) for p in (tmp_path / 'pids').read_text().split()]
    assert len(pids) == 3                                   # the bridge and two gait nodes
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


def test_a_node_that_misses_ticks_fails_the_test_with_the_bridges_line(tmp_path: Path) -> None:
    result, _ = inner_run(tmp_path, f'''
        def test_stalls(sim_world):
            sim_world.start(scene='pair', robots=2, controller=[{GAIT!r}, {FAULTY!r}],
                            controller_params={{'stall_at': 1.0}}, tick_timeout=2.0)
            sim_world.step_to(3.0)
    ''')
    assert result.returncode == 1, result.stdout + result.stderr
    line = ('lock-step: /smarticle_1/faulty_controller (robot 1) sent no joint command for the tick at sim time '
            '1.000 s (tick 20) within 2 s: stopping')
    assert line in result.stdout, result.stdout
    assert 'Traceback' not in result.stdout               # the line is the failure, nothing else


def test_step_to_raises_sim_stopped_with_that_line(tmp_path: Path) -> None:
    with SimWorld(tmp_path) as world:
        world.start(scene='pair', robots=2, controller=[FAULTY, FAULTY], controller_params={'stall_at': 0.5},
                    tick_timeout=1.0)
        with pytest.raises(SimStopped, match=r'sent no joint command for the tick at sim time 0\.500 s \(tick 10\)'):
            world.step_to(2.0)
        assert world.bridge.returncode == 4


def test_the_bridge_stops_soon_once_a_robots_controller_has_exited(tmp_path: Path) -> None:
    """Not after the 10 s tick timeout: once nobody publishes the robot's commands, in a few seconds."""
    import time

    with SimWorld(tmp_path) as world:
        world.start(scene='pair', robots=2, controller=[GAIT, FAULTY], controller_params={'exit_at': 1.0})
        world.step_to(0.5)
        started = time.monotonic()
        with pytest.raises(SimStopped, match=r'lock-step: the node publishing /smarticle_1/joint_commands \(robot 1\) '
                                             r'has exited at sim time 1\.000 s: stopping'):
            world.step_to(3.0)
        assert time.monotonic() - started < 9.0 and world.bridge.returncode == 4


def test_bad_commands_are_counted_logged_once_and_the_other_robot_runs_on(sim_world: SimWorld) -> None:
    sim_world.start(scene='pair', robots=2, controller=[GAIT, FAULTY], controller_params={'bad_at': 0.3})
    sim_world.step_to(1.0)
    # the bridge looks for unknown robots every 2 s (wall) and reports its counters every second while held
    assert sim_world.spin_until(lambda: 'unknown_robot_ids' in sim_world.counters(), 10.0), sim_world.output()
    counters = sim_world.counters()
    assert counters['nonfinite_targets'] == 1 and counters['future_stamps'] == 1, counters
    assert counters['unknown_robot_ids'] == 1, counters
    sim_world.step_to(2.0)
    log = sim_world.output()
    for cause in ('nonfinite_targets', 'future_stamps', 'unknown_robot_ids'):
        lines = [line for line in log.splitlines() if f'[{cause}:' in line]
        assert len(lines) == 1, log
        assert '/smarticle_1/faulty_controller' in lines[0]
    moved = np.linalg.norm(sim_world.poses(2.0)[0, :2] - sim_world.poses(0.0)[0, :2])
    assert moved > 0.0     # robot 0's gait kept the sim running
