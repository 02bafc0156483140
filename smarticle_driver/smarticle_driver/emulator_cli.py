"""`smarticle-fake-board`: run the Maestro emulator on a pty so the servo bridge runs without hardware.

Prints the port path to give the bridge (``servo_bridge --ros-args -p port:=<path>``), logs the servo
targets in degrees every ``--log-period`` seconds, and takes commands on stdin and/or from lines
appended to a ``--control`` file (``echo 'newtons arm1_front 2.5' >> ctl``)::

    volts <face|channel> <V>   set an analog input voltage, 0..5 V
    newtons <face> <N>         set the voltage that reads as N newtons through the FSR calibration
    unplug | replug            remove / recreate the port, as pulling and replugging the USB cable
    garbage [hex bytes]        send garbage before the next reply (default ff fe 07)
    truncate [n] | drop [n]    cut the next n replies to one byte / send nothing for them
    status                     print the servo and FSR state now
    help | quit
"""

from __future__ import annotations

import argparse
import math
import select
import signal
import sys
import time
from pathlib import Path
from typing import Any, TextIO

from smarticle_common import topics
from smarticle_driver import maestro
from smarticle_driver.board_calibration import (FsrModel, ServoCalibration, default_config_dir,
                                          load_fsr_calibration, load_servo_calibration)
from smarticle_driver.emulator import EmulatorError, MaestroEmulator, TargetRecord
from smarticle_driver.errors import DriverError
from smarticle_common.cli import add_version

DEFAULT_PORT = '/tmp/smarticle_fake_maestro'


class CommandError(DriverError, ValueError):
    """A console command that cannot be carried out; the message says how to write it."""


