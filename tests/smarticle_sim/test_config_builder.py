"""The one builder of a run's SimConfig and the diagnostics extension beside the shipped PhysicsConfig."""

from __future__ import annotations

import subprocess
from dataclasses import fields
from pathlib import Path

import pytest

from smarticle_sim.bridge import BridgeSettings
from smarticle_sim.cli import build_parser, config_from_args
from smarticle_sim.config_builder import build_config
from smarticle_sim.diagnostics import Diagnostics
from smarticle_sim.errors import ConfigError
from smarticle_sim.settings import NoiseConfig, PhysicsConfig, SimConfig

ROOT = Path(__file__).resolve().parents[2]


def test_the_default_build_is_the_shipped_model() -> None:
    config = build_config()
    assert config == SimConfig() and not config.diagnostics.active and not config.noise.enabled


def test_overrides_noise_and_diagnostics_land_in_their_fields() -> None:
    config = build_config('feedback', {'time_step': 1 / 480}, {'arm_mass': 0.005}, 'paper',
                          {'mass_model': 'uniform', 'cfm': 0.001})
    assert config.robot.name == 'feedback' and config.robot.arm_mass == 0.005
    assert config.physics.time_step == 1 / 480 and config.noise == NoiseConfig.paper()
    assert config.diagnostics.changed == ('cfm',)
    assert build_config(noise={'servo_jitter': 0.01}).noise == NoiseConfig(clock_rate_sd=0.0, servo_jitter=0.01,
                                                                            friction_sd=0.0)


@pytest.mark.parametrize('kwargs, match', [
    ({'physics': {'mass_model': 'authors'}}, r'physics\.mass_model is not a PhysicsConfig field'),
    ({'robot': {'colour': 1}}, r'robot\.colour is not a RobotSpec field'),
    ({'noise': {'seedd': 1}}, r'noise\.seedd is not a NoiseConfig field'),
    ({'diagnostics': {'x_rvt': 0.01}}, r'diagnostics\.x_rvt is not a Diagnostics field'),
    ({'preset': 'huge'}, 'huge'),
    ({'engine': 'ode'}, "unknown engine 'ode'"),
    ({'diagnostics': {'arm_ends': 'round'}, 'engine': 'mujoco'}, r'diagnostics\.arm_ends is built by Bullet only'),
    ({'noise': 'paper', 'engine': 'chrono'}, 'Chrono reference has no noise'),
])
def test_bad_settings_are_one_line_errors_naming_the_field(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        build_config(**kwargs)


def test_the_authors_masses_build_in_every_engine() -> None:
    for engine in ('bullet', 'mujoco', 'chrono'):
        assert build_config(diagnostics={'mass_model': 'authors'}, engine=engine).diagnostics.mass_model == 'authors'


def test_physics_config_holds_no_diagnostic_knob() -> None:
    shipped = {f.name for f in fields(PhysicsConfig)}
    assert not shipped & {f.name for f in fields(Diagnostics)}
    assert not shipped & {'yaw_inertia_scale', 'mass_model', 'plate_friction_slip', 'arm_ends'}


def test_the_cli_and_the_bridge_build_the_same_config_from_the_same_names() -> None:
    args = build_parser().parse_args(['run', '--preset', 'feedback', '--time-step', str(1 / 480),
                                      '--friction-sd', '0.05', '--friction-length', '0.04'])
    cli = config_from_args(args)
    bridge = BridgeSettings.defaults(preset='feedback', time_step=1 / 480, friction_sd=0.05,
                                     friction_length=0.04).sim
    assert cli == bridge == build_config('feedback', {'time_step': 1 / 480},
                                         noise={'friction_sd': 0.05, 'friction_length': 0.04})


def test_simconfig_is_constructed_in_one_module() -> None:
    """Outside the tests (and the archive, run from its own commit), only the builder calls SimConfig(...)."""
    command = ['git', 'grep', '-n', '--untracked', 'SimConfig(', '--', '*.py', ':!tests/', ':!archive/']
    found = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False).stdout.splitlines()
    if not found and not (ROOT / '.git').exists():
        pytest.skip('not a git checkout')
    places = {line.split(':', 1)[0] for line in found}
    assert places == {'smarticle_sim/smarticle_sim/config_builder.py'}
