"""Noise with a cause: clock rates, servo jitter and the plate's friction field; seeded, and nothing when off."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig

from smarticle_sim.batch import run_trial
from smarticle_sim.bridge import BridgeSettings, SimBridgeCore
from smarticle_sim.cli import build_parser, noise_from_args
from smarticle_sim.drift import phase_drift
from smarticle_sim.errors import ConfigError
from smarticle_sim.noise import FrictionField, ServoDelays, clock_rates
from smarticle_sim.physics import ARM_JOINTS, Physics
from smarticle_sim.runner import GaitController, Runner
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene
from smarticle_sim.settings import CLOCK_RATE_SD, FRICTION_SD, SERVO_FRAME, NoiseConfig, SimConfig

#: SHA-256 of the poses of ``dense_scene(seed=3)``, 7 robots, alpha_max 90 deg, 10 periods, default settings,
#: computed on the code before the noise existed (recomputed, noise code unchanged, when the default servo speed
#: became the authors' pi rad per 0.4 s).
#: With the noise off the trajectories must not change by a
#: bit; if this fails after a PyBullet or NumPy upgrade, recompute it on the commit before the noise.
PRE_NOISE_POSES_SHA256 = 'd10e386e914a60755e3d2c353234aebcf79548a784a54c1396ab4aab27a58daa'


def poses_hash(config: SimConfig, periods: float = 10.0, seed: int = 3) -> str:
    """SHA-256 of the recorded poses of a 7-robot dense trial."""
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    rec = run_trial(config, dense_scene(config.robot, gait, 7, seed=seed), periods)
    return hashlib.sha256(rec.poses.tobytes()).hexdigest()


def apart(gait: GaitConfig, n: int = 2) -> Scene:
    """``n`` robots 12 cm apart on a line (they never touch), all with ``gait``, scene seed 4."""
    a = gait.alpha_max
    return Scene(tuple(RobotPlacement(-0.12 + 0.12 * k, 0.0, math.pi / 2, a, a, gait) for k in range(n)),
                 name='apart', seed=4)


class SendLog:
    """Wraps ``physics.send``: every servo command as (time, robot, targets)."""

    def __init__(self, physics: Physics) -> None:
        self.sends: list[tuple[float, int, tuple[float, float]]] = []
        self._send = physics.send
        self._physics = physics
        physics.send = self  # type: ignore[method-assign]

    def __call__(self, k: int, targets: tuple[float, float], speed: float) -> None:
        self.sends.append((self._physics.time, k, targets))
        self._send(k, targets, speed)

    def times(self, robot: int) -> np.ndarray:
        """Send times of ``robot``'s commands."""
        return np.array([t for t, k, _ in self.sends if k == robot])


# ------------------------------------------------------------------------------------------- settings
@pytest.mark.parametrize('field, value', [
    ('clock_rate_sd', -0.001), ('clock_rate_sd', math.nan), ('clock_rate_sd', 0.2),
    ('servo_jitter', -0.01), ('servo_jitter', math.inf), ('servo_jitter', 0.5),
    ('friction_sd', -0.05), ('friction_sd', math.nan), ('friction_sd', 0.3),
    ('friction_length', 0.0), ('friction_length', -0.05), ('friction_tolerance', -1e-3),
    ('seed', -1), ('seed', True), ('seed', 1.5)])
def test_bad_noise_values_refused_with_the_field_named(field: str, value: float) -> None:
    with pytest.raises(ConfigError, match=f'NoiseConfig.{field}'):
        NoiseConfig(**{field: value})


def test_friction_sd_that_could_make_friction_negative_is_refused() -> None:
    """Refused above 0.2: the field is clipped at 4 sd, so the friction factor stays >= 0.2."""
    with pytest.raises(ConfigError, match='friction_sd.*positive'):
        NoiseConfig(friction_sd=0.25)
    field = FrictionField(0.2, 0.05, 0.6, seed=0)
    assert field.grid.min() >= -4.0 and field.grid.max() <= 4.0
    assert field.factor(np.zeros((1, 2)))[0] > 0.0


