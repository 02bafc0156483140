"""A Pololu Maestro on a pseudo-terminal: real bytes for real pyserial, for tests and hardware-free runs.

``MaestroEmulator`` opens a pty (``os.openpty``) and publishes its slave under a stable symlink
(``link_path``), which the servo bridge opens like ``/dev/ttyACM0``. A background thread answers the
compact protocol (``smarticle_driver.maestro``): servo channels slew toward their targets at the set
speed (``slew.SlewModel``), analog input channels return the voltages set with ``set_voltage``, every
Set Target is recorded with its arrival time, and faults can be injected: garbage bytes, truncated or
missing replies, and an unplugged port (symlink removed, pty closed) that ``replug`` brings back on a
new pty under the same path, as a power-cycled board (targets off, speeds unlimited).
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from smarticle_driver import maestro
from smarticle_driver.errors import DriverError
from smarticle_driver.slew import SlewModel


class EmulatorError(DriverError):
    """Misuse of the board emulator (unknown channel, voltage out of range, not started)."""


#: Analog replies kept by the emulator (about 4 minutes of four FSR inputs at 100 Hz).
MAX_ANALOG_RECORDS = 100_000


@dataclass(frozen=True)
class AnalogRecord:
    """One analog input reading the emulator sent: reply time (clock s), channel, counts (0..1023)."""

    time: float
    channel: int
    counts: int


@dataclass(frozen=True)
class TargetRecord:
    """One Set Target the emulator received: arrival time (clock s), channel, target (quarter-us)."""

    time: float
    channel: int
    quarter_us: int

    @property
    def pulse_us(self) -> float:
        """The target in microseconds."""
        return self.quarter_us / 4.0


class _Channel:
    def __init__(self) -> None:
        self.model = SlewModel()
        self.speed = 0
        self.acceleration = 0
        self.volts = 0.0


class MaestroEmulator:
    """A fake Maestro (six channels by default: servos on 0-1, analog inputs on 2-5) on a pty."""

    def __init__(self, link_path: str | Path, channels: int = 6, input_channels: Iterable[int] = (2, 3, 4, 5),
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not 1 <= channels <= maestro.MAX_CHANNEL + 1:
            raise EmulatorError(f'channels must be 1..{maestro.MAX_CHANNEL + 1}, got {channels}')
        self.link_path = Path(link_path)
        self.clock = clock
        self.input_channels = frozenset(input_channels)
        bad = [c for c in self.input_channels if not 0 <= c < channels]
        if bad:
            raise EmulatorError(f'input channels {bad} are not among the {channels} channels')
        self._channels = [_Channel() for _ in range(channels)]
        self._lock = threading.Lock()
        self._records: list[TargetRecord] = []
        self._analog: deque[AnalogRecord] = deque(maxlen=MAX_ANALOG_RECORDS)
        self._parser = maestro.CommandParser()
        self._error_bits = 0
        self._garbage = bytearray()
        self._truncate = 0
        self._drop = 0
        self._master: int | None = None
        self._slave: int | None = None
        self._slave_name = ''
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._wake_r, self._wake_w = -1, -1
        self.bytes_received = 0
        self.replies_sent = 0

    # -- life cycle -------------------------------------------------------------------------------

    def start(self) -> str:
        """Plug in the board and start answering; return the stable port path."""
        if self._thread is not None:
            raise EmulatorError('emulator already started')
        self._wake_r, self._wake_w = os.pipe()
        self.replug()
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name='maestro-emulator', daemon=True)
        self._thread.start()
        return str(self.link_path)

    def stop(self) -> None:
        """Stop answering, close the pty and remove the port path."""
        self._stop.set()
        if self._wake_w >= 0:
            os.write(self._wake_w, b'x')
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self.unplug()
        for fd in (self._wake_r, self._wake_w):
            if fd >= 0:
                os.close(fd)
        self._wake_r, self._wake_w = -1, -1

    def __enter__(self) -> MaestroEmulator:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def raise_priority(self, niceness: int = -10) -> bool:
        """Run the emulator's thread at ``niceness`` (Linux; negative needs the privilege): a real board has its own
        processor, so a busy host must not delay the emulator's time stamps. False if the system refused."""
        thread = self._thread
        if thread is None or thread.native_id is None:
            raise EmulatorError('emulator not started')
        try:
            os.setpriority(os.PRIO_PROCESS, thread.native_id, niceness)
        except PermissionError:
            return False
        return True

    @property
    def plugged(self) -> bool:
        """True while the pty exists and the port path points to it."""
        return self._master is not None

    @property
    def device(self) -> str:
        """The current pty slave device (``/dev/pts/N``), '' while unplugged."""
        return self._slave_name

    def unplug(self) -> None:
        """Emulate pulling the USB cable: remove the port path and close the pty."""
        with self._lock:
            try:
                self.link_path.unlink()
            except FileNotFoundError:
                pass
            for fd in (self._master, self._slave):
                if fd is not None:
                    os.close(fd)
            self._master = self._slave = None
            self._slave_name = ''
        self._wake()

    def replug(self) -> None:
        """Emulate plugging the board back in: a new pty under the same path, board state reset."""
        with self._lock:
            if self._master is not None:
                return
            master, slave = os.openpty()
            tty.setraw(slave)
            self._slave_name = os.ttyname(slave)
            tmp = self.link_path.with_name(self.link_path.name + '.new')
            tmp.unlink(missing_ok=True)
            os.symlink(self._slave_name, tmp)
            os.replace(tmp, self.link_path)
            self._master, self._slave = master, slave
            for ch in self._channels:       # a power-cycled Maestro: no pulses, unlimited speed
                ch.model.forget()
                ch.speed = ch.acceleration = 0
                ch.model.set_rate(0.0, self.clock())
            self._error_bits = 0
            self._parser = maestro.CommandParser()
        self._wake()

    # -- what a test or a user sets and reads ---------------------------------------------------------

    def set_voltage(self, channel: int, volts: float) -> None:
        """Set the voltage (0..5 V) on an analog input channel."""
        self._input(channel)
        if not 0.0 <= volts <= maestro.ANALOG_VOLTS:
            raise EmulatorError(f'analog input voltage must be 0..{maestro.ANALOG_VOLTS} V, got {volts}')
        with self._lock:
            self._channels[channel].volts = float(volts)

    def voltage(self, channel: int) -> float:
        """Return the voltage set on an analog input channel."""
        return self._channels[self._input(channel)].volts

    def counts(self, channel: int) -> int:
        """Return the 10-bit reading the board reports for an analog input channel."""
        return round(self.voltage(channel) / maestro.ANALOG_VOLTS * maestro.ANALOG_FULL_SCALE)

    def position_us(self, channel: int) -> float:
        """Return a servo channel's current (slewed) pulse width in us; 0 when it sends no pulses."""
        with self._lock:
            return self._pulse(channel, self.clock())

    def target_us(self, channel: int) -> float:
        """Return a servo channel's target in us (0 = off)."""
        with self._lock:
            model = self._channels[channel].model
            return model.target if model.known else 0.0

    def speed(self, channel: int) -> int:
        """Return a channel's speed limit in Maestro units (0 = unlimited)."""
        return self._channels[channel].speed

    def targets(self) -> list[TargetRecord]:
        """Return every Set Target received so far, in order."""
        with self._lock:
            return list(self._records)

    def analog_replies(self) -> list[AnalogRecord]:
        """Return the analog input readings sent so far (the latest MAX_ANALOG_RECORDS), in order."""
        with self._lock:
            return list(self._analog)

    def clear_targets(self) -> None:
        """Forget the recorded Set Target commands."""
        with self._lock:
            self._records.clear()

    @property
    def protocol_errors(self) -> int:
        """Malformed command bytes seen so far (the board's serial protocol error)."""
        return self._parser.protocol_errors

    # -- fault injection ------------------------------------------------------------------------------

    def inject_garbage(self, data: bytes = b'\xff\xfe\x07', now: bool = False) -> None:
        """Send ``data`` before the next reply, or at once (unsolicited) with ``now=True``."""
        with self._lock:
            if now:
                if self._master is not None:
                    os.write(self._master, data)
            else:
                self._garbage.extend(data)

    def truncate_replies(self, count: int = 1) -> None:
        """Send only the first byte of each of the next ``count`` replies."""
        with self._lock:
            self._truncate += count

    def drop_replies(self, count: int = 1) -> None:
        """Send nothing for the next ``count`` replies."""
        with self._lock:
            self._drop += count

    # -- the firmware ---------------------------------------------------------------------------------

    def _input(self, channel: int) -> int:
        if channel not in self.input_channels:
            raise EmulatorError(f'channel {channel} is not an analog input '
                                f'(inputs: {sorted(self.input_channels)})')
        return channel

    def _wake(self) -> None:
        if self._wake_w >= 0:
            os.write(self._wake_w, b'x')

    def _pulse(self, channel: int, now: float) -> float:
        model = self._channels[channel].model
        return model.position(now) if model.known else 0.0

    def _serve(self) -> None:
        """Thread body: read commands from the pty master and answer them."""
        while not self._stop.is_set():
            master = self._master
            watch = [self._wake_r] + ([master] if master is not None else [])
            try:
                ready, _, _ = select.select(watch, [], [], 0.1)
            except (OSError, ValueError):
                continue
            if self._wake_r in ready:
                os.read(self._wake_r, 64)
            if master is None or master not in ready:
                continue
            with self._lock:
                if self._master != master:
                    continue
                try:
                    data = os.read(master, 4096)
                except OSError:
                    continue
                self.bytes_received += len(data)
                reply = self._handle(data)
                if reply:
                    try:
                        os.write(master, reply)
                    except OSError:
                        continue

    def _handle(self, data: bytes) -> bytes:
        """Apply the commands in ``data``; return the reply bytes (with faults applied)."""
        now = self.clock()
        seen = self._parser.protocol_errors
        out = bytearray()
        for cmd in self._parser.feed(data):
            if self._parser.protocol_errors > seen:      # flag errors before a Get Errors in the same read
                seen = self._parser.protocol_errors
                self._error_bits |= 1 << maestro.MaestroErrorBit.SERIAL_PROTOCOL
            if cmd.code != maestro.GET_ERRORS and cmd.channel >= len(self._channels):
                self._error_bits |= 1 << maestro.MaestroErrorBit.SERIAL_PROTOCOL
                continue
            if cmd.code == maestro.SET_TARGET:
                self._records.append(TargetRecord(now, cmd.channel, cmd.value))
                if cmd.channel in self.input_channels:
                    continue
                model = self._channels[cmd.channel].model
                if cmd.value == 0:
                    model.forget()
                else:
                    model.set_target(cmd.value / 4.0, now)
            elif cmd.code == maestro.SET_SPEED:
                self._channels[cmd.channel].speed = cmd.value
                self._channels[cmd.channel].model.set_rate(maestro.units_to_speed(cmd.value), now)
            elif cmd.code == maestro.SET_ACCELERATION:
                self._channels[cmd.channel].acceleration = cmd.value
            elif cmd.code == maestro.GET_POSITION:
                if cmd.channel in self.input_channels:
                    value = round(self._channels[cmd.channel].volts / maestro.ANALOG_VOLTS
                                  * maestro.ANALOG_FULL_SCALE)
                    self._analog.append(AnalogRecord(now, cmd.channel, value))
                else:
                    value = round(self._pulse(cmd.channel, now) * 4.0)
                out += self._reply(value)
            elif cmd.code == maestro.GET_ERRORS:
                out += self._reply(self._error_bits)
                self._error_bits = 0
        if self._parser.protocol_errors > seen:
            self._error_bits |= 1 << maestro.MaestroErrorBit.SERIAL_PROTOCOL
        if out and self._garbage:
            out = self._garbage + out
            self._garbage = bytearray()
        return bytes(out)

    def _reply(self, value: int) -> bytes:
        self.replies_sent += 1
        reply = bytes((value & 0xFF, (value >> 8) & 0xFF))
        if self._drop:
            self._drop -= 1
            return b''
        if self._truncate:
            self._truncate -= 1
            return reply[:1]
        return reply
