"""The servo slew model: constant-speed approach, unknown start, speed changes, velocity sign."""

from __future__ import annotations

import math

import pytest

from smarticle_driver.slew import SlewModel


def test_unknown_position_jumps_to_the_first_target_then_slews() -> None:
    model = SlewModel()
    assert not model.known and math.isnan(model.position(0.0))
    model.set_rate(1000.0, 0.0)
    model.set_target(1500.0, 1.0)
    assert model.position(1.0) == 1500.0
    model.set_target(2000.0, 2.0)
    assert model.position(2.1) == pytest.approx(1600.0)
    assert model.velocity(2.1) == pytest.approx(1000.0)
    assert model.position(2.6) == 2000.0 and model.velocity(2.6) == 0.0


def test_retargeting_mid_move_starts_from_where_the_servo_is() -> None:
    model = SlewModel(rate=500.0)
    model.set_target(1000.0, 0.0)
    model.set_target(2000.0, 0.0)
    model.set_target(1000.0, 0.5)                # reversed at 1250 us
    assert model.position(0.6) == pytest.approx(1200.0)
    assert model.velocity(0.6) == pytest.approx(-500.0)


def test_a_speed_change_applies_from_then_on_and_zero_means_unlimited() -> None:
    model = SlewModel(rate=100.0)
    model.set_target(0.0, 0.0)
    model.set_target(100.0, 0.0)
    model.set_rate(200.0, 0.25)                  # at 25, 75 to go at 200/s
    assert model.position(0.5) == pytest.approx(75.0)
    model.set_rate(0.0, 0.5)
    assert model.position(0.5) == 100.0


def test_forget_makes_the_position_unknown() -> None:
    model = SlewModel(rate=10.0)
    model.set_target(5.0, 0.0)
    model.forget()
    assert not model.known and model.velocity(1.0) == 0.0
