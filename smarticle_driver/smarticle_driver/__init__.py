"""The servo bridge to Pololu Maestro boards: the protocol, the serial link, the bridge core, the board emulator."""

from __future__ import annotations

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


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