def test_presets_and_the_default_is_off() -> None:
    assert SimConfig().noise == NoiseConfig.none() and not SimConfig().noise.enabled
    paper = NoiseConfig.paper()
    assert paper == NoiseConfig() and paper.enabled
    assert paper.clock_rate_sd == pytest.approx(0.005 / math.sqrt(3)) == CLOCK_RATE_SD
    assert paper.servo_jitter == SERVO_FRAME == 0.020 and paper.friction_sd == FRICTION_SD
    assert SimConfig().with_noise().noise == paper
    assert SimConfig().with_noise(servo_jitter=0.0).noise.servo_jitter == 0.0
    assert NoiseConfig(seed=None).trial_seed(7) == 7 and NoiseConfig(seed=2).trial_seed(7) == 2
    assert NoiseConfig().trial_seed(None) == 0


def test_jitter_longer_than_a_quarter_is_refused(config: SimConfig) -> None:
    gait = GaitConfig.from_degrees(15.0, period=0.3)   # quarter 0.075 s
    with Physics(config.with_noise(servo_jitter=0.08), apart(gait, 1)) as physics:
        with pytest.raises(ConfigError, match='servo_jitter'):
            GaitController.for_scene(physics)


def test_cli_noise_options() -> None:
    parser = build_parser()
    assert noise_from_args(parser.parse_args(['run'])) == NoiseConfig.none()
    assert noise_from_args(parser.parse_args(['run', '--noise', 'paper'])) == NoiseConfig.paper()
    noise = noise_from_args(parser.parse_args(['run', '--noise', 'paper', '--friction-sd', '0',
                                               '--clock-rate-sd', '0.01', '--noise-seed', '9']))
    assert (noise.friction_sd, noise.clock_rate_sd, noise.servo_jitter, noise.seed) == (0.0, 0.01, 0.02, 9)
    assert noise_from_args(parser.parse_args(['phase-drift'])) == NoiseConfig.paper()


# ------------------------------------------------------------------------------- zero noise, seeds
def test_zero_noise_is_the_pre_noise_trajectory_bit_for_bit(config: SimConfig) -> None:
    # the hash was taken before noise existed, at the default of then (1/480 s, 10 solver iterations,
    # contact ERP 0.6 with restitution 0.85, roll / pitch inertia x100)
    config = config.with_physics(time_step=1.0 / 480.0, solver_iterations=10, contact_erp=0.6, restitution=0.85,
                                 tilt_inertia_scale=100.0)
    assert poses_hash(config) == PRE_NOISE_POSES_SHA256
    zeros = NoiseConfig(clock_rate_sd=0.0, servo_jitter=0.0, friction_sd=0.0, friction_length=0.3, seed=11)
    assert poses_hash(config.with_noise(zeros)) == PRE_NOISE_POSES_SHA256


def test_same_seed_same_trajectory_other_seed_other(config: SimConfig, gait90: GaitConfig) -> None:
    scene = dense_scene(config.robot, gait90, 7, seed=2)

    def poses(noise_seed: int | None) -> np.ndarray:
        return run_trial(config.with_noise(seed=noise_seed), scene, 4).poses

    first = poses(None)   # the scene's seed, 2
    assert np.array_equal(first, poses(None))
    assert np.array_equal(first, poses(2))
    other = poses(3)
    assert np.array_equal(first[0], other[0])   # the noise draws never move the scene's robots
    assert not np.array_equal(first, other)
    assert not np.array_equal(first, run_trial(config, scene, 4).poses)


def test_each_source_has_its_own_stream() -> None:
    """Switching one source on or off does not change another's draws; robots draw from their own streams."""
    a = clock_rates(NoiseConfig(), 7, seed=5)
    b = clock_rates(NoiseConfig(servo_jitter=0.0, friction_sd=0.0), 7, seed=5)
    assert np.array_equal(a, b) and not np.array_equal(a, clock_rates(NoiseConfig(), 7, seed=6))
    assert np.all(np.abs(a) <= 4 * CLOCK_RATE_SD)
    assert not np.any(clock_rates(NoiseConfig.none(), 7, seed=5))
    one, other = ServoDelays(0.02, 2, seed=5), ServoDelays(0.02, 2, seed=5)
    first = [one.draw(0) for _ in range(3)]
    other.draw(1)
    assert [other.draw(0) for _ in range(3)] == first


