"""`smarticle-bag clocks` on a recorded sim run whose gait nodes run fast and slow clocks (clock_rate_offset).

The lock-step sim bridge, two gait nodes with known clock errors and phases, and the recorder (joint commands
and states, use_sim_time) run as real processes over DDS; the command's table holds each true rate inside its
95 % interval and each phase within its half width, from joint commands and from joint states.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from smarticle_bags import cli
from smarticle_bags.recording import start_recording

from tests.helpers.ros import NodeProcesses

pytestmark = pytest.mark.integration

OFFSETS = (0.004, -0.003)
PHASES = (0.0, 0.1)
DURATION = 60.0
ROW = re.compile(r'^\s+(\d+)\s+(\w+)\s+(\d+)\s+([\d.]+)\s+\[([\d.]+), ([\d.]+)\]\s+\S+\s+([\d.]+)\s+([\d.]+)')


def record_run(nodes: NodeProcesses, bag: Path) -> None:
    """A 60 s pair run of gait nodes with clock errors, recorded in sim time."""
    topics = ['/clock', '/smarticles/poses', '/smarticles/start'] + [
        f'/smarticle_{k}/{leaf}' for k in range(2) for leaf in ('joint_states', 'joint_commands')]
    for k in range(2):
        nodes.start('gait', '--ros-args', '-p', f'robot_id:={k}', '-p', 'lockstep:=true', '-p', 'use_sim_time:=true',
                    '-p', f'clock_rate_offset:={OFFSETS[k]}', '-p', f'phase:={PHASES[k]}', '-p', 'start_at:=0.5')
    rec = start_recording(nodes, bag, topics, ros_args=['-p', 'use_sim_time:=true'])
    bridge = nodes.start('sim_bridge', '--ros-args', '-p', 'scene:=pair', '-p', 'robots:=2', '-p', 'pair_r:=3.0',
                         '-p', f'duration:={DURATION}', '-p', 'start_at:=0.5', '-p', 'wait_for_subscribers:=1')
    assert rec.wait_subscribed(timeout=60.0), nodes.output(rec.proc)
    assert bridge.wait(timeout=300) == 0, nodes.output(bridge)
    rec.stop()


def test_clocks_of_a_recorded_run_hold_the_true_rates(nodes: NodeProcesses, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    bag = tmp_path / 'bag'
    record_run(nodes, bag)
    for source in ('commands', 'states'):
        with pytest.raises(SystemExit) as done:
            cli.main(['clocks', str(bag), '--source', source])
        out = capsys.readouterr().out
        assert done.value.code == 0, out
        assert 'phase at 0.500 s, the gait start (/smarticles/start)' in out
        rows = [ROW.match(line) for line in out.splitlines()]
        found = {int(m.group(1)): m for m in rows if m}
        assert sorted(found) == [0, 1], out
        for k, m in found.items():
            rate, lo, hi = (float(m.group(i)) for i in (4, 5, 6))
            phase, halfwidth = float(m.group(7)), float(m.group(8))
            assert m.group(2) == source and int(m.group(3)) >= 140, out
            assert lo <= 1.0 + OFFSETS[k] <= hi, out
            assert hi < 1.0 or lo > 1.0, out           # a clock 0.3 % off is told from a true one
            assert abs((phase - PHASES[k] + 0.5) % 1.0 - 0.5) <= halfwidth, out
