"""`smarticle-bag analyze`: a bag of poses goes through the glider analysis to a table and a figure."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from smarticle_bags import cli
from smarticle_bags.writer import BagWriter, WriterOptions

from tests.helpers.bags import STORE, T0


def glider_poses(i: int, dt: float, speed: float = 0.002, wobble: float = 0.0) -> bytes:
    """Two anti-aligned robots 1.3 BL apart moving together in +x at ``speed`` (m/s; 0: a still pair, each robot
    wobbling by ``wobble`` m within the gait period), a third far away at rest."""
    types = STORE.types
    t = i * dt
    dx = wobble * math.sin(2.0 * math.pi * t / 1.6)
    xs = [(speed * t + dx, 0.0, math.pi / 2), (speed * t - dx, 0.07, -math.pi / 2), (0.25, 0.25, 0.0)]
    poses = [types['geometry_msgs/msg/Pose'](
        position=types['geometry_msgs/msg/Point'](x=x, y=y, z=0.0),
        orientation=types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(h / 2), w=math.cos(h / 2)))
        for x, y, h in xs]
    stamp = types['builtin_interfaces/msg/Time'](sec=int(t), nanosec=int(round((t % 1) * 1e9)))
    msg = types['geometry_msgs/msg/PoseArray'](header=types['std_msgs/msg/Header'](stamp=stamp, frame_id='arena'),
                                               poses=poses)
    return bytes(STORE.serialize_cdr(msg, 'geometry_msgs/msg/PoseArray'))


def test_analyze_finds_the_glider_in_a_bag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dt, frames = 0.1, 16 * 40  # 40 gait periods of 1.6 s
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(frames):
            writer.write('/smarticles/poses', glider_poses(i, dt), T0 + round(i * dt * 1e9))
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag'), '--plot', str(tmp_path / 'g.png')])
    out = capsys.readouterr().out
    assert exit_info.value.code == 0, out
    rows = [line for line in out.splitlines() if ' C1 ' in line]
    assert len(rows) == 1 and ' glider ' in rows[0], out        # one glider, pair (0, 1), anti-aligned
    assert '1 bound pair, 1 of them a glider (0-1 C1)' in out
    assert (tmp_path / 'g.png').stat().st_size > 10_000


def test_analyze_writes_nothing_unless_asked(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Reading a bag writes nothing: no figure beside the bag (or anywhere) without --plot."""
    dt, frames = 0.1, 16 * 40
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(frames):
            writer.write('/smarticles/poses', glider_poses(i, dt), T0 + round(i * dt * 1e9))
    before = sorted(p for p in tmp_path.rglob('*'))
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag')])
    out = capsys.readouterr().out
    assert exit_info.value.code == 0, out
    assert 'wrote' not in out
    assert sorted(p for p in tmp_path.rglob('*')) == before


def test_a_still_in_phase_pair_is_a_bound_pair_not_a_glider(tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    """60 s of a pair bound and still (its centre moves 0.01 W): a C1 bound pair, and no glider."""
    dt, frames = 0.1, 600
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(frames):
            writer.write('/smarticles/poses', glider_poses(i, dt, speed=0.054 * 0.01 / 60.0, wobble=0.005),
                         T0 + round(i * dt * 1e9))
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag')])
    out = capsys.readouterr().out
    assert exit_info.value.code == 0, out
    assert '1 bound pair, no glider' in out, out
    (row,) = [line for line in out.splitlines() if ' C1 ' in line]
    assert ' bound pair ' in row and ' False ' in row and ' glider ' not in row, out
    assert 'glider: a bound pair whose centre of mass travels >= 1 W per 100 periods' in out


def test_analyze_rejects_a_bad_rule_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
        for i in range(20):
            writer.write('/smarticles/poses', glider_poses(i, 0.1), T0 + round(i * 0.1e9))
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag'), '--travel-min', 'nan'])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.strip().splitlines()) == 1 and 'travel_min' in err, err


def test_analyze_of_a_bag_without_poses_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with BagWriter(tmp_path / 'bag', WriterOptions()) as writer:
        writer.add_topic('/smarticles/poses', 'geometry_msgs/msg/PoseArray')
    with pytest.raises(SystemExit) as exit_info:
        cli.main(['analyze', str(tmp_path / 'bag')])
    assert exit_info.value.code == 2
    assert 'nothing to analyse' in capsys.readouterr().err