class BoardConsole:
    """Applies the text commands of the fake board to an emulator; returns what to print."""

    def __init__(self, emulator: MaestroEmulator, servo_channels: tuple[int, ...],
                 fsr_channels: tuple[int, ...], servos: dict[str, ServoCalibration],
                 fsrs: dict[str, FsrModel]) -> None:
        self.emulator = emulator
        self.servo_channels = dict(zip(topics.JOINT_NAMES, servo_channels, strict=True))
        self.fsr_channels = dict(zip(topics.FSR_FACES, fsr_channels, strict=True))
        self.servos = servos
        self.fsrs = fsrs
        self.quit = False

    def run(self, line: str) -> str:
        """Carry out one command line; return the answer (or the error) as text."""
        words = line.split('#', 1)[0].split()
        if not words:
            return ''
        try:
            return self._run(words[0].lower(), words[1:])
        except (CommandError, EmulatorError) as err:
            return f'error: {err}'

    def _run(self, verb: str, args: list[str]) -> str:
        emu = self.emulator
        if verb == 'volts' and len(args) == 2:
            channel = self._channel(args[0])
            emu.set_voltage(channel, _float(args[1]))
            return f'channel {channel}: {emu.voltage(channel):.3f} V ({emu.counts(channel)} counts)'
        if verb == 'newtons' and len(args) == 2:
            if args[0] not in self.fsr_channels:
                faces = ', '.join(topics.FSR_FACES)
                raise CommandError(f'newtons needs an FSR face ({faces}), got {args[0]!r}')
            volts = self.volts_for(args[0], _float(args[1]))
            emu.set_voltage(self.fsr_channels[args[0]], volts)
            return f'{args[0]}: {volts:.3f} V'
        if verb in ('unplug', 'replug') and not args:
            getattr(emu, verb)()
            return f'{verb}ged: {emu.link_path} ' + (f'-> {emu.device}' if emu.plugged else 'removed')
        if verb == 'garbage':
            try:
                data = bytes.fromhex(''.join(args)) if args else b'\xff\xfe\x07'
            except ValueError as err:
                raise CommandError(f'garbage takes hex bytes such as "ff 00 13": {err}') from err
            emu.inject_garbage(data)
            return f'{len(data)} garbage byte(s) go out before the next reply'
        if verb in ('truncate', 'drop') and len(args) <= 1:
            count = int(_float(args[0])) if args else 1
            (emu.truncate_replies if verb == 'truncate' else emu.drop_replies)(count)
            return f'the next {count} reply(ies) will be {"truncated" if verb == "truncate" else "dropped"}'
        if verb == 'status' and not args:
            return self.status()
        if verb == 'help':
            return (__doc__ or '').split('::', 1)[1].strip('\n')
        if verb in ('quit', 'exit'):
            self.quit = True
            return 'bye'
        raise CommandError(f'cannot understand {" ".join([verb, *args])!r}; type help')

    def _channel(self, name: str) -> int:
        """Return the channel of an FSR face name or a channel number."""
        if name in self.fsr_channels:
            return self.fsr_channels[name]
        try:
            return int(name)
        except ValueError:
            raise CommandError(f'expected an FSR face ({", ".join(topics.FSR_FACES)}) or a channel number, '
                               f'got {name!r}') from None

    def volts_for(self, face: str, newtons: float) -> float:
        """Return the smallest input voltage whose reading gives at least ``newtons`` on ``face``."""
        model = self.fsrs[face]
        for counts in range(maestro.ANALOG_FULL_SCALE + 1):
            if model.newtons(counts) >= newtons:
                return counts * maestro.ANALOG_VOLTS / maestro.ANALOG_FULL_SCALE
        raise CommandError(f'{face} cannot read {newtons} N: its calibration tops out at '
                           f'{model.newtons(maestro.ANALOG_FULL_SCALE):.3g} N')

    def angle_deg(self, joint: str, pulse_us: float) -> float:
        """Return a pulse width of ``joint`` in degrees (nan when the channel is off)."""
        return math.degrees(self.servos[joint].pulse_to_angle(pulse_us)) if pulse_us > 0.0 else math.nan

    def status(self) -> str:
        """Describe the servo positions, targets and FSR inputs in one line."""
        emu = self.emulator
        parts = []
        for joint, ch in self.servo_channels.items():
            now, target = (self.angle_deg(joint, p) for p in (emu.position_us(ch), emu.target_us(ch)))
            parts.append(f'{joint} {_deg(now)} deg (target {_deg(target)})' if not math.isnan(now)
                         else f'{joint} off (no pulses)')
        volts = ' '.join(f'{emu.voltage(ch):.2f}' for ch in self.fsr_channels.values())
        state = f'-> {emu.device}' if emu.plugged else 'UNPLUGGED'
        return f'{"  ".join(parts)}  FSR V [{volts}]  {len(emu.targets())} Set Target received  {state}'

    def record_line(self, record: TargetRecord) -> str:
        """Format a received Set Target as a CSV line: time, channel, pulse us, angle deg."""
        joint = next((j for j, c in self.servo_channels.items() if c == record.channel), None)
        angle = self.angle_deg(joint, record.pulse_us) if joint else math.nan
        return f'{record.time:.6f},{record.channel},{record.pulse_us:.2f},{angle:.3f}\n'


def _deg(angle: float) -> str:
    return f'{angle:+6.1f}'


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise CommandError(f'expected a number, got {text!r}') from None


def build_parser() -> argparse.ArgumentParser:
    """Return the command-line parser of smarticle-fake-board."""
    verbs = ('volts', 'newtons', 'unplug', 'replug', 'garbage', 'truncate', 'drop', 'status', 'quit')
    summary = (__doc__ or '').split('\n\n')[0]
    parser = argparse.ArgumentParser(prog='smarticle-fake-board', description=summary,
                                     epilog='commands (stdin or --control file): ' + ' | '.join(verbs))
    add_version(parser, 'smarticle_driver')
    parser.add_argument('--port', default=DEFAULT_PORT,
                        help=f'stable port path (a symlink) (default {DEFAULT_PORT})')
    parser.add_argument('--servo-channels', type=int, nargs=2, default=(0, 1), metavar=('ARM1', 'ARM2'))
    parser.add_argument('--fsr-channels', type=int, nargs=4, default=(2, 3, 4, 5), metavar='CH')
    parser.add_argument('--servo-calibration', default=str(default_config_dir() / 'servo_calibration.yaml'),
                        help='servo calibration YAML, to show targets in degrees')
    parser.add_argument('--fsr-calibration', default=str(default_config_dir() / 'fsr_calibration.yaml'),
                        help='FSR calibration YAML, for the newtons command')
    parser.add_argument('--volts', type=float, nargs=4, default=(0.0, 0.0, 0.0, 0.0), metavar='V',
                        help='initial FSR input voltages, in face order ' + ' '.join(topics.FSR_FACES))
    parser.add_argument('--log-period', type=float, default=1.0,
                        help='seconds between status lines (0 = none)')
    parser.add_argument('--control', help='file to watch for appended command lines')
    parser.add_argument('--record',
                        help='CSV file receiving every Set Target: time_s,channel,pulse_us,angle_deg')
    parser.add_argument('--no-stdin', action='store_true', help='do not read commands from stdin')
    return parser


