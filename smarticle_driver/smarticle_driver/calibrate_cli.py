"""`smarticle-board-calibrate`: measure a robot's servo and FSR calibration against its connected board.

Walks a person through it, one prompt at a time, with the board driven live:

* **servos**, per arm: the arm is sent to ``center_us``; nudge it (``+20``, ``-5``: microseconds) until it
  is straight, in line with the body (alpha = 0), then press Enter. Then it is sent to the guess for
  +90 degrees (the tip toward the robot's heading, docs/gait.md); nudge it until a protractor reads 90
  degrees and press Enter. ``us_per_rad`` follows (negative for a mirrored servo); ``min_us`` /
  ``max_us`` are kept from the starting file.
* **FSRs**, per face: with nothing touching it, Enter reads the rest value (``zero_counts``); then press
  the face with known forces (a weight on the pad): type the force in newtons while it is applied and
  the board's reading is averaged; an empty answer ends the face. The face becomes a ``table`` model
  ([counts, newtons] points, counts increasing).

Writes ``servo_calibration.yaml`` and ``fsr_calibration.yaml`` (the formats of ``config/``; docs/servo_bridge.md)
into ``--out`` and loads them back to check them. ``--answers FILE`` reads the answers from a file, one
per line, instead of the keyboard (scripted runs); ``q`` at any prompt stops without writing.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import TextIO

import yaml

from smarticle_common import topics
from smarticle_common.cli import add_version
from smarticle_driver.board_calibration import (ServoCalibration, default_config_dir, load_fsr_calibration,
                                                load_servo_calibration)
from smarticle_driver.boards import ServoBoard, make_board
from smarticle_driver.errors import DriverError
from smarticle_driver.serial_link import SerialLink

#: Readings averaged per FSR measurement.
SAMPLES = 20
#: Seconds between two FSR readings of one measurement.
SAMPLE_PERIOD = 0.01


class CalibrationAborted(DriverError):
    """The person stopped the procedure (``q``) or the answers ran out."""


Ask = Callable[[str], str]


def _nudges(ask: Ask, board: ServoBoard, channel: int, pulse: float, what: str, say: Callable[[str], None]) -> float:
    """Drive ``channel`` to ``pulse`` and take nudges until the person accepts; return the accepted pulse."""
    while True:
        board.set_target(channel, pulse)
        answer = ask(f'{what}: at {pulse:.2f} us; nudge (+N / -N us) or Enter to accept: ').strip()
        if not answer:
            return pulse
        try:
            step = float(answer)
        except ValueError:
            say(f'  {answer!r} is not a number of microseconds (e.g. +20 or -5)')
            continue
        if not math.isfinite(step):
            say('  the nudge must be a finite number of microseconds')
            continue
        pulse = min(max(pulse + step, 1.0), 4000.0)


def calibrate_servos(ask: Ask, board: ServoBoard, channels: dict[str, int], start: dict[str, ServoCalibration],
                     say: Callable[[str], None]) -> dict[str, ServoCalibration]:
    """The servo part: center_us at alpha = 0 and us_per_rad from the +90 degree point, per arm."""
    result = {}
    for name in topics.JOINT_NAMES:
        cal, channel = start[name], channels[name]
        board.set_speed(channel, float('inf'))
        say(f'{name} (channel {channel}): first straight, in line with the body (alpha = 0)')
        center = _nudges(ask, board, channel, cal.center_us, f'{name} straight', say)
        quarter = cal.us_per_rad * math.pi / 2
        say(f'{name}: now +90 degrees, the tip turned toward the heading (a protractor on the joint)')
        plus90 = _nudges(ask, board, channel, center + quarter, f'{name} at +90 deg', say)
        if abs(plus90 - center) < 50.0:
            raise CalibrationAborted(f'{name}: +90 degrees only {abs(plus90 - center):.1f} us from straight; '
                                     'the servo does not follow the pulses')
        us_per_rad = (plus90 - center) / (math.pi / 2)
        result[name] = replace(cal, center_us=center, us_per_rad=us_per_rad)
        board.set_target(channel, center)
        say(f'{name}: center_us {center:.2f}, us_per_rad {us_per_rad:.2f}')
    return result


def _average(board: ServoBoard, channel: int) -> float:
    readings = []
    for _ in range(SAMPLES):
        readings.append(board.read_analog([channel])[0])
        time.sleep(SAMPLE_PERIOD)
    return sum(readings) / len(readings)


def calibrate_fsrs(ask: Ask, board: ServoBoard, channels: dict[str, int],
                   say: Callable[[str], None]) -> dict[str, list[list[float]]]:
    """The FSR part: the rest reading and [counts, newtons] points under known forces, per face."""
    tables = {}
    for face in topics.FSR_FACES:
        channel = channels[face]
        ask(f'{face} (input {channel}): nothing touching it, Enter to read the rest value: ')
        rest = _average(board, channel)
        points = [[round(rest, 1), 0.0]]
        say(f'  {face} at rest: {rest:.1f} counts')
        while True:
            answer = ask(f'{face}: apply a known force and type it in newtons (Enter = done with {face}): ').strip()
            if not answer:
                break
            try:
                newtons = float(answer)
            except ValueError:
                say(f'  {answer!r} is not a force in newtons')
                continue
            if not (math.isfinite(newtons) and newtons > 0.0):
                say('  the force must be a positive number of newtons')
                continue
            counts = _average(board, channel)
            if counts <= points[-1][0] or newtons <= points[-1][1]:
                say(f'  {counts:.1f} counts at {newtons:g} N does not rise above the last point '
                    f'{points[-1]}: not kept (press harder, in increasing order)')
                continue
            points.append([round(counts, 1), newtons])
            say(f'  {face}: {counts:.1f} counts at {newtons:g} N')
        if len(points) < 2:
            raise CalibrationAborted(f'{face}: no force measured; each face needs at least one')
        tables[face] = points
    return tables


def write_files(out: Path, servos: dict[str, ServoCalibration] | None,
                fsr_tables: dict[str, list[list[float]]] | None, port: str) -> list[Path]:
    """Write the calibration files of the parts measured into ``out`` and load them back (CalibrationError if
    one does not load); return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime('%Y-%m-%d %H:%M')
    servo_path, fsr_path = out / 'servo_calibration.yaml', out / 'fsr_calibration.yaml'
    written = []
    if servos is not None:
        written.append(_write_servos(servo_path, servos, port, stamp))
    if fsr_tables is not None:
        written.append(_write_fsrs(fsr_path, fsr_tables, port, stamp))
    return written


