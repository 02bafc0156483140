"""The lock-step ROS path with feedback is deterministic and equals the batch path, bit for bit.

sim_bridge (lock-step, an FSR sample every control tick), one gait node (lockstep, wait_for_feedback) and
one feedback node (lockstep) per robot, each a separate process over DDS (the sim_world fixture), on a C2
start of the P6 experiment: a halt is part of the tick of its FSR sample, so two runs give the same poses at every
stamp, and those are the poses of the batch path (Runner + FeedbackController + GaitController).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig
from smarticle_experiments.p6 import COLLIDING_START, c2_scene, default_feedback_config
from smarticle_feedback.controller import ImpactController
from smarticle_sim.bridge import BridgeSettings
from smarticle_sim.config_builder import build_config
from smarticle_sim.physics import Physics
from smarticle_sim.runner import FeedbackController, GaitController, Runner
from smarticle_sim.settings import SimConfig
from smarticle_sim.testing import FEEDBACK, SimWorld

pytestmark = pytest.mark.integration

START_AT = 0.5
SEED = 0
PERIODS = 1.5


def _start() -> tuple[SimConfig, dict[str, Any]]:
    """The feedback robot's config and the sim bridge parameters of seed SEED's C2 start."""
    config = build_config('feedback')
    gait = GaitConfig.from_degrees(90.0, servo_speed=config.robot.servo_speed)
    _, (r, theta, phi) = c2_scene(config, gait, SEED, COLLIDING_START)   # collides at once: halts early
    phases = COLLIDING_START[3]
    return config, {'preset': 'feedback', 'scene': 'pair', 'pair_r': r, 'pair_theta_deg': theta,
                    'pair_phi_deg': phi, 'pair_phase_0': phases[0], 'pair_phase_1': phases[1],
                    'alpha_max_deg': 90.0, 'publish_period': config.physics.control_tick,
                    'start_at': START_AT}


def _batch(config: SimConfig, params: dict[str, Any], ticks: int,
           clock_offsets: tuple[float, float] = (0.0, 0.0)) -> tuple[dict[int, np.ndarray], list[tuple]]:
    """Poses by stamp (ns) and halts (stamp ns, robot, face) of the batch path over ``ticks`` ticks.

    ``clock_offsets``: each robot's gait clock rate - 1 (the noise model's clock-rate draws, given here).
    """
    settings = BridgeSettings.defaults(**params)
    scene = settings.scene()
    physics = Physics(settings.sim, scene)
    gaits = GaitController(physics, [r.gait for r in scene.robots], clock_rates=clock_offsets)
    runner = Runner(physics, [gaits])
    runner.gaits = gaits
    runner.gaits.start(START_AT)
    feedback = default_feedback_config()
    policies = {k: ImpactController(replace(feedback, period=settings.gait.period, phase=p))
                for k, p in enumerate(COLLIDING_START[3])}
    for policy in policies.values():
        policy.start(START_AT)
    controller = FeedbackController(runner.gaits, policies)
    runner.controllers.insert(0, controller)
    poses: dict[int, np.ndarray] = {}
    try:
        for _ in range(ticks + 1):
            poses[round(runner.time * 1e9)] = runner.physics.poses()[:, :2].copy()
            runner.run(1)
    finally:
        runner.close()
    return poses, [(round(t * 1e9), k, face) for t, k, face in controller.halts]


def _ros(world: SimWorld, params: dict[str, Any], config: SimConfig, duration: float,
         clock_offsets: tuple[float, float] = (0.0, 0.0)) -> tuple[dict[int, np.ndarray], list[tuple]]:
    """Poses by stamp (ns) and halts (stamp ns, robot, face) of the lock-step ROS path (sim_world fixture)."""
    phases = COLLIDING_START[3]
    bridge = {k: v for k, v in params.items() if k not in ('scene', 'preset')}
    world.start(scene='pair', preset='feedback', params=bridge,
                controller_params=[{'alpha_max_deg': 90.0, 'servo_speed': config.robot.servo_speed,
                                    'phase': phases[k], 'start_at': START_AT, 'clock_rate_offset': clock_offsets[k]}
                                   for k in range(2)],
                feedback=FEEDBACK,
                feedback_params=[{'phase': phases[k], 'start_at': START_AT, 'clock_rate_offset': clock_offsets[k]}
                                 for k in range(2)])
    world.step_to(duration)
    return {stamp: p[:, :2] for stamp, p in world.data.poses.items()}, world.halts


#: Clock-rate offsets of the two robots' boards for the noisy case: about 1.5 and 1 sd of the cited
#: resonator spread (settings.CLOCK_RATE_SD, 0.29 %), apart by 0.7 %.
CLOCK_OFFSETS = (0.0043, -0.0029)


@pytest.mark.parametrize('clock_offsets, repeats', [((0.0, 0.0), 2), (CLOCK_OFFSETS, 1)],
                         ids=['same-clocks', 'clock-noise'])
def test_lockstep_feedback_is_deterministic_and_equals_the_batch_path(tmp_path: Path,
                                                                      clock_offsets: tuple[float, float],
                                                                      repeats: int) -> None:
    """Two runs agree bit for bit with the batch path; with clock-rate noise the gait and feedback nodes
    take each robot's offset (clock_rate_offset) as the batch path's gait controller does."""
    config, params = _start()
    duration = START_AT + PERIODS * 1.6
    ticks = round(duration / config.physics.control_tick)
    batch, batch_halts = _batch(config, params, ticks, clock_offsets)
    assert batch_halts, 'the C2 start must produce a halt in the batch path (else the test shows nothing)'
    if clock_offsets != (0.0, 0.0):
        same_clocks = _batch(config, params, ticks)[0]
        stamp = max(batch)
        assert not np.array_equal(batch[stamp], same_clocks[stamp]), 'the clock offsets must change the run'
    runs = []
    for i in range(repeats):
        with SimWorld(tmp_path / f'run{i}') as world:
            runs.append(_ros(world, params, config, duration, clock_offsets))
    for poses, halts in runs:
        assert halts == batch_halts
        common = sorted(set(poses) & set(batch))
        assert len(common) >= 0.8 * ticks, f'only {len(common)} of {ticks} pose messages arrived'
        for stamp in common:
            assert np.array_equal(poses[stamp], batch[stamp]), \
                f'differs from the batch path at t = {stamp * 1e-9:.4f} s by ' \
                f'{np.abs(poses[stamp] - batch[stamp]).max():.3g} m'
