"""Exceptions of the servo bridge side of smarticle_driver (protocol, calibration, serial link)."""

from __future__ import annotations


class DriverError(Exception):
    """Base class of the servo bridge errors."""


class ProtocolError(DriverError, ValueError):
    """A value that the board protocol cannot encode (channel, target or speed out of range)."""


class ReplyError(DriverError):
    """A reply from the board that cannot be trusted; ``kind`` names the counter it feeds."""

    kind = 'bad_reply'


class ShortReply(ReplyError):
    """Fewer reply bytes than the command asks for arrived before the reply timeout."""

    kind = 'short_reply'


class GarbageReply(ReplyError):
    """More bytes than the reply arrived: the stream was out of step, the sample is dropped."""

    kind = 'garbage'


class MalformedReply(ReplyError):
    """A reply of the right length whose value is impossible (e.g. an analog reading above 1023)."""

    kind = 'malformed'


class PortUnavailable(DriverError):
    """The serial port is closed, missing or failed; the link reopens it with back-off."""


class CalibrationError(DriverError, ValueError):
    """An invalid calibration file: the message names the file, the field and what was expected."""


class BridgeConfigError(DriverError, ValueError):
    """Servo bridge settings that contradict each other (e.g. two uses of one channel)."""
