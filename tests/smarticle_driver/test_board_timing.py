"""The servo bridge's timing on the board: the watchdog hold of a slow stroke, one arm at a time.

Real processes (``servo_bridge``, ``gait``) drive the board emulator through real pyserial on a
pseudo-terminal; the emulator's log of Set Target commands (arrival time, channel, pulse) is the board's
view. The hold test runs on a quiet machine and again with two CPU hogs (busy loops) competing for the
cores: a hold that depends on load is a defect.
"""

from __future__ import annotations

import math
import os
import signal
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from smarticle_common import topics
from smarticle_driver import maestro
from smarticle_driver.board_calibration import load_servo_calibration
from smarticle_driver.emulator import MaestroEmulator, TargetRecord
from smarticle_driver.servo_bridge_core import BOARD_SPEED_MARGIN, STROKE_GAP
from smarticle_driver.slew import SlewModel
from tests.helpers.fake_board import running_emulator
from tests.helpers.ros import spin_until

ROOT = Path(__file__).resolve().parents[2]
SERVOS = load_servo_calibration(ROOT / 'smarticle_driver' / 'config' / 'servo_calibration.yaml')
US_PER_RAD = {channel: abs(SERVOS[name].us_per_rad) for channel, name in enumerate(topics.JOINT_NAMES)}
WATCHDOG = 0.5
#: A pair of strokes whose first reached the board this much later than its second, each against its own
#: quarter, is not judged (see below): the bridge's own gap between strokes (STROKE_GAP).
LATE = STROKE_GAP


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[MaestroEmulator]:
    """The board emulator, its thread at a raised priority where the system allows it.

    A real Maestro is a microcontroller of its own: a busy host does not delay its clock. The emulator's
    thread shares this machine's cores with the load of the test, and a late wake-up would stamp a Set
    Target late and misplace the arm by speed x delay; a raised priority keeps its time stamps honest.
    """
    with running_emulator(tmp_path / 'maestro') as emu:
        emu.raise_priority()
        yield emu


@pytest.fixture(params=['quiet', 'loaded'])
def load(request: pytest.FixtureRequest) -> Iterator[str]:
    """Nothing, or two busy-loop processes (one per core of a 2-core machine) for the test's duration."""
    hogs = [] if request.param == 'quiet' else [
        subprocess.Popen([sys.executable, '-c', 'while 1: pass']) for _ in range(2)]
    try:
        yield request.param
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def board_position(records: list[TargetRecord], channel: int, rate_us_per_s: float, at: float) -> float:
    """Pulse (us) of ``channel`` on the board at time ``at``, replaying its Set Targets before ``at``."""
    model = SlewModel()
    model.set_rate(rate_us_per_s, 0.0)
    for record in records:
        if record.channel == channel and record.time < at:
            model.set_target(record.pulse_us, record.time)
    return model.position(at)


def strokes(records: list[TargetRecord], rates: dict[int, float]) -> list[tuple[int, float, float]]:
    """The moves on the board: (channel, start, end) of every Set Target that moves its servo."""
    models = {channel: SlewModel() for channel in rates}
    for channel, model in models.items():
        model.set_rate(rates[channel], 0.0)
    out = []
    for record in records:
        model = models.get(record.channel)
        if model is None:
            continue
        was = model.position(record.time)
        model.set_target(record.pulse_us, record.time)
        if model.known and not math.isnan(was) and abs(record.pulse_us - was) > 0.25:
            out.append((record.channel, record.time, record.time + abs(record.pulse_us - was) / rates[record.channel]))
    return out


def listen(probe: Any) -> list[float]:
    """Record when each joint command of robot 0 arrives at ``probe`` (time.monotonic())."""
    received: list[float] = []
    spec = topics.spec_of('joint_commands')
    probe.create_subscription(topics.message_class(spec.type), spec.resolve(0),
                              lambda _msg: received.append(time.monotonic()), topics.qos_profile(spec.qos))
    return received


def start(probe: Any, delay: float) -> float:
    """Publish the synchronised gait start ``delay`` s from now; return it (time.time())."""
    spec = topics.spec_of('start')
    header = topics.message_class(spec.type)
    publisher = probe.create_publisher(header, spec.resolve(), topics.qos_profile(spec.qos))
    assert spin_until(probe, lambda: publisher.get_subscription_count() >= 1, 10.0), 'the gait does not listen'
    t0 = time.time() + delay
    msg = header()
    msg.stamp.sec, msg.stamp.nanosec = int(t0), int((t0 % 1.0) * 1e9)
    publisher.publish(msg)
    return t0


