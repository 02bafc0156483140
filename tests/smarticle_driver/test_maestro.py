"""Maestro compact protocol: bytes as in the Pololu user's guide, replies, the firmware-side parser."""

from __future__ import annotations

import math

import pytest

from smarticle_driver import maestro
from smarticle_driver.errors import MalformedReply, ProtocolError, ShortReply


def test_set_target_matches_the_users_guide_example() -> None:
    # Pololu: "set the target of channel 0 to 1500 us: 0x84, 0x00, 0x70, 0x2E"
    assert maestro.encode_set_target(0, maestro.us_to_quarter(1500.0)) == bytes((0x84, 0x00, 0x70, 0x2E))


def test_set_speed_matches_the_users_guide_example() -> None:
    # Pololu: "set the speed of channel 5 to 140: 0x87, 0x05, 0x0C, 0x01"
    assert maestro.encode_set_speed(5, 140) == bytes((0x87, 0x05, 0x0C, 0x01))


def test_other_commands_encode_their_code_and_channel() -> None:
    assert maestro.encode_set_acceleration(3, 0) == bytes((0x89, 3, 0, 0))
    assert maestro.encode_get_position(4) == bytes((0x90, 4))
    assert maestro.encode_get_errors() == bytes((0xA1,))


@pytest.mark.parametrize('call', [
    lambda: maestro.encode_set_target(24, 6000),
    lambda: maestro.encode_set_target(-1, 6000),
    lambda: maestro.encode_set_target(0, 0x4000),
    lambda: maestro.encode_set_speed(0, -1),
    lambda: maestro.encode_set_target(True, 6000),
])
def test_values_outside_the_protocol_are_refused(call: object) -> None:
    with pytest.raises(ProtocolError, match='must be an integer'):
        call()  # type: ignore[operator]


def test_replies_decode_little_endian_and_check_their_length_and_range() -> None:
    assert maestro.decode_u16(bytes((0x70, 0x17))) == 6000   # full bytes, unlike commands
    assert maestro.decode_analog(bytes((0xFF, 0x03))) == 1023
    with pytest.raises(MalformedReply, match='above the 10-bit full scale'):
        maestro.decode_analog(bytes((0x00, 0x04)))
    with pytest.raises(ShortReply, match='got 1 byte'):
        maestro.decode_u16(b'\x01')


def test_error_bits_decode_to_names() -> None:
    assert maestro.decode_errors(b'\x00\x00') == []
    assert maestro.decode_errors(bytes((0x10, 0x01))) == ['serial_protocol', 'script_program_counter']
    assert maestro.decode_errors(bytes((0x00, 0x80))) == ['unknown_bits_0x8000']


def test_speed_units_are_quarter_microseconds_per_ten_milliseconds() -> None:
    assert maestro.SPEED_UNIT_US_PER_S == pytest.approx(25.0)
    assert maestro.speed_to_units(3500.0) == 140
    assert maestro.speed_to_units(1.0) == 1            # a limit never becomes "unlimited"
    assert maestro.speed_to_units(math.inf) == 0
    assert maestro.speed_to_units(1e9) == maestro.MAX_14BIT
    assert maestro.units_to_speed(0) == math.inf
    assert maestro.units_to_speed(140) == pytest.approx(3500.0)


def test_parser_splits_a_stream_and_counts_protocol_errors() -> None:
    parser = maestro.CommandParser()
    stream = (maestro.encode_set_target(1, 7000) + maestro.encode_get_errors()
              + maestro.encode_set_speed(2, 300) + maestro.encode_get_position(5))
    commands = list(parser.feed(stream[:3])) + list(parser.feed(stream[3:]))   # split mid-command
    assert commands == [maestro.Command(0x84, 1, 7000), maestro.Command(0xA1),
                        maestro.Command(0x87, 2, 300), maestro.Command(0x90, 5)]
    assert parser.protocol_errors == 0
    # a stray data byte, an unknown command, and a command cut short by the next one
    bad = b'\x13' + b'\xC0' + maestro.encode_set_target(0, 6000)[:2] + maestro.encode_get_position(2)
    assert list(parser.feed(bad)) == [maestro.Command(0x90, 2)]
    assert parser.protocol_errors == 3
