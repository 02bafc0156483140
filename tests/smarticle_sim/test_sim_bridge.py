"""The sim bridge: its pure core, and the real node in lock-step with real gait nodes over DDS."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from smarticle_common import topics
from smarticle_common.gait import TIME_EPS, GaitConfig, SquareGait, open_loop_angles
from smarticle_sim.bridge import BridgeSettings, SimBridgeCore
from smarticle_sim.errors import ConfigError
from smarticle_sim.testing import SimWorld

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize('changes, field', [
    ({'publish_period': 0.051}, 'publish_period'),
    ({'scene': 'cloud'}, 'scene'),
    ({'mode': 'fast'}, 'mode'),
    ({'preset': 'huge'}, 'preset'),
    ({'time_step': 0.0}, 'time_step'),
    ({'robots': 0}, 'robots'),
    ({'seed': -1}, 'seed'),
])
def test_invalid_settings_name_the_field(changes: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        BridgeSettings.defaults(**changes)


def test_unknown_parameter_is_refused() -> None:
    with pytest.raises(ConfigError, match='bogus'):
        BridgeSettings.defaults(bogus=1)


def drive_with_gait_cores(core: SimBridgeCore, gaits: list[SquareGait], periods: int) -> list[np.ndarray]:
    """Run the core as the lock-step ROS path does, with the gait cores answering every barrier."""
    out = [core.physics.poses().copy()]
    for _ in range(periods):
        for k, gait in enumerate(gaits):
            cmd = gait.command(core.time_ns * 1e-9 + TIME_EPS)   # as the gait node asks
            core.apply_command(k, list(topics.JOINT_NAMES), list(cmd.targets), [cmd.speed] * 2, core.time_ns)
        assert core.waiting_for() == []
        core.advance()
        out.append(core.physics.poses().copy())
    return out


def test_core_barrier_waits_for_every_robot_and_drops_bad_commands() -> None:
    core = SimBridgeCore(BridgeSettings.defaults(scene='pair'))
    try:
        assert core.waiting_for() == [0, 1]
        bad = core.apply_command(0, ['arm1', 'arm2', 'tail'], [math.nan, 3.0, 0.0], [], core.time_ns)
        assert bad.counts == {'nonfinite_targets': 1, 'unknown_joints': 1, 'clamped_targets': 1}
        assert core.waiting_for() == [1]
        assert np.all(np.isfinite(core.physics.poses()))
    finally:
        core.close()


def test_fsr_samples_hold_the_peak_of_each_publish_period() -> None:
    """The bridge's FSR sample is the peak since the last one (as in the batch feedback path), not the instant.

    With the FSR window set to one step each step's reading is that step's force, so the held peak is never
    below the instant's force (the averaging over a longer window is tested in test_physics.py).
    """
    settings = BridgeSettings.defaults(scene='pair', preset='feedback', pair_r=1.3, pair_theta_deg=0.0,
                                       pair_phi_deg=350.0, pair_phase_1=0.25, publish_period=1.0 / 60.0)
    settings = replace(settings, sim=settings.sim.with_physics(fsr_window=settings.sim.physics.time_step))
    core = SimBridgeCore(settings)
    gaits = [SquareGait(GaitConfig.from_degrees(90.0, phase=p)) for p in (0.0, 0.25)]
    for gait in gaits:
        gait.start(0.0)
    held, instant = [], []
    try:
        core.fsr_sample([0, 1])
        for _ in range(2 * 96):                          # two gait periods of control ticks
            for k, gait in enumerate(gaits):
                cmd = gait.command(core.time_ns * 1e-9 + TIME_EPS)   # as the gait node asks
                core.apply_command(k, list(topics.JOINT_NAMES), list(cmd.targets), [cmd.speed] * 2, core.time_ns)
            core.advance()
            instant.append(core.physics.fsr([0, 1]))
            held.append(core.fsr_sample([0, 1]))
        assert core.runner.step_hooks
        core.fsr_sample([])
        assert not core.runner.step_hooks, 'nobody listens: no per-step FSR work'
    finally:
        core.close()
    held_arr, instant_arr = np.array(held), np.array(instant)
    assert np.all(held_arr >= instant_arr)
    assert (held_arr.max(axis=(1, 2)) > 1.0).sum() > (instant_arr.max(axis=(1, 2)) > 1.0).sum()


def test_core_is_deterministic_for_the_same_seed() -> None:
    runs = []
    for _ in range(2):
        core = SimBridgeCore(BridgeSettings.defaults(robots=3, scene='random', seed=4))
        gaits = [SquareGait(GaitConfig.from_degrees(90.0)) for _ in range(3)]
        for gait in gaits:
            gait.start(0.5)
        try:
            runs.append(np.array(drive_with_gait_cores(core, gaits, 40)))
        finally:
            core.close()
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.integration
def test_gait_nodes_drive_the_sim_in_lockstep_deterministically(tmp_path: Path) -> None:
    duration = 4.0
    runs: list[dict[int, np.ndarray]] = []
    states: dict[int, np.ndarray] = {}
    for run in range(2):
        with SimWorld(tmp_path / f'run{run}') as world:
            world.start(scene='pair', params={'pair_r': 2.5, 'start_at': 0.5},
                        controller_params={'start_at': 0.5}, joint_states=run == 0)
            world.step_to(duration)
            runs.append(dict(world.data.poses))
            if run == 0:
                states = dict(world.joint_states(0))
    common = sorted(set(runs[0]) & set(runs[1]))
    assert len(common) >= 0.8 * duration / 0.05, 'too few pose messages arrived'
    for stamp in common:
        assert np.array_equal(runs[0][stamp], runs[1][stamp]), f'runs differ at t = {stamp * 1e-9:.2f} s'
    # robot 0's joint states follow the square gait: at the end of each quarter the arms sit at its corner
    gait = GaitConfig.from_degrees(90.0)
    checked = 0
    for stamp, angles in states.items():
        tau = (stamp * 1e-9 - 0.5) / gait.period
        if tau > 0 and 0.85 < (4 * tau) % 1.0 < 0.99:   # late in a quarter: the stroke is over
            assert tuple(angles) == pytest.approx(open_loop_angles(gait, tau), abs=math.radians(6.0))
            checked += 1
    assert checked >= 8


@pytest.mark.integration
def test_bridge_core_and_ros_path_agree(sim_world: SimWorld) -> None:
    duration = 2.0
    sim_world.start(scene='pair', gliders=True)        # the glider monitor listens too: it changes nothing
    sim_world.step_to(duration)
    assert sim_world.glider_reports, 'the glider monitor reported nothing'
    assert all(stamp <= round(duration * 1e9) for stamp, _ in sim_world.glider_reports)
    poses = {stamp: p[:, :2] for stamp, p in sim_world.data.poses.items()}

    core = SimBridgeCore(BridgeSettings.defaults(scene='pair'))
    gaits = [SquareGait(GaitConfig.from_degrees(90.0)) for _ in range(2)]
    for gait in gaits:
        gait.start(0.5)
    try:
        batch = drive_with_gait_cores(core, gaits, round(duration / 0.05))
    finally:
        core.close()
    matched = 0
    for i, ref in enumerate(batch):
        stamp = round(i * 0.05 * 1e9)
        if stamp in poses:
            assert np.array_equal(poses[stamp], ref[:, :2]), f'differs at t = {i * 0.05:.2f} s'
            matched += 1
    assert matched >= 0.8 * len(batch)
