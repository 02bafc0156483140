"""The Maestro board over real pyserial on the emulator's pty: normal traffic and every fault."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from tests.helpers.fake_board import open_board, running_emulator, wait_until

from smarticle_driver import maestro
from smarticle_driver.emulator import EmulatorError, MaestroEmulator
from smarticle_driver.errors import GarbageReply, PortUnavailable, ShortReply
from smarticle_driver.serial_link import SerialLink


@pytest.fixture
def emulator(tmp_path: Path) -> Iterator[MaestroEmulator]:
    with running_emulator(tmp_path / 'maestro') as emu:
        yield emu


def test_analog_inputs_read_back_the_set_voltages(emulator: MaestroEmulator) -> None:
    link, board = open_board(emulator.link_path)
    for channel, volts in zip((2, 3, 4, 5), (0.0, 1.25, 2.5, 5.0), strict=True):
        emulator.set_voltage(channel, volts)
    assert board.read_analog((2, 3, 4, 5)) == [0, 256, 512, 1023]
    with pytest.raises(EmulatorError, match='not an analog input'):
        emulator.set_voltage(0, 1.0)
    link.close()


def test_targets_are_recorded_and_the_servo_slews_at_the_set_speed(emulator: MaestroEmulator) -> None:
    link, board = open_board(emulator.link_path)
    assert board.read_pulse(0) == 0.0                        # no pulses after power-up
    board.set_target(0, 1000.0)                              # first target: reached at once
    assert board.set_speed(0, 2000.0) == pytest.approx(2000.0)
    start = time.monotonic()
    board.set_target(0, 2000.0)
    assert wait_until(lambda: len(emulator.targets()) == 2, 1.0)
    records = emulator.targets()
    assert [(r.channel, r.pulse_us) for r in records] == [(0, 1000.0), (0, 2000.0)]
    time.sleep(0.2)
    pulse = board.read_pulse(0)
    elapsed = time.monotonic() - start
    assert 1000.0 + 2000.0 * 0.15 < pulse <= min(1000.0 + 2000.0 * elapsed + 1.0, 2000.0)
    assert emulator.speed(0) == 80
    assert wait_until(lambda: board.read_pulse(0) == 2000.0, 1.0)
    link.close()


def test_garbage_before_a_reply_spoils_one_sample_only(emulator: MaestroEmulator) -> None:
    link, board = open_board(emulator.link_path)
    emulator.set_voltage(2, 2.5)
    emulator.inject_garbage(b'\xff\x13\x37')
    with pytest.raises(GarbageReply, match='unexpected byte'):
        board.read_analog((2, 3))
    assert board.read_analog((2, 3)) == [512, 0]
    emulator.inject_garbage(b'\x99\x98', now=True)           # unsolicited bytes between transactions
    assert wait_until(lambda: link._serial is not None and link._serial.in_waiting == 2, 1.0)
    assert board.read_analog((2,)) == [512]
    assert link.discarded_bytes == 3 + 2
    link.close()


def test_truncated_and_missing_replies_are_short_and_the_stream_recovers(emulator: MaestroEmulator) -> None:
    link, board = open_board(emulator.link_path, reply_timeout=0.03)
    emulator.set_voltage(5, 5.0)
    emulator.truncate_replies(1)
    with pytest.raises(ShortReply, match='expected 4 reply bytes .* got 3'):
        board.read_analog((5, 4))
    emulator.drop_replies(1)
    with pytest.raises(ShortReply, match='got 0: nothing'):
        board.get_errors()
    assert board.read_analog((5, 4)) == [1023, 0]
    link.close()


def test_protocol_errors_are_reported_by_get_errors(emulator: MaestroEmulator) -> None:
    link, board = open_board(emulator.link_path)
    link.write(b'\x05\x06' + maestro.encode_set_target(0, 6000)[:2])
    assert board.get_errors() == ['serial_protocol']
    assert board.get_errors() == []                           # reading clears them
    link.close()


def test_an_unplugged_port_is_reopened_with_back_off_after_replug(emulator: MaestroEmulator) -> None:
    # A generous reply timeout: the emulator's thread must first notice the replugged pty, and a loaded
    # machine can delay it past 50 ms (this test is about reconnecting, not about reply timing).
    link, board = open_board(emulator.link_path, backoff_initial=0.05, backoff_max=0.2, reply_timeout=0.5)
    board.set_target(1, 1500.0)
    emulator.unplug()
    assert not emulator.link_path.exists()
    with pytest.raises(PortUnavailable, match='Input/output error|failed'):
        board.read_analog((2,))
    assert not link.is_open and link.disconnects == 1
    with pytest.raises(PortUnavailable, match='not open'):
        board.set_target(1, 1600.0)
    assert wait_until(lambda: (link.poll() or True) and link.failed_opens >= 3, 2.0)
    assert 0.0 < link.seconds_to_retry() <= 0.2               # doubled, capped at backoff_max
    emulator.replug()
    assert wait_until(link.poll, 1.0)
    assert board.read_pulse(1) == 0.0                          # a replugged board starts without pulses
    emulator.set_voltage(3, 1.0)
    assert board.read_analog((3,)) == [205]
    link.close()


def test_a_port_that_never_existed_just_stays_down(tmp_path: Path) -> None:
    link = SerialLink(str(tmp_path / 'no_such_port'), backoff_initial=0.01, backoff_max=0.02)
    assert not link.poll()
    assert 'cannot open' in link.last_error and link.failed_opens == 1
    with pytest.raises(PortUnavailable):
        link.transact(b'\xa1', 2)
