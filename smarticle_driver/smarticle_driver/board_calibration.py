"""Per-servo and per-FSR calibration: arm angle <-> pulse width, ADC counts -> newtons, YAML files.

Servo (one per joint, ``servo_calibration.yaml``)::

    pulse_us = center_us + us_per_rad * alpha        (limited to min_us .. max_us)

``us_per_rad`` may be negative (a mirrored servo). Angles in radians, pulses in microseconds.

FSR (one per face, ``fsr_calibration.yaml``), model ``divider``: the FSR 402 sits between the supply
``vcc`` and the analog input, the measuring resistor ``r_measure_ohm`` from the input to ground, so::

    v_out  = counts / adc_full_scale * adc_volts
    v_out  = vcc * Rm / (Rm + R_fsr)        ->   R_fsr = Rm * (vcc - v_out) / v_out
    G      = 1 / R_fsr  (in microsiemens)
    F      = G / micro_siemens_per_newton                                  for G <= knee_micro_siemens
    F      = knee / micro_siemens_per_newton + (G - knee) / micro_siemens_per_newton_above_knee  above

The FSR's conductance is roughly proportional to force (Interlink FSR 400-series integration guide);
the default constants (10 kOhm measuring resistor, 80 uS/N up to 1000 uS, then 30 uS/N) are the
widely used piecewise-linear fit of the FSR 402 datasheet curve (Adafruit's FSR guide). Readings at
or below ``zero_counts`` are 0 N, and the force is capped at ``max_newtons`` (the FSR 402 saturates
near 100 N). Model ``table`` instead interpolates linearly in a measured ``points`` list of
``[counts, newtons]`` pairs (counts increasing), holding the end values outside it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Protocol

import yaml

from smarticle_common import topics
from smarticle_driver.errors import CalibrationError

#: Longest pulse a Maestro can emit (14-bit quarter-microseconds).
MAX_PULSE_US = 0x3FFF / 4.0


@dataclass(frozen=True)
class ServoCalibration:
    """Linear angle <-> pulse map of one servo, with the pulse limits of its mechanics."""

    center_us: float = 1500.0
    us_per_rad: float = 600.0
    min_us: float = 500.0
    max_us: float = 2500.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not math.isfinite(value):
                raise CalibrationError(f'servo calibration {f.name}: expected a finite number, got {value!r}')
        if self.us_per_rad == 0.0:
            raise CalibrationError('servo calibration us_per_rad: expected a non-zero number, got 0')
        if not 0.0 < self.min_us < self.max_us <= MAX_PULSE_US:
            raise CalibrationError(f'servo calibration min_us/max_us: expected 0 < min_us < max_us <= '
                                   f'{MAX_PULSE_US}, got {self.min_us} and {self.max_us}')
        if not self.min_us <= self.center_us <= self.max_us:
            raise CalibrationError(f'servo calibration center_us: expected a value within min_us..max_us '
                                   f'({self.min_us}..{self.max_us}), got {self.center_us}')

    def angle_to_pulse(self, angle: float) -> float:
        """Return the pulse width (us) for arm angle ``angle`` (rad), not limited."""
        return self.center_us + self.us_per_rad * angle

    def pulse_to_angle(self, pulse_us: float) -> float:
        """Return the arm angle (rad) of pulse width ``pulse_us``."""
        return (pulse_us - self.center_us) / self.us_per_rad

    def angle_limits(self) -> tuple[float, float]:
        """Return the (lowest, highest) reachable angle in radians."""
        a, b = self.pulse_to_angle(self.min_us), self.pulse_to_angle(self.max_us)
        return (min(a, b), max(a, b))

    def rate_to_pulse_rate(self, rad_per_s: float) -> float:
        """Convert an angular speed (rad/s) to a pulse rate (us/s)."""
        return abs(self.us_per_rad) * rad_per_s


class FsrModel(Protocol):
    """Anything that turns ADC counts into a force in newtons."""

    def newtons(self, counts: float) -> float:
        """Return the force (N) of an ADC reading."""


@dataclass(frozen=True)
class DividerFsr:
    """FSR 402 in a voltage divider with a measuring resistor (see the module docstring)."""

    vcc: float = 5.0
    r_measure_ohm: float = 10_000.0
    adc_full_scale: float = 1023.0
    adc_volts: float = 5.0
    micro_siemens_per_newton: float = 80.0
    knee_micro_siemens: float = 1000.0
    micro_siemens_per_newton_above_knee: float = 30.0
    zero_counts: float = 0.0
    max_newtons: float = 100.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            minimum = 0.0 if f.name in ('zero_counts', 'knee_micro_siemens') else None
            if not math.isfinite(value) or (value < 0.0 if minimum is not None else value <= 0.0):
                want = 'a finite number >= 0' if minimum is not None else 'a finite positive number'
                raise CalibrationError(f'FSR calibration {f.name}: expected {want}, got {value!r}')

    def newtons(self, counts: float) -> float:
        """Return the force (N) of an ADC reading through the divider and conductance model."""
        if counts <= self.zero_counts:
            return 0.0
        v_out = counts / self.adc_full_scale * self.adc_volts
        if v_out >= self.vcc:
            return self.max_newtons
        r_fsr = self.r_measure_ohm * (self.vcc - v_out) / v_out
        conductance = 1e6 / r_fsr
        if conductance <= self.knee_micro_siemens:
            force = conductance / self.micro_siemens_per_newton
        else:
            force = (self.knee_micro_siemens / self.micro_siemens_per_newton
                     + (conductance - self.knee_micro_siemens) / self.micro_siemens_per_newton_above_knee)
        return min(force, self.max_newtons)

    def counts_for(self, newtons: float) -> float:
        """Return the ADC reading that gives ``newtons`` (the inverse model, for tests and emulators)."""
        if newtons <= 0.0:
            return 0.0
        knee_force = self.knee_micro_siemens / self.micro_siemens_per_newton
        if newtons <= knee_force:
            conductance = newtons * self.micro_siemens_per_newton
        else:
            above = (newtons - knee_force) * self.micro_siemens_per_newton_above_knee
            conductance = self.knee_micro_siemens + above
        r_fsr = 1e6 / conductance
        v_out = self.vcc * self.r_measure_ohm / (self.r_measure_ohm + r_fsr)
        return v_out / self.adc_volts * self.adc_full_scale


@dataclass(frozen=True)
class TableFsr:
    """Measured lookup table: linear interpolation of newtons over increasing ADC counts."""

    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        if len(self.points) < 2:
            raise CalibrationError('FSR calibration points: expected at least two [counts, newtons] pairs')
        for (c0, _), (c1, _) in zip(self.points, self.points[1:], strict=False):
            if not c1 > c0:
                raise CalibrationError('FSR calibration points: expected strictly increasing counts, '
                                       f'got {c0} then {c1}')
        for counts, force in self.points:
            if not (math.isfinite(counts) and math.isfinite(force) and force >= 0.0):
                raise CalibrationError(f'FSR calibration points: expected finite counts and newtons >= 0, '
                                       f'got [{counts}, {force}]')

    def newtons(self, counts: float) -> float:
        """Return the force (N) interpolated at ``counts`` (end values outside the table)."""
        pts = self.points
        if counts <= pts[0][0]:
            return pts[0][1]
        for (c0, f0), (c1, f1) in zip(pts, pts[1:], strict=False):
            if counts <= c1:
                return f0 + (f1 - f0) * (counts - c0) / (c1 - c0)
        return pts[-1][1]


def default_config_dir() -> Path:
    """Return the package's config folder: the colcon-installed share dir if any, else the source tree."""
    try:
        from ament_index_python.packages import (PackageNotFoundError,
                                                 get_package_share_directory)
        try:
            share = Path(get_package_share_directory('smarticle_driver')) / 'config'
            if share.is_dir():
                return share
        except (PackageNotFoundError, OSError, ValueError):
            pass
    except ImportError:
        pass
    return Path(__file__).resolve().parents[1] / 'config'


