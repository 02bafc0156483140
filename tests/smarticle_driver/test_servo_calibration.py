"""Servo and FSR calibration maths, the shipped files, and bad files that must stop start-up clearly."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from smarticle_common import topics
from smarticle_driver.board_calibration import (DividerFsr, ServoCalibration, TableFsr, default_config_dir,
                                          load_fsr_calibration, load_servo_calibration)
from smarticle_driver.errors import CalibrationError

CONFIG = Path(__file__).resolve().parents[2] / 'smarticle_driver' / 'config'


def test_servo_angle_and_pulse_convert_both_ways_with_either_sign() -> None:
    for cal in (ServoCalibration(1500, 600, 500, 2500), ServoCalibration(1480, -550, 600, 2400)):
        for angle in (-1.2, 0.0, 0.3, math.pi / 2 * 0.99):
            assert cal.pulse_to_angle(cal.angle_to_pulse(angle)) == pytest.approx(angle)
    mirrored = ServoCalibration(1500, -600, 500, 2500)
    assert mirrored.angle_to_pulse(0.5) == pytest.approx(1200.0)
    assert mirrored.angle_limits() == pytest.approx((-1000 / 600, 1000 / 600))
    assert mirrored.rate_to_pulse_rate(2.0) == pytest.approx(1200.0)


@pytest.mark.parametrize('kwargs, field', [
    ({'us_per_rad': 0.0}, 'us_per_rad'), ({'min_us': 2600.0}, 'min_us'),
    ({'center_us': 3000.0, 'max_us': 2600.0}, 'center_us'), ({'center_us': math.nan}, 'center_us'),
])
def test_nonsense_servo_calibrations_are_refused(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(CalibrationError, match=field):
        ServoCalibration(**kwargs)


def test_divider_model_follows_the_voltage_divider_and_conductance_law() -> None:
    fsr = DividerFsr()   # 5 V, 10 kOhm, 80 uS/N up to 1000 uS, then 30 uS/N
    # 2.5 V out: R_fsr = Rm = 10 kOhm -> G = 100 uS -> 1.25 N
    assert fsr.newtons(1023 / 2) == pytest.approx(1.25)
    # 4.5 V out: R_fsr = 10k * 0.5 / 4.5 = 1111 Ohm -> 900 uS -> 11.25 N
    assert fsr.newtons(1023 * 0.9) == pytest.approx(11.25)
    # above the knee: 4.9 V -> R = 204.08 Ohm -> 4900 uS -> 12.5 + 3900 / 30 = 142.5 N, capped at 100 N
    assert fsr.newtons(1023 * 0.98) == pytest.approx(100.0)
    assert DividerFsr(max_newtons=1000).newtons(1023 * 0.98) == pytest.approx(142.5)
    assert fsr.newtons(0) == 0.0 and fsr.newtons(1023) == 100.0
    forces = [fsr.newtons(c) for c in range(0, 1024, 8)]
    assert forces == sorted(forces)
    for newtons in (0.3, 5.0, 12.5, 40.0):
        assert fsr.newtons(fsr.counts_for(newtons)) == pytest.approx(newtons)


def test_lookup_table_interpolates_linearly_and_holds_its_ends() -> None:
    table = TableFsr(((100.0, 0.0), (300.0, 2.0), (700.0, 10.0)))
    assert table.newtons(50) == 0.0
    assert table.newtons(200) == pytest.approx(1.0)
    assert table.newtons(500) == pytest.approx(6.0)
    assert table.newtons(1000) == 10.0


def test_the_shipped_files_load_and_are_found_from_the_package() -> None:
    assert (default_config_dir() / 'servo_calibration.yaml').exists()
    servos = load_servo_calibration(CONFIG / 'servo_calibration.yaml')
    assert set(servos) == set(topics.JOINT_NAMES)
    lo, hi = servos['arm1'].angle_limits()
    assert lo < -math.radians(90) and hi > math.radians(90), 'default limits must allow a 90 degree gait'
    fsrs = load_fsr_calibration(CONFIG / 'fsr_calibration.yaml')
    assert set(fsrs) == set(topics.FSR_FACES)


SERVO_OK = 'servos:\n  arm1: {center_us: 1500, us_per_rad: 600, min_us: 500, max_us: 2500}\n' \
           '  arm2: {center_us: 1500, us_per_rad: -600, min_us: 500, max_us: 2500}\n'


@pytest.mark.parametrize('text, field, expected', [
    ('servos: [1, 2]\n', "'servos'", 'mapping'),
    (SERVO_OK.replace('us_per_rad: 600,', "us_per_rad: 'fast',"), 'servos.arm1.us_per_rad', 'finite number'),
    (SERVO_OK.replace('min_us: 500, max_us: 2500}\n  arm2', 'min_us: 500}\n  arm2').replace(
        'center_us: 1500, us_per_rad: 600', 'center_us: 2600, us_per_rad: 600'), 'servos.arm1', 'center_us'),
    (SERVO_OK.replace('  arm2:', '  arm3:'), 'servos.arm2', 'mapping'),
    (SERVO_OK + '  arm3: {}\n', 'servos.arm3', 'unknown joint'),
    (SERVO_OK.replace('min_us: 500, max_us', 'min_um: 500, max_us'), "servos.arm1.'min_um'",
     'expected one of'),
    ('servos: {arm1: {center_us: 1500\n', '', 'not valid YAML'),
])
def test_bad_servo_files_name_the_file_the_field_and_the_expectation(tmp_path: Path, text: str, field: str,
                                                                      expected: str) -> None:
    path = tmp_path / 'servo_calibration.yaml'
    path.write_text(text)
    with pytest.raises(CalibrationError) as info:
        load_servo_calibration(path)
    message = str(info.value)
    assert str(path) in message and field in message and expected in message, message


FSR_OK = 'sensors:\n  arm1_front: {}\n  arm1_back: {}\n  arm2_front: {}\n  arm2_back: {}\n'


@pytest.mark.parametrize('text, field, expected', [
    (FSR_OK.replace('  arm2_back: {}\n', ''), 'sensors.arm2_back', 'missing'),
    (FSR_OK.replace('arm1_back: {}', 'arm1_back: {r_measure_ohm: -5}'), 'sensors.arm1_back', 'positive'),
    (FSR_OK.replace('arm1_back: {}', 'arm1_back: {model: spline}'), 'sensors.arm1_back.model',
     "'divider' or 'table'"),
    (FSR_OK.replace('arm1_back: {}', 'arm1_back: {model: table, points: [[0, 0], [0, 1]]}'),
     'sensors.arm1_back', 'increasing'),
    (FSR_OK.replace('arm1_back: {}', 'arm1_back: {model: table, points: [1, 2]}'), 'sensors.arm1_back.points',
     '[counts, newtons]'),
    (FSR_OK + '  arm3_front: {}\n', 'sensors.arm3_front', 'unknown FSR face'),
    ('defaults: 3\n' + FSR_OK, 'defaults', 'mapping'),
])
def test_bad_fsr_files_name_the_file_the_field_and_the_expectation(tmp_path: Path, text: str, field: str,
                                                                    expected: str) -> None:
    path = tmp_path / 'fsr_calibration.yaml'
    path.write_text(text)
    with pytest.raises(CalibrationError) as info:
        load_fsr_calibration(path)
    message = str(info.value)
    assert str(path) in message and field in message and expected in message, message


def test_a_missing_file_is_a_calibration_error(tmp_path: Path) -> None:
    with pytest.raises(CalibrationError, match='cannot read'):
        load_fsr_calibration(tmp_path / 'nope.yaml')


def test_table_sensors_and_defaults_mix(tmp_path: Path) -> None:
    path = tmp_path / 'fsr.yaml'
    path.write_text('defaults: {r_measure_ohm: 4700}\n' + FSR_OK.replace(
        'arm2_back: {}', 'arm2_back: {model: table, points: [[0, 0], [1000, 20]]}'))
    fsrs = load_fsr_calibration(path)
    assert fsrs['arm1_front'] == DividerFsr(r_measure_ohm=4700.0)
    assert fsrs['arm2_back'].newtons(500) == pytest.approx(10.0)