def _write_servos(servo_path: Path, servos: dict[str, ServoCalibration], port: str, stamp: str) -> Path:
    servo_data = {'servos': {name: {'center_us': round(c.center_us, 2), 'us_per_rad': round(c.us_per_rad, 3),
                                    'min_us': c.min_us, 'max_us': c.max_us} for name, c in servos.items()}}
    servo_path.write_text(f'# Servo calibration measured with smarticle-board-calibrate on {port}, {stamp}.\n'
                          '#   pulse_us = center_us + us_per_rad * alpha   (alpha in radians, 0 = arm straight)\n'
                          + yaml.safe_dump(servo_data, sort_keys=False), encoding='utf-8')
    load_servo_calibration(servo_path)
    return servo_path


def _write_fsrs(fsr_path: Path, fsr_tables: dict[str, list[list[float]]], port: str, stamp: str) -> Path:
    fsr_data = {'sensors': {face: {'model': 'table', 'points': points} for face, points in fsr_tables.items()}}
    fsr_path.write_text(f'# FSR calibration measured with smarticle-board-calibrate on {port}, {stamp}:\n'
                        '# [ADC counts, newtons] points, interpolated linearly (docs/servo_bridge.md).\n'
                        + yaml.safe_dump(fsr_data, sort_keys=False, default_flow_style=None), encoding='utf-8')
    load_fsr_calibration(fsr_path)
    return fsr_path