# ----------------------------------------------------------------------------------------- clocks
def test_fast_clock_gets_a_quarter_period_ahead_in_50_periods(config: SimConfig, gait90: GaitConfig) -> None:
    """eps = +0.5 %: after 50 periods of sim time its gait is at 50.25 periods, one quarter ahead."""
    eps = 0.005
    T = gait90.period
    with Physics(config, apart(gait90)) as physics:
        gaits = GaitController(physics, [gait90, gait90], clock_rates=[eps, 0.0])
        log = SendLog(physics)
        runner = Runner(physics, [gaits])
        gaits.start(0.0)
        runner.run(runner.ticks_for(50 * T))
        now = physics.time
        assert now == pytest.approx(50 * T)
        fast, steady = gaits.gait(0), gaits.gait(1)
        assert fast.gait_time(gaits.local_time(0, now)) == pytest.approx(50.25, abs=1e-9)
        assert steady.gait_time(gaits.local_time(1, now)) == pytest.approx(50.0, abs=1e-9)
        assert fast.command(gaits.local_time(0, now) + 1e-6).quarter == 1   # 201 quarters done
        sent_fast, sent_steady = log.times(0), log.times(1)
        # the start plus one command per quarter boundary passed: 201 + 1 against 200 + 1
        assert len(sent_fast) - len(sent_steady) == 1
        # quarter q ends at q T / 4 / (1 + eps) of sim time; its command goes at the first tick from then
        q = np.arange(len(sent_fast))
        boundary = q * T / 4 / (1 + eps)
        tick = physics.control_tick
        assert np.all(sent_fast >= boundary - 1e-9) and np.all(sent_fast < boundary + tick)


# ------------------------------------------------------------------------------------ servo jitter
def test_servo_jitter_delays_each_quarter_command_within_the_frame(config: SimConfig,
                                                                  gait90: GaitConfig) -> None:
    jitter = 0.02
    seed = 4
    T = gait90.period
    with Physics(config.with_noise(NoiseConfig.none(), servo_jitter=jitter), apart(gait90)) as physics:
        gaits = GaitController.for_scene(physics)
        log = SendLog(physics)
        runner = Runner(physics, [gaits])
        gaits.start(0.0)
        runner.run(runner.ticks_for(10 * T))
        tick = physics.control_tick
        draws = ServoDelays(jitter, 2, seed)   # the same streams as the controller's (scene seed 4)
        for k in range(2):
            sent = log.times(k)
            boundary = np.arange(len(sent)) * T / 4
            delay = np.array([draws.draw(k) for _ in sent])
            late = sent - boundary
            assert np.all(late >= -1e-9) and np.all(late < jitter + tick)
            # sent at the first tick at or after boundary + its own drawn delay
            assert np.all(sent >= boundary + delay - 1e-9) and np.all(sent < boundary + delay + tick)
            assert delay.max() > jitter / 2 and delay.min() < jitter / 2   # really spread over the frame
        assert len(log.times(0)) == 40   # the start and one per quarter boundary before 10 T


def test_a_halt_drops_a_command_still_waiting(config: SimConfig, gait90: GaitConfig) -> None:
    cfg = config.with_noise(NoiseConfig.none(), servo_jitter=0.019)
    with Physics(cfg, apart(gait90, 1)) as physics:
        gaits = GaitController.for_scene(physics)
        runner = Runner(physics, [gaits])
        gaits.start(0.0)
        runner.tick()    # the start command is drawn a delay and waits for its frame
        assert gaits.pending(0) is not None and gaits.pending(0) > physics.time - physics.control_tick
        log = SendLog(physics)
        assert gaits.halt(0)
        assert gaits.pending(0) is None
        runner.run(runner.ticks_for(0.5))   # before the next period, when the gait resumes
        assert [k for _, k, _ in log.sends] == [0]   # only the hold
        hold = log.sends[0][2]
        assert np.allclose(physics.arm_angles()[0], hold, atol=0.05)