class _ControlFile:
    """Reads the lines appended to a file since the last look (starts over if it shrinks)."""

    def __init__(self, path: str) -> None:
        self.path = Path(path)
        self.offset = 0
        self._partial = ''

    def new_lines(self) -> list[str]:
        try:
            size = self.path.stat().st_size
        except FileNotFoundError:
            return []
        if size < self.offset:
            self.offset, self._partial = 0, ''
        if size == self.offset:
            return []
        with open(self.path, encoding='utf-8', errors='replace') as handle:
            handle.seek(self.offset)
            text = self._partial + handle.read()
            self.offset = handle.tell()
        lines = text.split('\n')
        self._partial = lines.pop()
        return lines


def _say(out: TextIO, text: str) -> None:
    if text:
        out.write(text + '\n')
        out.flush()


def main(argv: list[str] | None = None) -> int:
    """Entry point of smarticle-fake-board."""
    args = build_parser().parse_args(argv)
    out = sys.stdout
    try:
        servos = load_servo_calibration(args.servo_calibration)
        fsrs = load_fsr_calibration(args.fsr_calibration)
        emulator = MaestroEmulator(args.port, input_channels=args.fsr_channels)
    except DriverError as err:
        sys.stderr.write(f'smarticle-fake-board: {err}\n')
        return 2
    console = BoardConsole(emulator, tuple(args.servo_channels), tuple(args.fsr_channels), servos, fsrs)
    signal.signal(signal.SIGTERM, _terminate)
    emulator.start()
    record: Any = open(args.record, 'w', encoding='utf-8') if args.record else None
    try:
        for face, volts in zip(topics.FSR_FACES, args.volts, strict=True):
            _say(out, console.run(f'volts {face} {volts}') if volts else '')
        _say(out, f'smarticle-fake-board: Maestro emulator on {emulator.link_path} -> {emulator.device}')
        _say(out, f'  run: servo_bridge --ros-args -p port:={emulator.link_path}')
        _serve(args, console, out, record)
    except KeyboardInterrupt:
        pass
    finally:
        emulator.stop()
        if record is not None:
            record.close()
    return 0


def _serve(args: argparse.Namespace, console: BoardConsole, out: TextIO, record: Any) -> None:
    """Main loop: commands from stdin and the control file, periodic status, the target record."""
    control = _ControlFile(args.control) if args.control else None
    stdin_open = not args.no_stdin and sys.stdin is not None and not sys.stdin.closed
    if record is not None:
        record.write('time_s,channel,pulse_us,angle_deg\n')
    written = 0
    t0 = time.monotonic()
    next_log = t0 + args.log_period
    while not console.quit:
        ready: list[Any] = []
        if stdin_open:
            try:
                ready, _, _ = select.select([sys.stdin], [], [], 0.05)
            except (OSError, ValueError):
                stdin_open = False
        else:
            time.sleep(0.05)
        if ready:
            line = sys.stdin.readline()
            if line:
                _say(out, console.run(line))
            else:
                stdin_open = False
        for line in control.new_lines() if control else []:
            _say(out, console.run(line))
        if record is not None:
            records = console.emulator.targets()
            for rec in records[written:]:
                record.write(console.record_line(rec))
            written = len(records)
            record.flush()
        now = time.monotonic()
        if args.log_period > 0 and now >= next_log:
            _say(out, f't={now - t0:7.1f} s  {console.status()}')
            next_log = now + args.log_period


def _terminate(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


if __name__ == '__main__':
    sys.exit(main())
