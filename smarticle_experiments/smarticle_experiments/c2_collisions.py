"""The collisions of a C2 cycle, measured: record a C2 pair step by step and list every contact event.

``record_pair`` runs a P6 start (``p6.C2_START`` by default, seeded like ``p6.run_pair_trial``, with the
same noise) open loop and records, at every physics step, both robots' FSR forces, which links touch and
r; ``smarticle_feedback.collisions`` cuts that into events (gait quarter, links and faces, FSR peaks, dr)
and their signature.
Command line: ``smarticle-experiments c2-collisions --seed 1 --periods 150 --out out/feedback/c2`` (table,
CSV, PNG, npz); ``--start colliding --noise none`` records the start that collides from its first period.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from smarticle_common.gait import GaitConfig
from smarticle_feedback.collisions import CollisionRecord

from .p6 import C2_START, start_scene


def record_pair(seed: int = 0, periods: float = 40.0, alpha_max_deg: float = 90.0, preset: str = 'feedback',
                base: tuple[float, float, float, tuple[float, float]] | str = C2_START,
                noise: Any = None) -> CollisionRecord:
    """Run the seed's C2 start open loop for ``periods`` and record every physics step.

    ``base``: pair coordinates and phases (``p6.STARTS``) or ``p6.HELD`` (the seed's held-C2 state).
    ``noise``: a ``NoiseConfig`` (None: off), its draws from ``seed`` unless it names its own, as in P6.
    """
    from smarticle_common.pairs import pair_coordinates
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.physics import FsrReading, Physics
    from smarticle_sim.runner import Runner

    config = build_config(preset, noise=noise)   # the pair scene carries the trial seed its draws take
    gait = GaitConfig.from_degrees(alpha_max_deg, servo_speed=config.robot.servo_speed)
    scene, _, phases = start_scene(config, gait, seed, base)
    times: list[float] = []
    fsr: list[np.ndarray] = []
    links: list[np.ndarray] = []
    poses: list[np.ndarray] = []

    with Runner.with_gaits(config, scene) as runner:
        reading = FsrReading(runner.physics)

        def on_step(run: Runner) -> None:
            ph = run.physics
            assert isinstance(ph, Physics)   # Bullet's link contacts: the world Runner.with_gaits builds by default
            times.append(ph.time)
            fsr.append(reading.step())   # what the feedback policy's FSR sample is made of
            links.append(ph.link_contacts(0, 1))
            poses.append(ph.poses().copy())

        runner.step_hooks.append(on_step)
        assert runner.gaits is not None
        runner.gaits.start(0.0)
        runner.run(runner.ticks_for(periods * gait.period))
        rates = runner.gaits.clock_rates
    coords = pair_coordinates(np.asarray(poses))
    return CollisionRecord(np.asarray(times), np.asarray(fsr), np.asarray(links),
                           coords.r[:, 0] / config.robot.body_length, gait.period,
                           (float(phases[0]), float(phases[1])), clock_rates=(float(rates[0]), float(rates[1])))