def _load_yaml(path: str | Path) -> Any:
    p = Path(path)
    try:
        text = p.read_text(encoding='utf-8')
    except OSError as err:
        raise CalibrationError(f'{p}: cannot read the calibration file ({err.strerror or err})') from err
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise CalibrationError(f'{p}: not valid YAML ({err})') from err


def _section(path: str | Path, data: Any, key: str, what: str) -> dict[str, Any]:
    if not isinstance(data, dict) or not isinstance(data.get(key), dict):
        raise CalibrationError(f'{path}: field {key!r}: expected a mapping of {what}, got '
                               f'{type(data.get(key) if isinstance(data, dict) else data).__name__}')
    return data[key]


def _number(path: str | Path, field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise CalibrationError(f'{path}: field {field!r}: expected a finite number, got {value!r}')
    return float(value)


def _build(path: str | Path, where: str, cls: type, raw: Mapping[str, Any], skip: Sequence[str] = ()) -> Any:
    allowed = {f.name for f in fields(cls)}
    values: dict[str, Any] = {}
    for name, value in raw.items():
        if name in skip:
            continue
        if name not in allowed:
            raise CalibrationError(f'{path}: field {where}.{name!r} is unknown; expected one of '
                                   f'{", ".join(sorted(allowed))}')
        values[name] = _number(path, f'{where}.{name}', value)
    try:
        return cls(**values)
    except CalibrationError as err:
        raise CalibrationError(f'{path}: {where}: {err}') from err


def load_servo_calibration(path: str | Path) -> dict[str, ServoCalibration]:
    """Read ``servos: {arm1: {...}, arm2: {...}}`` from a YAML file; raise CalibrationError if invalid."""
    servos = _section(path, _load_yaml(path), 'servos', 'joint name -> calibration')
    result: dict[str, ServoCalibration] = {}
    for joint in topics.JOINT_NAMES:
        raw = servos.get(joint)
        if not isinstance(raw, dict):
            raise CalibrationError(f'{path}: field servos.{joint}: expected a mapping with center_us, '
                                   f'us_per_rad, min_us, max_us, got {raw!r}')
        result[joint] = _build(path, f'servos.{joint}', ServoCalibration, raw)
    extra = set(servos) - set(topics.JOINT_NAMES)
    if extra:
        raise CalibrationError(f'{path}: field servos.{sorted(extra)[0]}: unknown joint; expected '
                               f'{", ".join(topics.JOINT_NAMES)}')
    return result


def _fsr_model(path: str | Path, face: str, raw: dict[str, Any]) -> FsrModel:
    model = raw.get('model', 'divider')
    if model == 'divider':
        return _build(path, f'sensors.{face}', DividerFsr, raw, skip=('model',))
    if model == 'table':
        extra = set(raw) - {'model', 'points'}
        if extra:
            raise CalibrationError(f'{path}: field sensors.{face}.{sorted(extra)[0]} is unknown for model '
                                   'table; expected points')
        pts = raw.get('points')
        if not isinstance(pts, list) or not all(isinstance(p, list) and len(p) == 2 for p in pts):
            raise CalibrationError(f'{path}: field sensors.{face}.points: expected a list of '
                                   f'[counts, newtons] pairs, got {pts!r}')
        where = f'sensors.{face}.points'
        points = tuple((_number(path, where, c), _number(path, where, f)) for c, f in pts)
        try:
            return TableFsr(points)
        except CalibrationError as err:
            raise CalibrationError(f'{path}: sensors.{face}: {err}') from err
    raise CalibrationError(f"{path}: field sensors.{face}.model: expected 'divider' or 'table', "
                           f'got {model!r}')


def load_fsr_calibration(path: str | Path) -> dict[str, FsrModel]:
    """Read ``sensors: {<face>: {...}}`` (plus optional ``defaults``) for the four FSR faces."""
    data = _load_yaml(path)
    sensors = _section(path, data, 'sensors', 'FSR face -> calibration')
    defaults = data.get('defaults', {})
    if not isinstance(defaults, dict):
        raise CalibrationError(f'{path}: field defaults: expected a mapping, got {defaults!r}')
    extra = set(sensors) - set(topics.FSR_FACES)
    if extra:
        raise CalibrationError(f'{path}: field sensors.{sorted(extra)[0]}: unknown FSR face; expected '
                               f'{", ".join(topics.FSR_FACES)}')
    result: dict[str, FsrModel] = {}
    for face in topics.FSR_FACES:
        raw = sensors.get(face)
        if raw is None:
            raise CalibrationError(f'{path}: field sensors.{face}: missing; every face of '
                                   f'{", ".join(topics.FSR_FACES)} needs an entry '
                                   '(use {} for the defaults)')
        if not isinstance(raw, dict):
            raise CalibrationError(f'{path}: field sensors.{face}: expected a mapping, got {raw!r}')
        is_table = raw.get('model', defaults.get('model', 'divider')) == 'table'
        merged = dict(raw) if is_table else {**defaults, **raw}
        result[face] = _fsr_model(path, face, merged)
    return result
