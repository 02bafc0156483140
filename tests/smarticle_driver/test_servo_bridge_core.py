"""The servo bridge core on a real emulated board: commands, slew model, watchdog, FSRs, faults, reconnect."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

from smarticle_common import topics
from smarticle_driver.board_calibration import FsrModel, load_fsr_calibration, load_servo_calibration
from smarticle_driver.emulator import MaestroEmulator
from smarticle_driver.errors import BridgeConfigError
from smarticle_driver.maestro import MaestroBoard
from smarticle_common.params import read_defaults_yaml
from smarticle_driver import maestro
from smarticle_driver.servo_bridge_core import (BOARD_SPEED_MARGIN, MAX_STROKE_DELAY, NODE_NAME, STROKE_GAP,
                                                BridgeConfig, Level, ServoBridgeCore, StepResult, check_command)
from tests.helpers.fake_board import open_board, running_emulator, wait_until

ROOT = Path(__file__).resolve().parents[2]
Command = tuple[list[str], list[float], list[float]]
LIMITS = {'arm1': (-1.5, 1.5), 'arm2': (-1.5, 1.5)}


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[MaestroEmulator]:
    with running_emulator(tmp_path / 'maestro') as emu:
        yield emu


@pytest.fixture
def core(emulator: MaestroEmulator) -> Iterator[ServoBridgeCore]:
    # both arms move together in these tests (one_arm_at_a_time has its own test below)
    config = BridgeConfig(port=str(emulator.link_path), watchdog_timeout=0.2, reply_timeout=0.03,
                          reconnect_initial=0.02, reconnect_max=0.1, one_arm_at_a_time=False)
    bridge = ServoBridgeCore.from_config(config)
    yield bridge
    bridge.close()


def test_one_arm_at_a_time_holds_a_stroke_until_the_other_arm_is_done_but_never_a_hold(
        emulator: MaestroEmulator) -> None:
    config = BridgeConfig(port=str(emulator.link_path), watchdog_timeout=5.0, reply_timeout=0.03)
    core = ServoBridgeCore.from_config(config)
    try:
        core.step(time.monotonic())
        core.handle_command(['arm1', 'arm2'], [0.0, 0.0], [], time.monotonic())
        assert wait_until(lambda: not core.service(time.monotonic()).events
                          and {r.channel for r in emulator.targets()} == {0, 1}, 1.0)   # both arms straight
        time.sleep(0.05)
        emulator.clear_targets()
        sent = time.monotonic()
        core.handle_command(['arm1', 'arm2'], [0.3, 0.0], [1.0, 1.0], sent)     # arm1: a 0.3 rad stroke
        assert wait_until(lambda: len(emulator.targets()) >= 1, 1.0)
        board_rate = maestro.units_to_speed(emulator.speed(0))                 # the margin, rounded up
        assert board_rate >= 600 * 1.0 * (1 + BOARD_SPEED_MARGIN)
        end = emulator.targets()[0].time + 0.3 * 600 / board_rate
        time.sleep(end - 0.01 - time.monotonic())
        arrived = time.monotonic()
        core.handle_command(['arm1', 'arm2'], [0.3, 0.6], [1.0, 1.0], arrived)   # arm2 10 ms before arm1 ends
        due = core.next_deadline()
        assert due is not None and due == pytest.approx(end + STROKE_GAP, abs=0.002)
        while time.monotonic() < due - 0.001:
            core.service(time.monotonic())
            assert [r.channel for r in emulator.targets()] == [0], 'arm2 started while arm1 was moving'
            time.sleep(0.001)
        time.sleep(0.002)
        core.service(time.monotonic())
        assert wait_until(lambda: len(emulator.targets()) >= 2, 1.0)
        records = emulator.targets()
        assert [r.channel for r in records] == [0, 1] and records[1].time >= end + STROKE_GAP - 0.001
        # a new target of the moving arm itself (a halt's hold) is never delayed
        core.handle_command(['arm1', 'arm2'], [0.3, 0.5], [1.0, 1.0], time.monotonic())
        assert wait_until(lambda: [r.channel for r in emulator.targets()] == [0, 1, 1], 1.0), emulator.targets()
        # a target arriving early in the other arm's stroke waits MAX_STROKE_DELAY at most: never far behind
        arrived = time.monotonic()
        core.handle_command(['arm1', 'arm2'], [-0.3, 0.5], [1.0, 1.0], arrived)
        assert core.next_deadline() == pytest.approx(arrived + MAX_STROKE_DELAY, abs=1e-6)
    finally:
        core.close()


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
    (['arm1'], [0.1], [math.inf], 'bad_speeds', 'not a positive number', {'arm1': 0.1}),
    (['arm1'], [0.1], [1e308], 'clamped_speeds', 'clamped to it', {'arm1': 0.1}),
])
def test_bad_commands_are_rejected_or_clamped_with_a_warning(names: list[str], positions: list[float],
                                                             velocities: list[float], counter: str, text: str,
                                                             accepted: dict[str, float]) -> None:
    out = check_command(names, positions, velocities, LIMITS, 3.0, max_speed=10.0)
    assert out.counts == {counter: 1}
    assert all(0.0 < v <= 10.0 for v in out.speeds.values())
    assert len(out.warnings) == 1 and text in out.warnings[0], out.warnings
    assert out.targets == pytest.approx(accepted)


def test_shipped_defaults_build_the_bridge_config() -> None:
    shipped = read_defaults_yaml(str(ROOT / 'smarticle_driver' / 'config' / 'servo_bridge.yaml'), NODE_NAME)
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


def test_the_calibration_folder_of_smarticle_board_calibrate_is_read(tmp_path: Path) -> None:
    """calibration_dir (board.launch.xml's calibration:=robot0/): its files, the package's for a part it lacks."""
    shipped = ROOT / 'smarticle_driver' / 'config'
    robot = tmp_path / 'robot0'
    robot.mkdir()
    (robot / 'servo_calibration.yaml').write_text((shipped / 'servo_calibration.yaml').read_text())
    config = BridgeConfig(port='/dev/null', calibration_dir=str(robot))
    assert config.servo_calibration_path() == robot / 'servo_calibration.yaml'
    assert config.fsr_calibration_path() == shipped / 'fsr_calibration.yaml'     # --skip fsrs: the package's
    (robot / 'fsr_calibration.yaml').write_text((shipped / 'fsr_calibration.yaml').read_text())
    assert config.fsr_calibration_path() == robot / 'fsr_calibration.yaml'
    own = BridgeConfig(port='/dev/null', calibration_dir=str(robot), servo_calibration_file='mine.yaml')
    assert own.servo_calibration_path() == Path('mine.yaml')                       # a file set by name wins
    with pytest.raises(BridgeConfigError, match='is not a folder'):
        BridgeConfig(port='/dev/null', calibration_dir=str(tmp_path / 'robot9'))
    with pytest.raises(BridgeConfigError, match='has neither servo_calibration.yaml nor fsr_calibration.yaml'):
        BridgeConfig(port='/dev/null', calibration_dir=str(tmp_path))


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
    assert emulator.speed(0) == math.ceil(2.0 * 600 * (1 + BOARD_SPEED_MARGIN) / 25) == emulator.speed(1)
    move: Command = (['arm1'], [-0.5], [2.0])                          # 1 rad at 2 rad/s: 0.5 s
    results = run(core, 0.25, heartbeat=move)
    moving = results[-1]
    assert moving.joint_positions is not None and moving.joint_velocities is not None
    assert -0.5 < moving.joint_positions[0] < 0.3
    assert moving.joint_positions[1] == pytest.approx(0.5, abs=1e-3)
    assert moving.joint_velocities[0] == pytest.approx(-2.0 * (1 + BOARD_SPEED_MARGIN), rel=0.01)  # the board's
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


@pytest.mark.parametrize('velocity', [1e308, math.inf, 1e6])
def test_a_huge_speed_limit_reaches_the_board_as_the_servo_top_speed_never_unlimited(
        core: ServoBridgeCore, emulator: MaestroEmulator, velocity: float) -> None:
    """Set Speed 0 means *unlimited* to a Maestro: no command may produce it."""
    core.step(time.monotonic())                                   # opens the port
    core.handle_command(['arm1', 'arm2'], [0.5, -0.5], [velocity, velocity], time.monotonic())
    assert wait_until(lambda: emulator.speed(0) != 0 and emulator.speed(1) != 0, 1.0), \
        (emulator.speed(0), emulator.speed(1))
    top = core.joints[0].cal.rate_to_pulse_rate(core.config.max_speed)
    fallback = core.joints[0].cal.rate_to_pulse_rate(core.config.default_speed)
    for channel in (0, 1):
        assert maestro.units_to_speed(emulator.speed(channel)) == pytest.approx(
            (top if math.isfinite(velocity) else fallback) * (1 + BOARD_SPEED_MARGIN), rel=0.01)
    counter = 'clamped_speeds' if math.isfinite(velocity) else 'bad_speeds'
    assert getattr(core.counters, counter) == 2


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


# -- threads: the node runs commands and steps in different threads -----------------------------------

#: Seconds a test thread waits for another before the test gives up (a hang guard, not a timing limit).
LIVENESS = 10.0


class OrderedBoard:
    """A Maestro that logs its calls in order; the next FSR read can be held open until released."""

    def __init__(self, board: MaestroBoard, log: list[str]) -> None:
        self.board, self.log = board, log
        self.analog_full_scale, self.analog_volts = board.analog_full_scale, board.analog_volts
        self.hold_read = False
        self.reading, self.release_read, self.target_sent = threading.Event(), threading.Event(), threading.Event()

    def set_target(self, channel: int, pulse_us: float) -> float:
        sent = self.board.set_target(channel, pulse_us)
        self.log.append(f'set_target {channel}')
        self.target_sent.set()
        return sent

    def set_speed(self, channel: int, us_per_s: float) -> float:
        return self.board.set_speed(channel, us_per_s)

    def read_analog(self, channels: Sequence[int]) -> list[int]:
        if self.hold_read:
            self.hold_read = False
            self.log.append('fsr read begins')
            self.reading.set()
            assert self.release_read.wait(LIVENESS)
        counts = self.board.read_analog(channels)
        self.log.append('fsr read ends')
        return counts

    def read_pulse(self, channel: int) -> float:
        return self.board.read_pulse(channel)

    def get_errors(self) -> list[str]:
        return self.board.get_errors()


class ObservedLock:
    """The core's lock, telling when a thread has to wait for it."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.waited = threading.Event()

    def __enter__(self) -> ObservedLock:
        if not self._lock.acquire(blocking=False):
            self.waited.set()
            self._lock.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self._lock.release()


class SlowFsr:
    """An FSR model whose conversion, while ``wait_for`` is set, lasts until that event is set."""

    def __init__(self, model: FsrModel) -> None:
        self.model = model
        self.wait_for: threading.Event | None = None

    def newtons(self, counts: float) -> float:
        if self.wait_for is not None:
            self.wait_for.wait(LIVENESS)
        return self.model.newtons(counts)


def ordered_core(emulator: MaestroEmulator, log: list[str]) -> tuple[ServoBridgeCore, OrderedBoard, SlowFsr]:
    """A core on the emulator whose board logs its calls and whose first FSR face converts slowly."""
    config = BridgeConfig(port=str(emulator.link_path), watchdog_timeout=30.0, reply_timeout=0.05,
                          one_arm_at_a_time=False)
    servos = load_servo_calibration(config.servo_calibration_path())
    fsrs: dict[str, FsrModel] = dict(load_fsr_calibration(config.fsr_calibration_path()))
    slow = SlowFsr(fsrs[topics.FSR_FACES[0]])
    fsrs[topics.FSR_FACES[0]] = slow
    link, maestro = open_board(emulator.link_path, reply_timeout=0.05)
    board = OrderedBoard(maestro, log)
    return ServoBridgeCore(config, servos, fsrs, link, board), board, slow


def test_a_command_during_a_slow_fsr_step_is_written_before_the_step_ends(emulator: MaestroEmulator) -> None:
    """Order of events, not timing: the command waits for the FSR transaction only, not for the step."""
    log: list[str] = []
    core, board, slow = ordered_core(emulator, log)
    core.handle_command(['arm1', 'arm2'], [0.0, 0.0], [2.0, 2.0], time.monotonic())
    core.step(time.monotonic())
    core.lock = lock = ObservedLock()
    log.clear()
    board.target_sent.clear()
    board.hold_read = True                 # the step's FSR transaction stays open until released ...
    slow.wait_for = board.target_sent      # ... and the rest of the step lasts until a target is written

    def step() -> None:
        core.step(time.monotonic())
        log.append('step ends')

    stepping = threading.Thread(target=step)
    stepping.start()
    assert board.reading.wait(LIVENESS)
    commanding = threading.Thread(target=core.handle_command,
                                  args=(['arm1', 'arm2'], [0.5, 0.0], [2.0, 2.0], time.monotonic()))
    commanding.start()
    assert lock.waited.wait(LIVENESS), 'the command must wait while the FSR transaction is in progress'
    board.release_read.set()
    stepping.join(LIVENESS)
    commanding.join(LIVENESS)
    assert not stepping.is_alive() and not commanding.is_alive()
    assert log == ['fsr read begins', 'fsr read ends', 'set_target 0', 'step ends'], (
        'the command must wait for the FSR transaction but not for the end of the step')
    assert wait_until(lambda: [(r.channel, r.pulse_us) for r in emulator.targets()[-1:]] == [(0, 1800.0)],
                      LIVENESS)
    assert core.counters.commands == 2 and core.counters.fsr_samples == 2
    core.close()


def test_commands_and_steps_from_two_threads_keep_the_byte_stream_and_counters_intact(
        core: ServoBridgeCore, emulator: MaestroEmulator) -> None:
    core.step(time.monotonic())
    emulator.set_voltage(3, 1.0)
    commands = 300
    angles = [0.4 * math.sin(i / 7.0) for i in range(commands)]

    def command() -> None:
        for a in angles:
            core.handle_command(['arm1', 'arm2'], [a, -a], [50.0, 50.0], time.monotonic())

    commanding = threading.Thread(target=command)
    commanding.start()
    steps = 0
    while commanding.is_alive() or steps < 20:
        result = core.step(time.monotonic())
        assert result.fsr_counts == (0, 205, 0, 0) and not result.warnings, result
        steps += 1
    commanding.join()
    final = round((1500 + 600 * angles[-1]) * 4) / 4     # both arms (arm2 is mirrored, its target is -a)

    def arrived() -> bool:
        last = {r.channel: r.pulse_us for r in emulator.targets()}
        return last.get(0) == last.get(1) == final

    assert wait_until(arrived, LIVENESS), emulator.targets()[-2:]
    assert emulator.protocol_errors == 0, 'interleaved bytes from two threads would break the protocol'
    assert core.counters.commands == commands and core.counters.fsr_samples == steps + 1
    assert core.link.discarded_bytes == 0
    assert core.status(time.monotonic()).values['commands'] == str(commands)


def test_a_closed_core_stays_closed(core: ServoBridgeCore) -> None:
    core.step(time.monotonic())
    core.close()
    result = core.step(time.monotonic())
    assert not core.link.is_open and result.fsr_newtons is None and not result.events
    assert core.poll_board_errors() == []
