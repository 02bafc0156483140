"""Pololu Maestro compact serial protocol: byte encoding, reply decoding, a stream parser, a board.

Reference: Pololu Maestro Servo Controller User's Guide, section 5.e "Serial Servo Commands".
Compact protocol = a command byte (bit 7 set) followed by data bytes (bit 7 clear):

====================  ==========================================  ================================
command               bytes                                       reply
====================  ==========================================  ================================
Set Target            ``0x84, channel, low 7 bits, high 7 bits``  none
Set Speed             ``0x87, channel, low 7 bits, high 7 bits``  none
Set Acceleration      ``0x89, channel, low 7 bits, high 7 bits``  none
Get Position          ``0x90, channel``                           2 bytes, little endian
Get Errors            ``0xA1``                                    2 bytes, little endian
====================  ==========================================  ================================

Units: targets and servo positions in quarter-microseconds (0 = no pulses); speed in
(0.25 us)/(10 ms), 0 = unlimited; acceleration in (0.25 us)/(10 ms)/(80 ms), 0 = unlimited.
For a channel configured as an analog input, Get Position returns 0..1023 for 0..5 V.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol

from smarticle_driver.errors import MalformedReply, ProtocolError, ShortReply

SET_TARGET = 0x84
SET_SPEED = 0x87
SET_ACCELERATION = 0x89
GET_POSITION = 0x90
GET_ERRORS = 0xA1

#: Largest value two 7-bit data bytes carry.
MAX_14BIT = 0x3FFF
#: Highest channel number of the largest Maestro (Mini Maestro 24).
MAX_CHANNEL = 23
#: Analog inputs read 0..ANALOG_FULL_SCALE for 0..ANALOG_VOLTS.
ANALOG_FULL_SCALE = 1023
ANALOG_VOLTS = 5.0
#: One speed unit of Set Speed, in microseconds of pulse width per second: 0.25 us / 10 ms.
SPEED_UNIT_US_PER_S = 0.25 / 0.010


class MaestroErrorBit(IntEnum):
    """Bits of the Get Errors reply (Maestro user's guide, section 4.b)."""

    SERIAL_SIGNAL = 0
    SERIAL_OVERRUN = 1
    SERIAL_BUFFER_FULL = 2
    SERIAL_CRC = 3
    SERIAL_PROTOCOL = 4
    SERIAL_TIMEOUT = 5
    SCRIPT_STACK = 6
    SCRIPT_CALL_STACK = 7
    SCRIPT_PROGRAM_COUNTER = 8


#: Number of data bytes after each command byte.
DATA_LENGTH: dict[int, int] = {SET_TARGET: 3, SET_SPEED: 3, SET_ACCELERATION: 3, GET_POSITION: 1,
                               GET_ERRORS: 0}
#: Number of reply bytes each command produces.
REPLY_LENGTH: dict[int, int] = {SET_TARGET: 0, SET_SPEED: 0, SET_ACCELERATION: 0, GET_POSITION: 2,
                                GET_ERRORS: 2}


def _channel(channel: int) -> int:
    if isinstance(channel, bool) or not isinstance(channel, int) or not 0 <= channel <= MAX_CHANNEL:
        raise ProtocolError(f'Maestro channel must be an integer 0..{MAX_CHANNEL}, got {channel!r}')
    return channel


def _value14(value: int, what: str) -> bytes:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_14BIT:
        raise ProtocolError(f'{what} must be an integer 0..{MAX_14BIT}, got {value!r}')
    return bytes((value & 0x7F, (value >> 7) & 0x7F))


def encode_set_target(channel: int, quarter_us: int) -> bytes:
    """Encode Set Target: ``quarter_us`` = pulse width in quarter-microseconds (0 = pulses off)."""
    return bytes((SET_TARGET, _channel(channel))) + _value14(quarter_us, 'target (quarter-us)')


def encode_set_speed(channel: int, speed: int) -> bytes:
    """Encode Set Speed in Maestro units of (0.25 us)/(10 ms); 0 means unlimited."""
    return bytes((SET_SPEED, _channel(channel))) + _value14(speed, 'speed')


def encode_set_acceleration(channel: int, acceleration: int) -> bytes:
    """Encode Set Acceleration in (0.25 us)/(10 ms)/(80 ms); 0 means unlimited."""
    return bytes((SET_ACCELERATION, _channel(channel))) + _value14(acceleration, 'acceleration')


def encode_get_position(channel: int) -> bytes:
    """Encode Get Position (servo position in quarter-us, or analog counts on an input channel)."""
    return bytes((GET_POSITION, _channel(channel)))


def encode_get_errors() -> bytes:
    """Encode Get Errors (the board clears its error bits when it answers)."""
    return bytes((GET_ERRORS,))


def decode_u16(reply: bytes) -> int:
    """Decode a 2-byte little-endian reply; raise ShortReply if it is not 2 bytes long."""
    if len(reply) != 2:
        raise ShortReply(f'expected a 2-byte reply, got {len(reply)} byte(s): {reply.hex() or "nothing"}')
    return reply[0] | (reply[1] << 8)


def decode_analog(reply: bytes) -> int:
    """Decode a Get Position reply of an analog input: counts 0..1023 (MalformedReply above)."""
    counts = decode_u16(reply)
    if counts > ANALOG_FULL_SCALE:
        raise MalformedReply(f'analog reading {counts} is above the 10-bit full scale {ANALOG_FULL_SCALE}')
    return counts


def decode_errors(reply: bytes) -> list[str]:
    """Decode a Get Errors reply into the names of the bits that are set."""
    bits = decode_u16(reply)
    names = [bit.name.lower() for bit in MaestroErrorBit if bits & (1 << bit)]
    unknown = bits & ~((1 << (max(MaestroErrorBit) + 1)) - 1)
    if unknown:
        names.append(f'unknown_bits_0x{unknown:04x}')
    return names


def us_to_quarter(pulse_us: float) -> int:
    """Round a pulse width in microseconds to the Maestro's quarter-microsecond target units."""
    return int(round(pulse_us * 4.0))


def speed_to_units(us_per_s: float) -> int:
    """Convert a pulse rate (us/s; inf or <= 0 = unlimited) to Set Speed units, at least 1 when limited.

    Rounds up: the board never moves slower than asked, so a stroke timed to fit a gait quarter at the
    servo speed still ends inside it (at 600 us/rad and pi/0.4 rad/s: 189 units, a 180 degree stroke in
    0.3989 s, not 188 units and 0.4011 s).
    """
    if not us_per_s < float('inf') or us_per_s <= 0.0:
        return 0
    return min(max(math.ceil(us_per_s / SPEED_UNIT_US_PER_S - 1e-9), 1), MAX_14BIT)


def units_to_speed(units: int) -> float:
    """Convert Set Speed units back to a pulse rate in us/s (0 units = unlimited = inf)."""
    return float('inf') if units == 0 else units * SPEED_UNIT_US_PER_S


@dataclass(frozen=True)
class Command:
    """One decoded compact-protocol command: its code, channel (-1 if none) and 14-bit value."""

    code: int
    channel: int = -1
    value: int = 0


class CommandParser:
    """Splits a byte stream into commands, as the board's firmware does; counts protocol errors.

    A data byte with no command in progress, an unknown command byte, or a new command byte before
    the previous command is complete is a *serial protocol error* (error bit 4): that data is dropped.
    """

    def __init__(self) -> None:
        self._pending = bytearray()
        self.protocol_errors = 0

    def feed(self, data: bytes) -> Iterator[Command]:
        """Consume ``data`` and yield every command completed by it."""
        for byte in data:
            if byte & 0x80:
                if self._pending:
                    self.protocol_errors += 1
                self._pending = bytearray()
                if byte not in DATA_LENGTH:
                    self.protocol_errors += 1
                    continue
                self._pending.append(byte)
            elif not self._pending:
                self.protocol_errors += 1
                continue
            else:
                self._pending.append(byte)
            code = self._pending[0]
            if len(self._pending) == 1 + DATA_LENGTH[code]:
                args = bytes(self._pending[1:])
                self._pending = bytearray()
                if code == GET_ERRORS:
                    yield Command(code)
                elif code == GET_POSITION:
                    yield Command(code, args[0])
                else:
                    yield Command(code, args[0], args[1] | (args[2] << 7))


class ByteLink(Protocol):
    """What a board needs of its serial link (smarticle_driver.serial_link.SerialLink has it)."""

    def write(self, data: bytes) -> None:
        """Send ``data``."""

    def transact(self, data: bytes, reply_length: int) -> bytes:
        """Send ``data`` and return exactly ``reply_length`` reply bytes."""


class MaestroBoard:
    """A Pololu Maestro over a byte link; implements smarticle_driver.boards.ServoBoard."""

    analog_full_scale = ANALOG_FULL_SCALE
    analog_volts = ANALOG_VOLTS

    def __init__(self, link: ByteLink) -> None:
        self.link = link

    def set_target(self, channel: int, pulse_us: float) -> float:
        """Command a pulse width in microseconds; return the pulse actually sent (quarter-us steps)."""
        quarter = us_to_quarter(pulse_us)
        self.link.write(encode_set_target(channel, quarter))
        return quarter / 4.0

    def set_speed(self, channel: int, us_per_s: float) -> float:
        """Limit a channel's pulse rate (us/s, inf = unlimited); return the rate the board will use."""
        units = speed_to_units(us_per_s)
        self.link.write(encode_set_speed(channel, units) + encode_set_acceleration(channel, 0))
        return units_to_speed(units)

    def read_analog(self, channels: Sequence[int]) -> list[int]:
        """Read analog inputs in one transaction: counts 0..1023 per channel."""
        request = b''.join(encode_get_position(channel) for channel in channels)
        reply = self.link.transact(request, 2 * len(channels))
        return [decode_analog(reply[2 * i:2 * i + 2]) for i in range(len(channels))]

    def read_pulse(self, channel: int) -> float:
        """Read a servo channel's current pulse width in microseconds (0 = no pulses)."""
        return decode_u16(self.link.transact(encode_get_position(channel), 2)) / 4.0

    def get_errors(self) -> list[str]:
        """Read and clear the board's error bits; return their names."""
        return decode_errors(self.link.transact(encode_get_errors(), 2))