@pytest.mark.integration
def test_a_slow_stroke_killed_mid_way_gets_one_hold_at_the_arm_position(
        nodes: Any, ros_node: Any, emulator: MaestroEmulator, load: str) -> None:
    """Gait at period 16 s and 1 rad/s killed (SIGKILL) mid-stroke: one Set Target at the arm's position,
    within the watchdog timeout + 0.1 s of the last command, then nothing."""
    bridge = nodes.start('servo_bridge', '--ros-args', '-p', f'port:={emulator.link_path}',
                         '-p', f'watchdog_timeout:={WATCHDOG}')
    gait = nodes.start('gait', '--ros-args', '-p', 'period:=16.0', '-p', 'servo_speed:=1.0',
                       '-p', 'alpha_max_deg:=90.0')
    probe = ros_node('hold_probe')
    received = listen(probe)
    assert spin_until(probe, lambda: len(received) > 2 and len(emulator.targets()) >= 2, 20.0), nodes.output(gait)
    start_at = start(probe, 1.0)
    # arm1 strokes from +90 to -90 degrees over pi s from start_at: kill the gait 1.5 s into it
    kill_at = start_at + 1.5
    assert spin_until(probe, lambda: time.time() >= kill_at, 30.0)
    assert gait.poll() is None and bridge.poll() is None, nodes.output(gait) + nodes.output(bridge)
    os.killpg(gait.pid, signal.SIGKILL)
    killed = time.monotonic()
    time.sleep(WATCHDOG + 1.5)     # not spinning: the emulator's thread in this process gets the GIL at once
    last_command = max(t for t in received if t <= killed)
    records = emulator.targets()
    after = [r for r in records if r.time > last_command + 0.005]
    rate = maestro.units_to_speed(emulator.speed(0))
    assert rate == pytest.approx(US_PER_RAD[0] * 1.0 * (1 + BOARD_SPEED_MARGIN), rel=0.03), 'not 1 rad/s'
    log = nodes.output(bridge)
    assert len(after) == 1, f'expected one hold, got {after}\n{log}'
    hold = after[0]
    assert hold.channel == 0, f'the hold must be on the moving arm (channel 0): {hold}'
    delay = hold.time - last_command
    assert delay <= WATCHDOG + 0.1, f'hold {delay * 1e3:.0f} ms after the last command ({load})\n{log}'
    arm = board_position(records, 0, rate, hold.time)
    error_deg = math.degrees(abs(hold.pulse_us - arm) / US_PER_RAD[0])
    assert error_deg <= 0.5, f'hold at {hold.pulse_us} us, arm at {arm:.2f} us: {error_deg:.2f} deg off ({load})'
    assert 'watchdog' in log


@pytest.mark.integration
def test_at_the_default_gait_no_two_strokes_overlap_on_the_board(
        nodes: Any, ros_node: Any, emulator: MaestroEmulator) -> None:
    """The paper's gait moves one arm at a time: over >= 8 periods of the default gait (180 degree strokes
    filling their 0.4 s quarter), no stroke starts on the board before the other arm's has ended.

    The emulator dates a Set Target when its reader thread takes the bytes from the pseudo-terminal, which
    a busy machine delays by up to tens of milliseconds (the kernel hands pty writes over from a worker
    thread). A delay common to two strokes moves both and cannot make them overlap; only the first stroke
    arriving later than the second, each against its own quarter boundary, can. So a pair is judged unless
    its first stroke is misdated by more than LATE (the bridge's 5 ms gap between strokes) relative to the
    second: the overlaps the margin exists for (strokes longer than their quarter, a next stroke sent before
    the other arm stopped) are judged on a loaded machine too.
    """
    period = 1.6
    bridge = nodes.start('servo_bridge', '--ros-args', '-p', f'port:={emulator.link_path}')
    gait = nodes.start('gait', '--ros-args')
    probe = ros_node('stroke_probe')
    received = listen(probe)
    assert spin_until(probe, lambda: len(received) > 2 and len(emulator.targets()) >= 2, 20.0), nodes.output(gait)
    t0 = start(probe, 0.5)
    time.sleep(t0 - time.time() + 9 * period)
    assert gait.poll() is None and bridge.poll() is None
    rates = {channel: maestro.units_to_speed(emulator.speed(channel)) for channel in (0, 1)}
    moves = strokes(emulator.targets(), rates)
    assert len(moves) >= 4 * 8, f'{len(moves)} strokes in 9 periods'
    # the quarter boundaries on the board's clock: the gait keeps time by the wall clock, whose rate against
    # the emulator's monotonic clock may wander (a slewed system clock), so each stroke's lateness is taken
    # against the earliest of its neighbours (four strokes either side): a stroke never starts before its
    # boundary, and the gait's tick and DDS delay every stroke by a few ms at most
    starts = [begin for _, begin, _ in moves]
    spacing = statistics.median(b - a for a, b in zip(starts, starts[1:], strict=False))
    assert spacing == pytest.approx(period / 4, rel=0.01)
    phase = [begin - k * spacing for k, begin in enumerate(starts)]
    late = [phase[k] - min(phase[max(k - 4, 0):k + 5]) for k in range(len(phase))]
    table = '\n'.join(f'ch{c} {b - starts[0]:9.4f} {e - starts[0]:9.4f} {lag * 1e3:6.1f} ms late'
                       for (c, b, e), lag in zip(moves, late, strict=True))
    judged = 0
    for k, ((ch_a, _, end_a), (ch_b, start_b, _)) in enumerate(zip(moves, moves[1:], strict=False)):
        assert ch_a != ch_b, f'two strokes in a row on channel {ch_a}'
        if late[k] - late[k + 1] > LATE:
            continue
        judged += 1
        assert start_b >= end_a, (f'channel {ch_b} started {(end_a - start_b) * 1e3:.2f} ms before channel '
                                  f'{ch_a} stopped\n{table}')
    assert judged >= 4 * 5, f'only {judged} pairs of strokes reached the board in step\n{table}'
    durations = [end - begin for _, begin, end in moves[1:]]
    assert max(durations) < period / 4, f'a stroke takes {max(durations) * 1e3:.2f} ms, longer than its quarter'
