"""Tracks from other trackers: a CSV of robot poses (motion capture, AprilTag or ArUco tracks) into a bag.

The user names the time column and each robot's x, y and heading columns (other columns are ignored),
the length unit (m, cm, mm, or pixels per W, the body width) and the angle unit; ``read_tracks`` turns the
file into ``Tracks`` (seconds, metres, radians) and ``write_bag`` writes them as the stack's pose topic
(``/smarticles/poses``, ``geometry_msgs/msg/PoseArray``, index = robot id), so ``info``, ``analyze``,
``smarticle-calibrate`` and rosbag2 read the result.

Nothing is guessed: a missing value (an empty cell or ``nan``) makes that robot's pose unseen in that
message (the contract's unseen pose, read back as NaN), a time step much longer than the median is
reported as a gap, and neither is filled in. A value that is not a number, a missing time and times
that do not increase are bad input (``CsvImportError``, one line per problem naming the line and
column). Headings are read modulo a full turn: wrapped (to [-180, 180) or [0, 360)) and unwrapped
(continuous) headings give the same pose. No ROS import.
"""

from __future__ import annotations

import csv
import math
import re
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing as npt

from smarticle_common import topics as contract
from smarticle_common.facts import robot_preset
from smarticle_common.errors import RobotSpecError

from .errors import CsvImportError, OptionError
from .metadata import BagInfo
from .qos import QosRecord
from .timebase import TimeBase, custom_data
from .writer import BagWriter, WriterOptions

FloatArray = npt.NDArray[np.float64]

#: Metres per length unit a CSV may use (``px``: see ``ImportSpec.length_scale``).
LENGTH_UNITS: dict[str, float] = {'m': 1.0, 'cm': 0.01, 'mm': 0.001}
#: Seconds per time unit a CSV may use.
TIME_UNITS: dict[str, float] = {'s': 1.0, 'ms': 1e-3, 'us': 1e-6, 'ns': 1e-9}
#: Cells that mean "no value here" (a gap): empty, or NaN as spreadsheets and pandas write it.
MISSING = frozenset({'', 'nan', 'NaN', 'NAN', 'NA', 'N/A', 'null'})
#: A time step longer than this many median steps is reported as a gap.
GAP_FACTOR = 3.0
#: Problems listed before the rest are only counted.
MAX_LISTED = 20

#: The offered QoS written for the imported pose topic: the contract's sensor profile.
SENSOR_QOS = QosRecord(history='keep_last', depth=10, reliability='best_effort', durability='volatile')


@dataclass(frozen=True)
class RobotColumns:
    """The CSV columns of one robot's pose."""

    robot: int
    x: str
    y: str
    heading: str


