"""The README's main command in a short mode: the whole sim-in-the-loop stack, summary and figures."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest


@pytest.mark.integration
@pytest.mark.slow
def test_demo_runs_the_stack_and_writes_its_outputs(tmp_path: Path) -> None:
    out = tmp_path / 'demo'
    # a relative output folder, as ./demo.sh uses (out/demo): the launch files must not resolve it themselves
    proc = subprocess.run([sys.executable, '-m', 'smarticle_bringup.demo', '--robots', '3', '--periods', '4',
                           '--out', 'demo'], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert 'gliders (pairs bound' in proc.stdout and 'net displacement' in proc.stdout
    data = np.load(out / 'poses.npz')
    assert data['poses'].shape[1:] == (3, 3)
    assert data['time'][-1] == pytest.approx(4 * 1.6, abs=0.2)
    assert np.all(np.isfinite(data['poses']))
    assert (out / 'trajectories.png').stat().st_size > 10_000
    host = list((out / 'logs').glob('smarticle-compose-*.log'))        # composed by default
    assert 'composed in one process' in proc.stdout and len(host) == 1
    assert 'live glider monitor, last report' in proc.stdout
    assert '3 feedback nodes' in proc.stdout and 'feedback halts per robot: 0:' in proc.stdout   # on by default
    assert host[0].read_text().count('windows') == 3                   # each feedback node started
    graph = (out / 'nodes.txt').read_text().split()              # the ROS graph during the run
    assert 'every fully qualified name distinct' in proc.stdout and len(graph) == len(set(graph)), graph
    for k in range(3):                                           # each robot's nodes in its namespace
        assert f'/smarticle_{k}/gait' in graph and f'/smarticle_{k}/feedback' in graph, graph
    assert {'/sim_bridge', '/glider_monitor'} <= set(graph), graph
    from smarticle_bags.arrays import read_poses
    from smarticle_bags.reader import BagReader

    recorded = read_poses(BagReader(out / 'bag'))   # the bag holds the same poses the demo analysed
    assert recorded.xyh.shape[1] == 3 and len(recorded.stamp) >= 0.9 * len(data['time'])


@pytest.mark.integration
@pytest.mark.slow
def test_demo_without_feedback_runs_the_open_loop_gait_only(tmp_path: Path) -> None:
    out = tmp_path / 'demo'
    proc = subprocess.run([sys.executable, '-m', 'smarticle_bringup.demo', '--robots', '2', '--periods', '3',
                           '--no-feedback', '--separate', '--out', str(out)], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert 'feedback nodes' not in proc.stdout and 'feedback halts' not in proc.stdout
    assert 'as separate processes' in proc.stdout
    assert not list((out / 'logs').glob('feedback-*.log')) and len(list((out / 'logs').glob('gait-*.log'))) == 2
    assert np.load(out / 'poses.npz')['poses'].shape[1:] == (2, 3)


def test_clock_noise_gives_each_robot_the_batch_paths_clock_offset(tmp_path: Path) -> None:
    """--clock-noise writes each robot's clock_rate_offset (gait and feedback alike): the batch path's draw."""
    import yaml
    from smarticle_bringup.demo import build_parser, write_params
    from smarticle_sim.noise import clock_rates
    from smarticle_sim.settings import NoiseConfig

    path = tmp_path / 'params.yaml'
    write_params(build_parser().parse_args(['--robots', '3', '--seed', '4', '--clock-noise']), path)
    data = yaml.safe_load(path.read_text(encoding='utf-8'))
    expected = clock_rates(NoiseConfig.paper(), 3, 4)
    assert np.any(expected != 0.0)
    for k in range(3):
        gait, feedback = (data[f'/smarticle_{k}/{node}']['ros__parameters'] for node in ('gait', 'feedback'))
        assert gait['clock_rate_offset'] == feedback['clock_rate_offset'] == expected[k]
        assert gait['phase'] == feedback['phase']
    write_params(build_parser().parse_args(['--robots', '3', '--seed', '4']), path)
    data = yaml.safe_load(path.read_text(encoding='utf-8'))
    assert all('clock_rate_offset' not in data[f'/smarticle_{k}/gait']['ros__parameters'] for k in range(3))
