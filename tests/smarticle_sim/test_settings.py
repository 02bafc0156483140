"""Settings: the presets match the paper, nonsense is refused with the field named."""

from __future__ import annotations

import math

import pytest

from smarticle_sim.config_builder import build_config
from smarticle_sim.errors import ConfigError
from smarticle_sim.settings import (PhysicsConfig, steps_per_tick)


@pytest.mark.parametrize('field, value', [('time_step', 0.0), ('time_step', -1e-3), ('solver_iterations', 0),
                                          ('friction_body_plate', -0.1), ('restitution', 1.5),
                                          ('max_speed', math.inf), ('friction_arm_arm', 0.0),
                                          ('friction_arm_arm', math.nan), ('contact_erp', 0.0),
                                          ('contact_erp', 1.5), ('penetration_checks', 0)])
def test_bad_physics_values_refused(field: str, value: float) -> None:
    with pytest.raises(ConfigError, match=f'PhysicsConfig.{field}'):
        PhysicsConfig(**{field: value})


def test_control_tick_must_be_whole_steps() -> None:
    assert PhysicsConfig().steps_per_tick == 16
    assert steps_per_tick(0.01, 0.001) == 10
    with pytest.raises(ValueError, match='control_tick'):
        PhysicsConfig(time_step=1 / 240, control_tick=0.01)
    with pytest.raises(ValueError, match='control_tick'):
        PhysicsConfig(time_step=0.01, control_tick=0.005)


def test_build_config_rejects_unknown_field() -> None:
    assert build_config('small', {'time_step': 1 / 960, 'control_tick': 1 / 60}).physics.steps_per_tick == 16
    with pytest.raises(ConfigError, match='timestep'):
        build_config('small', {'timestep': 0.01})


@pytest.mark.parametrize('arm_arm', [None, 0.3, 1.5])
def test_link_frictions_multiply_to_the_pair_values(arm_arm: float | None) -> None:
    ph = PhysicsConfig(friction_robot_robot=0.3, friction_body_plate=0.35, friction_arm_arm=arm_arm)
    arm, body, plate = ph.link_frictions()
    assert arm * arm == pytest.approx(0.3 if arm_arm is None else arm_arm)
    assert arm * body == pytest.approx(0.3)
    assert body * plate == pytest.approx(0.35)


def test_unreachable_plate_friction_refused() -> None:
    with pytest.raises(ConfigError, match='friction_arm_arm'):
        PhysicsConfig(friction_robot_robot=0.01, friction_arm_arm=5.0)


def test_a_step_that_lets_arms_pass_through_each_other_is_refused_with_the_field_named() -> None:
    with pytest.raises(ConfigError, match=r'PhysicsConfig\.time_step: .* more than the arm is thick'):
        build_config('small', {'time_step': 1 / 120, 'control_tick': 1 / 60})
    with pytest.raises(ConfigError, match=r'PhysicsConfig\.time_step'):
        build_config('small', {'time_step': 0.1, 'control_tick': 0.1})


def test_a_coarse_step_or_a_fast_servo_is_warned_about() -> None:
    from smarticle_sim.settings import NotConvergedWarning
    with pytest.warns(NotConvergedWarning, match='PhysicsConfig.time_step'):
        build_config('small', {'time_step': 1 / 240, 'control_tick': 1 / 60})
    with pytest.warns(NotConvergedWarning, match='PhysicsConfig.servo_bandwidth'):
        build_config('small', {'servo_bandwidth': 600.0})


def test_a_ccd_radius_larger_than_the_arm_is_refused() -> None:
    with pytest.raises(ConfigError, match='ccd_swept_sphere_radius'):
        build_config('small', {'ccd_swept_sphere_radius': 0.002})
    assert build_config('small', {'ccd_swept_sphere_radius': 0.001}).physics.ccd_swept_sphere_radius == 0.001
