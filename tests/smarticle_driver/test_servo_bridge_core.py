"""The servo bridge core on a real emulated board: commands, slew model, watchdog, FSRs, faults, reconnect."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from smarticle_driver import topics
from smarticle_driver.calibration import load_fsr_calibration
from smarticle_driver.emulator import MaestroEmulator
from smarticle_driver.errors import BridgeConfigError
from smarticle_driver.params import read_defaults_yaml
from smarticle_driver.servo_bridge_core import (NODE_NAME, PARAMS, BridgeConfig, Level, ServoBridgeCore,
                                                StepResult, check_command)
from tests.smarticle_driver.fake_board_helpers import running_emulator, wait_until

ROOT = Path(__file__).resolve().parents[2]
Command = tuple[list[str], list[float], list[float]]
LIMITS = {'arm1': (-1.5, 1.5), 'arm2': (-1.5, 1.5)}


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[MaestroEmulator]:
    with running_emulator(tmp_path / 'maestro') as emu:
        yield emu


@pytest.fixture
def core(emulator: MaestroEmulator) -> Iterator[ServoBridgeCore]:
    config = BridgeConfig(port=str(emulator.link_path), watchdog_timeout=0.2, reply_timeout=0.03,
                          reconnect_initial=0.02, reconnect_max=0.1)
    bridge = ServoBridgeCore.from_config(config)
    yield bridge
    bridge.close()


def run(core: ServoBridgeCore, seconds: float, heartbeat: Command | None = None) -> list[StepResult]:
    """Step the core at 100 Hz for ``seconds``, re-sending ``heartbeat`` every 0.1 s if given."""
    results = []
    deadline = time.monotonic() + seconds
    next_beat = time.monotonic()
    while time.monotonic() < deadline:
        if heartbeat is not None and time.monotonic() >= next_beat:
            core.handle_command(*heartbeat, time.monotonic())
            next_beat += 0.1
        results.append(core.step(time.monotonic()))
        time.sleep(0.01)
    return results


# -- pure parts ------------------------------------------------------------------------------------

def test_valid_commands_pass_and_a_missing_velocity_uses_the_fallback_speed() -> None:
    out = check_command(['arm2', 'arm1'], [0.5, -0.5], [], LIMITS, 3.0)
    assert out.targets == {'arm2': 0.5, 'arm1': -0.5} and out.speeds == {'arm1': 3.0, 'arm2': 3.0}
    assert not out.warnings


@pytest.mark.parametrize('names, positions, velocities, counter, text, accepted', [
    (['arm1', 'arm2'], [math.nan, 0.1], [1.0, 1.0], 'nonfinite_targets', 'not finite', {'arm2': 0.1}),
    (['arm1'], [math.inf], [1.0], 'nonfinite_targets', 'not finite', {}),
    (['arm1'], [2.0], [1.0], 'clamped_targets', 'clamped to 85.9', {'arm1': 1.5}),
    (['arm1', 'tail'], [0.1, 0.2], [1.0, 1.0], 'unknown_joints', "unknown joint 'tail'", {'arm1': 0.1}),
    (['arm1', 'arm2'], [0.1], [], 'rejected_commands', '2 names but 1 positions', {}),
    (['arm1', 'arm2'], [0.1, 0.2], [1.0], 'rejected_commands', 'velocities', {}),
    (['arm1', 'arm1'], [0.1, 0.2], [], 'rejected_commands', 'repeated', {}),
    (['arm1'], [0.1], [math.nan], 'bad_speeds', 'using 3 rad/s', {'arm1': 0.1}),
    (['arm1'], [0.1], [-2.0], 'bad_speeds', 'not a positive number', {'arm1': 0.1}),
])
def test_bad_commands_are_rejected_or_clamped_with_a_warning(names: list[str], positions: list[float],
                                                             velocities: list[float], counter: str, text: str,
                                                             accepted: dict[str, float]) -> None:
    out = check_command(names, positions, velocities, LIMITS, 3.0)
    assert out.counts == {counter: 1}
    assert len(out.warnings) == 1 and text in out.warnings[0], out.warnings
    assert out.targets == pytest.approx(accepted)


def test_shipped_yaml_equals_declared_defaults() -> None:
    shipped = read_defaults_yaml(str(ROOT / 'smarticle_driver' / 'config' / 'servo_bridge.yaml'), NODE_NAME)
    assert shipped == {spec.name: spec.default for spec in PARAMS}
    config = BridgeConfig.from_values(shipped)
    assert config.servo_channels == (0, 1) and config.fsr_channels == (2, 3, 4, 5)
    assert config.fsr_rate_hz >= 100.0
    assert config.servo_calibration_path().name == 'servo_calibration.yaml'


@pytest.mark.parametrize('kwargs, text', [
    ({'fsr_channels': (2, 3, 4, 1)}, 'must all differ'),
    ({'board': 'dynamixel'}, 'board must be one of'),
    ({'reconnect_initial': 5.0, 'reconnect_max': 1.0}, 'must not exceed'),
    ({'port': ''}, 'serial device'),
])
def test_contradictory_settings_are_refused(kwargs: dict[str, object], text: str) -> None:
    with pytest.raises(BridgeConfigError, match=text):
        BridgeConfig(**{'port': '/dev/null', **kwargs})  # type: ignore[arg-type]


# -- with the emulated board -------------------------------------------------------------------------

def test_commands_reach_the_board_and_joint_states_follow_the_slew_model(core: ServoBridgeCore,
                                                                         emulator: MaestroEmulator) -> None:
    first = core.step(time.monotonic())
    assert any('opened' in e for e in first.events)
    assert first.joint_positions is None, 'no joint states before the first command: position unknown'
    assert first.fsr_newtons == (0.0, 0.0, 0.0, 0.0)
    assert core.handle_command(['arm1', 'arm2'], [0.5, 0.5], [2.0, 2.0], time.monotonic()) == []
    start = core.step(time.monotonic())
    assert start.joint_positions == pytest.approx((0.5, 0.5), abs=1e-3)   # a fresh board jumps to it
    assert [(r.channel, r.pulse_us) for r in emulator.targets()] == [(0, 1800.0), (1, 1200.0)]
    assert emulator.speed(0) == round(2.0 * 600 / 25) == emulator.speed(1)
    move: Command = (['arm1'], [-0.5], [2.0])                          # 1 rad at 2 rad/s: 0.5 s
    results = run(core, 0.25, heartbeat=move)
    moving = results[-1]
    assert moving.joint_positions is not None and moving.joint_velocities is not None
    assert -0.5 < moving.joint_positions[0] < 0.3
    assert moving.joint_positions[1] == pytest.approx(0.5, abs=1e-3)
    assert moving.joint_velocities[0] == pytest.approx(-2.0, rel=0.01)
    emulated = emulator.position_us(0)
    modelled = 1500 + 600 * core.step(time.monotonic()).joint_positions[0]  # type: ignore[index]
    assert modelled == pytest.approx(emulated, abs=600 * math.radians(1.0))   # the model mirrors the board
    final = run(core, 0.4, heartbeat=move)[-1]
    assert final.joint_positions == pytest.approx((-0.5, 0.5), abs=1e-3)
    assert final.joint_velocities == (0.0, 0.0)


def test_an_unchanged_heartbeat_command_sends_nothing_new(core: ServoBridgeCore,
                                                          emulator: MaestroEmulator) -> None:
    core.step(time.monotonic())
    for _ in range(5):
        core.handle_command(['arm1', 'arm2'], [0.2, 0.3], [5.0, 5.0], time.monotonic())
    core.step(time.monotonic())
    assert len(emulator.targets()) == 2


def test_the_watchdog_holds_the_arms_where_they_are_and_a_new_command_releases_them(
        core: ServoBridgeCore, emulator: MaestroEmulator) -> None:
    core.step(time.monotonic())
    core.handle_command(['arm1', 'arm2'], [-1.0, 0.0], [], time.monotonic())
    core.step(time.monotonic())
    core.handle_command(['arm1', 'arm2'], [1.0, 0.0], [1.0, 1.0], time.monotonic())   # 2 s move
    results = run(core, 0.35)
    events = [e for r in results for e in r.events]
    assert any(e.startswith('watchdog') for e in events), events
    assert core.holding and core.counters.watchdog_trips == 1
    assert core.status(time.monotonic()).level is Level.WARN
    held = emulator.targets()[-1]
    assert held.channel == 0 and 1500 - 600 < held.pulse_us < 1500 + 600 * (-1.0 + 0.45), held
    time.sleep(0.1)
    assert emulator.position_us(0) == pytest.approx(held.pulse_us, abs=0.3)   # stopped, not still moving
    positions = run(core, 0.05)[-1].joint_positions
    assert positions is not None and positions[0] == pytest.approx((held.pulse_us - 1500) / 600, abs=1e-3)
    core.handle_command(['arm1', 'arm2'], [1.0, 0.0], [1.0, 1.0], time.monotonic())
    assert not core.holding
    assert wait_until(lambda: emulator.targets()[-1].pulse_us == 2100.0, 1.0)


def test_fsr_voltages_become_newtons_through_the_calibration(core: ServoBridgeCore,
                                                             emulator: MaestroEmulator) -> None:
    fsrs = load_fsr_calibration(ROOT / 'smarticle_driver' / 'config' / 'fsr_calibration.yaml')
    volts = (0.0, 1.0, 2.5, 4.2)
    for channel, v in zip((2, 3, 4, 5), volts, strict=True):
        emulator.set_voltage(channel, v)
    result = core.step(time.monotonic())
    counts = tuple(round(v / 5.0 * 1023) for v in volts)
    assert result.fsr_counts == counts
    expected = [fsrs[face].newtons(c) for face, c in zip(topics.FSR_FACES, counts, strict=True)]
    assert result.fsr_newtons == pytest.approx(expected)
    assert result.fsr_newtons[0] == 0.0 and 1.0 < result.fsr_newtons[2] < result.fsr_newtons[3]


def test_bad_replies_are_counted_reported_and_survived(core: ServoBridgeCore,
                                                       emulator: MaestroEmulator) -> None:
    core.step(time.monotonic())
    emulator.set_voltage(2, 2.5)
    emulator.inject_garbage(b'\xff\xee\xdd')
    garbage = core.step(time.monotonic())
    assert garbage.fsr_newtons is None and 'garbage' in garbage.warnings[0]
    emulator.truncate_replies(1)
    short = core.step(time.monotonic())
    assert short.fsr_newtons is None and 'short_reply' in short.warnings[0]
    assert core.step(time.monotonic()).fsr_counts == (512, 0, 0, 0)
    assert (core.counters.garbage, core.counters.short_reply) == (1, 1)
    status = core.status(time.monotonic())
    assert status.level is Level.WARN and '2 bad board replies' in status.message
    assert status.values['garbage'] == '1' and status.values['short_reply'] == '1'
    assert core.status(time.monotonic()).level is Level.OK      # reported once, then quiet again
    core.link.write(b'\x13\x14')                                 # bytes the firmware cannot parse
    assert core.poll_board_errors() == ['board reports errors: serial_protocol']
    assert core.status(time.monotonic()).values['last_board_errors'] == 'serial_protocol'


def test_a_vanished_port_is_reopened_and_the_targets_are_sent_again(core: ServoBridgeCore,
                                                                    emulator: MaestroEmulator) -> None:
    core.step(time.monotonic())
    core.handle_command(['arm1', 'arm2'], [0.3, -0.3], [], time.monotonic())
    assert core.step(time.monotonic()).joint_positions is not None
    emulator.unplug()
    down = run(core, 0.3)
    assert any('lost' in e for r in down for e in r.events)
    assert all(r.joint_positions is None and r.fsr_newtons is None for r in down[1:])
    status = core.status(time.monotonic())
    assert status.level is Level.ERROR and 'down' in status.message
    assert core.link.failed_opens >= 2
    core.handle_command(['arm1', 'arm2'], [0.4, -0.3], [], time.monotonic())   # accepted while down
    emulator.clear_targets()
    emulator.replug()
    assert wait_until(lambda: core.step(time.monotonic()).joint_positions is not None, 1.0)
    up = run(core, 0.1)
    assert sorted((r.channel, r.pulse_us) for r in emulator.targets()) == [(0, 1740.0), (1, 1680.0)]
    assert up[-1].joint_positions == pytest.approx((0.4, -0.3), abs=1e-3)
    assert up[-1].fsr_newtons is not None
    assert core.status(time.monotonic()).values['port_disconnects'] == '1' and core.link.opens == 2
