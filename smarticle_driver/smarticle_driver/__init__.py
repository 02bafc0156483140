"""The servo bridge to Pololu Maestro boards: the protocol, the serial link, the bridge core, the board emulator."""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'MaestroBoard': 'maestro', 'CommandParser': 'maestro',
    'BridgeConfig': 'servo_bridge_core', 'ServoBridgeCore': 'servo_bridge_core',
    'MaestroEmulator': 'emulator', 'EmulatorError': 'emulator',
    'SerialLink': 'serial_link',
    'DriverError': 'errors', 'ProtocolError': 'errors', 'ReplyError': 'errors', 'ShortReply': 'errors',
    'GarbageReply': 'errors', 'MalformedReply': 'errors', 'PortUnavailable': 'errors', 'CalibrationError': 'errors',
    'BridgeConfigError': 'errors',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