# --------------------------------------------------------------------------------------- friction
def test_bullet_body_friction_follows_the_field(config: SimConfig, gait90: GaitConfig) -> None:
    noise = NoiseConfig(clock_rate_sd=0.0, servo_jitter=0.0, friction_sd=0.1, friction_length=0.03)
    cfg = config.with_noise(noise)
    mu = cfg.physics.friction_body_plate
    arm_link = cfg.physics.link_frictions()[0]
    with Runner.with_gaits(cfg, dense_scene(cfg.robot, gait90, 7, seed=1)) as runner:
        physics = runner.physics
        field = physics.friction_field
        assert field is not None
        runner.gaits.start(0.0)  # type: ignore[union-attr]
        for _ in range(3):
            runner.run(runner.ticks_for(gait90.period))
            physics.update_plate_friction()
            expected = mu * field.factor(physics.body_xy())
            reported = np.array([physics.plate_friction(k) for k in range(physics.n_robots)])
            assert np.all(np.abs(reported - expected) <= noise.friction_tolerance * mu + 1e-9)
        assert np.ptp(reported) > 5 * noise.friction_tolerance * mu    # the robots feel different plates
        client = physics.client
        for body in physics.body_ids:   # arm links untouched
            assert all(client.getDynamicsInfo(body, j)[1] == pytest.approx(arm_link) for j in ARM_JOINTS)
    with Physics(config, dense_scene(config.robot, gait90, 7, seed=1)) as plain:
        assert plain.friction_field is None
        assert all(plain.plate_friction(k) == pytest.approx(mu) for k in range(7))


def test_friction_updates_only_past_the_tolerance(config: SimConfig, gait90: GaitConfig) -> None:
    cfg = config.with_noise(NoiseConfig.none(), friction_sd=0.06)
    with Physics(cfg, apart(gait90)) as physics:
        assert physics.update_plate_friction() == 0    # set at construction; nothing moved
        assert physics.friction_field is not None


@pytest.mark.parametrize('length', [0.03, 0.08])
def test_friction_field_statistics_match_the_config(length: float) -> None:
    """Over 32 seeded 1.2 m plates: sd = friction_sd, correlation exp(-1/2) at one length, ~0 at three."""
    sd = 0.06
    h = length / 4.0
    axis = np.arange(-0.6, 0.6 + 1e-12, h)
    xx, yy = np.meshgrid(axis, axis, indexing='ij')
    points = np.column_stack([xx.ravel(), yy.ravel()])
    var, lag1, lag3 = [], [], []
    for seed in range(32):
        z = (FrictionField(sd, length, 1.2, seed).factor(points).reshape(xx.shape) - 1.0) / sd
        var.append(float(np.mean(z * z)))      # about the known mean 1: unbiased
        lag1.append(float(np.mean(z[:-4] * z[4:]) + np.mean(z[:, :-4] * z[:, 4:])) / 2)
        lag3.append(float(np.mean(z[:-12] * z[12:]) + np.mean(z[:, :-12] * z[:, 12:])) / 2)
    assert sd * math.sqrt(np.mean(var)) == pytest.approx(sd, rel=0.08)
    assert np.mean(lag1) / np.mean(var) == pytest.approx(math.exp(-0.5), abs=0.06)
    assert abs(np.mean(lag3)) < 0.08    # exp(-4.5) = 0.01


def test_short_friction_length_for_the_plate_is_refused() -> None:
    with pytest.raises(ConfigError, match='friction_length'):
        FrictionField(0.06, 0.001, 0.6, seed=0)


def test_sim_bridge_applies_the_friction_field() -> None:
    core = SimBridgeCore(BridgeSettings.defaults(friction_sd=0.06, robots=3))
    try:
        assert core.physics.friction_field is not None
        assert core.settings.sim.noise.clock_rate_sd == 0.0 and core.settings.sim.noise.servo_jitter == 0.0
    finally:
        core.close()
    plain = SimBridgeCore(BridgeSettings.defaults(robots=3))
    try:
        assert plain.physics.friction_field is None
    finally:
        plain.close()


# --------------------------------------------------------------------------------------- drift study
def test_phase_drift_study_follows_the_clock_rates(config: SimConfig, gait90: GaitConfig) -> None:
    cfg = config.with_noise(NoiseConfig.none(), clock_rate_sd=0.01)
    study = phase_drift(cfg, dense_scene(config.robot, gait90, 7, seed=1), 12)
    spread, expected = study.spread(), study.expected_spread()
    assert spread[0] < 0.02                                   # in phase at the start
    assert spread[-1] == pytest.approx(expected[-1], rel=0.2)  # apart as the clocks say
    assert expected[-1] > 5 * spread[0]