@dataclass(frozen=True)
class ImportSpec:
    """How to read a CSV of tracks: columns, units and conventions (checked on construction)."""

    time: str
    robots: tuple[RobotColumns, ...]
    length_unit: str = 'm'              # 'm', 'cm', 'mm' or 'px'
    px_per_bl: float | None = None      # with length_unit 'px': pixels per W (body width)
    body_preset: str = 'small'          # the robot whose W a pixel length is scaled by
    angle_unit: str = 'rad'             # 'rad' or 'deg'
    time_unit: str = 's'
    time_offset: float = 0.0            # s added to every time (after the unit)
    heading_offset: float = 0.0         # rad added to every heading (tracker's zero to the body normal)
    y_down: bool = False                # the tracker's y axis points down (image rows): mirror y and headings
    gap_factor: float = GAP_FACTOR

    def __post_init__(self) -> None:
        """Reject nonsense with a message naming the option."""
        if not self.robots:
            raise OptionError('name at least one robot\'s columns (--robot K:X,Y,H or --pattern X,Y,H)')
        ids = [r.robot for r in self.robots]
        if len(set(ids)) != len(ids):
            raise OptionError(f'a robot id is given twice: {sorted(ids)}')
        for r in self.robots:
            try:
                contract.validate_robot_id(r.robot)
            except contract.ContractError as err:
                raise OptionError(str(err)) from None
        if self.length_unit == 'px':
            if self.px_per_bl is None or not math.isfinite(self.px_per_bl) or self.px_per_bl <= 0.0:
                raise OptionError(f'pixel tracks need --px-per-bl > 0 (pixels per W, the body width), '
                                  f'got {self.px_per_bl}')
            try:
                robot_preset(self.body_preset)
            except RobotSpecError as err:
                raise OptionError(str(err)) from None
        elif self.length_unit not in LENGTH_UNITS:
            raise OptionError(f'length unit must be one of {", ".join([*LENGTH_UNITS, "px"])}, '
                              f'got {self.length_unit!r}')
        elif self.px_per_bl is not None:
            raise OptionError(f'--px-per-bl is for pixel tracks; the length unit is {self.length_unit}')
        if self.angle_unit not in ('rad', 'deg'):
            raise OptionError(f'angle unit must be rad or deg, got {self.angle_unit!r}')
        if self.time_unit not in TIME_UNITS:
            raise OptionError(f'time unit must be one of {", ".join(TIME_UNITS)}, got {self.time_unit!r}')
        for name in ('time_offset', 'heading_offset'):
            if not math.isfinite(getattr(self, name)):
                raise OptionError(f'{name.replace("_", " ")} must be finite, got {getattr(self, name)}')
        if not (math.isfinite(self.gap_factor) and self.gap_factor > 1.0):
            raise OptionError(f'gap factor must be > 1 (median time steps), got {self.gap_factor}')

    @property
    def length_scale(self) -> float:
        """Metres per CSV length unit (for pixels: W of ``body_preset`` / ``px_per_bl``)."""
        if self.length_unit == 'px':
            assert self.px_per_bl is not None
            return robot_preset(self.body_preset).body_length / self.px_per_bl
        return LENGTH_UNITS[self.length_unit]

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column the import reads: time first, then x, y, heading per robot."""
        return (self.time, *(c for r in self.robots for c in (r.x, r.y, r.heading)))

    def describe_units(self) -> str:
        """One line: how lengths, angles and times are converted."""
        if self.length_unit == 'px':
            w = robot_preset(self.body_preset).body_length
            length = (f'px, {self.px_per_bl:g} px per W (W = {w:g} m, robot {self.body_preset}): '
                      f'x {self.length_scale:.6g} m')
        else:
            length = f'{self.length_unit}: x {self.length_scale:g} m'
        angle = 'deg: x pi/180 rad' if self.angle_unit == 'deg' else 'rad'
        extra = []
        if self.heading_offset:
            extra.append(f'heading + {math.degrees(self.heading_offset):g} deg')
        if self.y_down:
            extra.append('y axis down: y and heading mirrored')
        time = f'{self.time_unit}: x {TIME_UNITS[self.time_unit]:g} s, + {self.time_offset:g} s'
        return '; '.join([f'length {length}', f'angle {angle}', f'time {time}', *extra])

    def describe_columns(self) -> str:
        """One line: which columns were read."""
        robots = '; '.join(f'{r.robot}: {r.x},{r.y},{r.heading}' for r in self.robots)
        return f'time: {self.time}; {robots}'


@dataclass(frozen=True)
class Tracks:
    """Poses read from a CSV: ``xyh[t, robot]`` in m, m, rad (NaN where missing), times in s."""

    time: FloatArray          # (T,) seconds, after the unit and the offset
    xyh: FloatArray           # (T, N, 3), N = largest robot id + 1
    lines: npt.NDArray[np.int64]   # (T,) the line number of each row in the file (1 = first line)
    gaps: tuple[str, ...]     # one line per gap found (missing values, long time steps)


def parse_robot(text: str) -> RobotColumns:
    """Parse ``K:X,Y,H`` (robot id, then its x, y and heading columns) or raise OptionError."""
    match = re.fullmatch(r'\s*(\d+)\s*:\s*([^,]+),([^,]+),([^,]+)\s*', text)
    if match is None:
        raise OptionError(f'--robot {text!r}: give ROBOT_ID:X_COLUMN,Y_COLUMN,HEADING_COLUMN, e.g. 0:x0,y0,h0')
    robot, x, y, h = match.groups()
    return RobotColumns(int(robot), x.strip(), y.strip(), h.strip())


def robots_from_pattern(pattern: str, header: Sequence[str]) -> tuple[RobotColumns, ...]:
    """Every robot k whose three columns of ``pattern`` (``X,Y,H`` with ``{k}``) are all in ``header``."""
    parts = [p.strip() for p in pattern.split(',')]
    if len(parts) != 3 or not all('{k}' in p for p in parts):
        raise OptionError(f'--pattern {pattern!r}: give three column names with {{k}} for the robot id, '
                          'e.g. x{k},y{k},h{k}')
    regex = re.compile('^' + re.escape(parts[0]).replace(re.escape('{k}'), r'(\d+)') + '$')
    names = set(header)
    robots = []
    for column in header:
        match = regex.match(column)
        if match is None:
            continue
        k = match.group(1)
        if all(p.replace('{k}', k) in names for p in parts[1:]):
            robots.append(RobotColumns(int(k), *(p.replace('{k}', k) for p in parts)))
    if not robots:
        raise OptionError(f'--pattern {pattern!r} matches no robot\'s three columns in the header '
                          f'({", ".join(header)})')
    return tuple(sorted(robots, key=lambda r: r.robot))


def read_header(path: Path, delimiter: str | None = None, skip_rows: int = 0) -> tuple[list[str], str]:
    """The column names of a CSV (after ``skip_rows`` lines) and its delimiter (sniffed if not given)."""
    with open(path, newline='', encoding='utf-8-sig') as stream:
        for _ in range(skip_rows):
            stream.readline()
        line = stream.readline()
    if not line.strip():
        raise CsvImportError([f'{path.name}: no header line (line {skip_rows + 1} is empty); the first line '
                              'after --skip-rows must name the columns'])
    if delimiter is None:
        counts = {d: line.count(d) for d in (',', ';', '\t')}
        delimiter = max(counts, key=lambda d: counts[d]) if any(counts.values()) else ','
    header = next(csv.reader([line], delimiter=delimiter))
    return [name.strip() for name in header], delimiter


def _number(cell: str) -> float | None:
    """The value of a cell: a float, None for a missing one; ValueError if it is not a number."""
    text = cell.strip()
    if text in MISSING:
        return None
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(text)
    return value


def _listed(problems: list[str]) -> list[str]:
    """At most MAX_LISTED problems, then a line counting the rest."""
    if len(problems) <= MAX_LISTED:
        return problems
    return [*problems[:MAX_LISTED], f'... and {len(problems) - MAX_LISTED} more']


def read_tracks(path: Path | str, spec: ImportSpec, delimiter: str | None = None,
                skip_rows: int = 0) -> Tracks:
    """Read the named columns of a CSV into ``Tracks``; CsvImportError lists every bad row."""
    path = Path(path)
    header, delimiter = read_header(path, delimiter, skip_rows)
    index = {name: i for i, name in enumerate(header)}
    absent = [c for c in spec.columns if c not in index]
    if absent:
        raise CsvImportError([f'{path.name}: column {c!r} is not in the header (columns: {", ".join(header)})'
                              for c in absent])
    wanted = [index[c] for c in spec.columns]
    problems: list[str] = []
    rows: list[list[float | None]] = []
    lines: list[int] = []
    with open(path, newline='', encoding='utf-8-sig') as stream:
        for _ in range(skip_rows + 1):
            stream.readline()
        for offset, cells in enumerate(csv.reader(stream, delimiter=delimiter)):
            line = skip_rows + 2 + offset
            if not cells or all(not c.strip() for c in cells):
                continue   # a blank line
            if len(cells) <= max(wanted):
                problems.append(f'{path.name} line {line}: {len(cells)} cells, the header has {len(header)}')
                continue
            row: list[float | None] = []
            for column, i in zip(spec.columns, wanted, strict=True):
                try:
                    value = _number(cells[i])
                except ValueError:
                    problems.append(f'{path.name} line {line}, column {column!r}: {cells[i].strip()!r} is not '
                                    'a finite number')
                    value = math.nan
                if value is None and column == spec.time:
                    problems.append(f'{path.name} line {line}, column {column!r}: no time')
                row.append(value)
            rows.append(row)
            lines.append(line)
    if problems:
        raise CsvImportError(_listed(problems))
    if len(rows) < 2:
        raise CsvImportError([f'{path.name}: {len(rows)} row(s) of tracks; at least 2 are needed'])
    values = np.array([[math.nan if v is None else v for v in row] for row in rows], dtype=float)
    line_numbers = np.asarray(lines, dtype=np.int64)
    time = values[:, 0] * TIME_UNITS[spec.time_unit] + spec.time_offset
    steps = np.diff(time)
    backwards = np.flatnonzero(steps <= 0.0)
    if backwards.size:
        raise CsvImportError(_listed([
            f'{path.name} line {line_numbers[i + 1]}: time {time[i + 1]:.6g} s is not after line '
            f'{line_numbers[i]}\'s {time[i]:.6g} s (sort the rows by time or remove the repeated ones)'
            for i in backwards]))
    if time[0] < 0.0:
        raise CsvImportError([f'{path.name} line {line_numbers[0]}: time {time[0]:.6g} s is before 0; a bag\'s '
                              f'times start at 0 or later: add --time-offset {math.ceil(-time[0])}'])
    n = max(r.robot for r in spec.robots) + 1
    xyh = np.full((len(time), n, 3), math.nan)
    scale = spec.length_scale
    to_rad = math.pi / 180.0 if spec.angle_unit == 'deg' else 1.0
    gaps: list[str] = []
    for j, r in enumerate(spec.robots):
        x, y, h = (values[:, 1 + 3 * j + c] for c in range(3))
        heading = h * to_rad + spec.heading_offset
        if spec.y_down:
            y, heading = -y, -heading
        xyh[:, r.robot, 0] = x * scale
        xyh[:, r.robot, 1] = y * scale
        xyh[:, r.robot, 2] = np.mod(heading + math.pi, 2.0 * math.pi) - math.pi
        missing = ~(np.isfinite(x) & np.isfinite(y) & np.isfinite(h))
        xyh[missing, r.robot, :] = math.nan
        gaps += [f'{path.name} {_span(line_numbers, a, b)}: robot {r.robot} has no pose (t = {time[a]:.6g}'
                 f'{"" if a == b else f" to {time[b]:.6g}"} s, {b - a + 1} row{"s" if b > a else ""}); '
                 'written as unseen, not interpolated' for a, b in _runs(missing)]
    median = float(np.median(steps))
    for at in np.flatnonzero(steps > spec.gap_factor * median):
        gaps.append(f'{path.name} lines {line_numbers[at]}-{line_numbers[at + 1]}: {steps[at]:.6g} s between rows, '
                    f'{steps[at] / median:.1f}x the median step {median:.6g} s; nothing filled in')
    return Tracks(time=time, xyh=xyh, lines=line_numbers, gaps=tuple(gaps))


def _span(lines: npt.NDArray[np.int64], a: int, b: int) -> str:
    """``line N`` or ``lines N-M`` for rows a..b."""
    return f'line {lines[a]}' if a == b else f'lines {lines[a]}-{lines[b]}'


def _runs(mask: npt.NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(first, last) index of each run of True in ``mask``."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [(int(a), int(b)) for a, b in zip(starts, ends, strict=True)]


def _cdr_string(text: str, offset: int) -> tuple[bytes, int]:
    """A CDR string (length with NUL, bytes, NUL) at ``offset``; returns it and the offset after it."""
    data = text.encode() + b'\0'
    return struct.pack('<I', len(data)) + data, offset + 4 + len(data)


def encode_pose_array(stamp_ns: int, xyh: FloatArray, frame_id: str = contract.ARENA_FRAME) -> bytes:
    """CDR (little endian) of a ``geometry_msgs/msg/PoseArray``: robot k at ``xyh[k]``, unseen where NaN."""
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    out = bytearray(b'\x00\x01\x00\x00')              # encapsulation: CDR little endian
    out += struct.pack('<iI', sec, nanosec)
    text, offset = _cdr_string(frame_id, 8)
    out += text
    pad = -offset % 4
    out += b'\0' * pad
    offset += pad
    out += struct.pack('<I', len(xyh))
    offset += 4
    pad = -offset % 8
    out += b'\0' * pad
    poses = np.zeros((len(xyh), 7))
    poses[:, 6] = 1.0
    seen = np.all(np.isfinite(xyh), axis=1)
    poses[seen, 0:2] = xyh[seen, 0:2]
    poses[~seen, 2] = contract.UNSEEN_Z
    poses[seen, 5] = np.sin(xyh[seen, 2] / 2.0)
    poses[seen, 6] = np.cos(xyh[seen, 2] / 2.0)
    out += poses.astype('<f8').tobytes()
    return bytes(out)


def write_bag(tracks: Tracks, output: Path | str, spec: ImportSpec, source: str,
              options: WriterOptions | None = None) -> BagInfo:
    """Write ``tracks`` as the stack's pose topic into a new bag folder; its metadata names the source."""
    notes = {
        'imported_from': f'CSV {source}',
        'import_columns': spec.describe_columns(),
        'import_units': spec.describe_units(),
        'import_gaps': str(len(tracks.gaps)),
        **custom_data(TimeBase.TRACKER),
    }
    topic = contract.topic('poses')
    with BagWriter(output, options, custom_data=notes) as writer:
        writer.add_topic(topic, contract.spec_of('poses').type, [SENSOR_QOS])
        for t, xyh in zip(tracks.time, tracks.xyh, strict=True):
            ns = int(round(float(t) * 1e9))
            writer.write(topic, encode_pose_array(ns, xyh), ns)
        return writer.close()