def _answers(path: str, out: TextIO) -> Ask:
    lines: Iterator[str] = iter(Path(path).read_text(encoding='utf-8').splitlines())

    def ask(prompt: str) -> str:
        try:
            answer = next(lines)
        except StopIteration:
            raise CalibrationAborted(f'{path}: the answers ran out at: {prompt.strip()}') from None
        out.write(f'{prompt}{answer}\n')
        if answer.strip().lower() == 'q':
            raise CalibrationAborted('stopped at the person\'s request; nothing written')
        return answer
    return ask


def _keyboard(prompt: str) -> str:
    try:
        answer = input(prompt)
    except EOFError:
        raise CalibrationAborted('input ended; nothing written') from None
    if answer.strip().lower() == 'q':
        raise CalibrationAborted('stopped at the person\'s request; nothing written')
    return answer


def build_parser() -> argparse.ArgumentParser:
    """The command-line parser of smarticle-board-calibrate."""
    parser = argparse.ArgumentParser(prog='smarticle-board-calibrate', description=(__doc__ or '').split('\n')[0])
    add_version(parser, 'smarticle_driver')
    parser.add_argument('--port', default='/dev/ttyACM0', help='serial port of the board (default /dev/ttyACM0)')
    parser.add_argument('--board', default='maestro', help='board protocol (default maestro)')
    parser.add_argument('--out', default='.', help='folder to write servo_calibration.yaml and fsr_calibration.yaml '
                        'into (default: the current folder)')
    parser.add_argument('--start', default=str(default_config_dir() / 'servo_calibration.yaml'),
                        help="servo calibration to start from (default: the package's)")
    parser.add_argument('--servo-channels', type=int, nargs=2, default=(0, 1), metavar=('ARM1', 'ARM2'))
    parser.add_argument('--fsr-channels', type=int, nargs=4, default=(2, 3, 4, 5), metavar='CH',
                        help='analog inputs, in face order ' + ' '.join(topics.FSR_FACES))
    parser.add_argument('--skip', choices=('servos', 'fsrs'), help='leave one part out (its file is not written)')
    parser.add_argument('--answers', help='read the answers from this file, one per line (scripted runs)')
    return parser


def run(args: argparse.Namespace, ask: Ask, say: Callable[[str], None]) -> int:
    """The procedure against the board at ``args.port``; return the exit code."""
    link = SerialLink(args.port, reply_timeout=0.05)
    if not link.poll():
        say(f'smarticle-board-calibrate: cannot open {args.port}: {link.last_error}')
        return 2
    try:
        board = make_board(args.board, link)
        servos = load_servo_calibration(args.start)
        joints = dict(zip(topics.JOINT_NAMES, args.servo_channels, strict=True))
        faces = dict(zip(topics.FSR_FACES, args.fsr_channels, strict=True))
        measured = None if args.skip == 'servos' else calibrate_servos(ask, board, joints, servos, say)
        tables = None if args.skip == 'fsrs' else calibrate_fsrs(ask, board, faces, say)
        for path in write_files(Path(args.out), measured, tables, args.port):
            say(f'wrote {path}')
        say('use them with: servo_bridge --ros-args -p servo_calibration_file:=<servo file> '
            '-p fsr_calibration_file:=<fsr file>')
        return 0
    except CalibrationAborted as err:
        say(f'smarticle-board-calibrate: {err}')
        return 1
    except DriverError as err:
        say(f'smarticle-board-calibrate: {err}')
        return 2
    finally:
        link.close()


def main(argv: list[str] | None = None) -> int:
    """Entry point of smarticle-board-calibrate."""
    args = build_parser().parse_args(argv)

    def say(text: str) -> None:
        print(text, flush=True)
    try:
        ask = _answers(args.answers, sys.stdout) if args.answers else _keyboard
    except OSError as err:
        say(f'smarticle-board-calibrate: cannot read the answers: {err}')
        return 2
    return run(args, ask, say)


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
