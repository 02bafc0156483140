"""Calibration guards (docs/sim_calibration.md) under the default settings.

Short and deterministic (40 periods, a few seconds). With robot 2's gait 0.03 period ahead (the
experiments' phase drift) a pair started near the paper's C1 configuration binds, settles 15-18 deg off
anti-alignment and *translates* (1.3-1.6 W in 100 periods from the starts of the calibration note).
"""

from __future__ import annotations

import math

import numpy as np
from smarticle_common.gait import GaitConfig
from smarticle_tracking.gliders import GliderClass, GliderConfig, analyse_gliders

from smarticle_sim.batch import run_trial
from smarticle_common.pairs import one_pair
from smarticle_sim.scenes import pair_scene
from smarticle_sim.settings import SimConfig

PERIODS = 40
#: Measured 0.72 W in 40 periods for this start (0.19 W, mostly the first pushes, with equal phases);
#: the bound asks for under half.
MIN_TRAVEL_W = 0.3


def test_c1_pair_binds_and_glides_under_default_settings(config: SimConfig, gait90: GaitConfig) -> None:
    bl = config.robot.body_length
    scene = pair_scene(config.robot, gait90, 1.3, math.radians(330.0), math.pi, (0.0, 0.03))
    rec = run_trial(config, scene, PERIODS, sample_every=2, record_fsr=False, record_contacts=True)
    assert rec.trouble == ''
    per = round(gait90.period / (config.physics.control_tick * 2))
    touching = rec.contacts[:, 0, 1]
    touched = [bool(touching[q * per:(q + 1) * per].any()) for q in range(PERIODS)]
    assert all(touched), touched                        # touches the other robot in every period
    end_r, _, end_phi = one_pair(rec.poses[-1, 0], rec.poses[-1, 1])
    assert end_r / bl < 1.5                             # held within arm's reach, not pushed apart
    assert 5.0 < abs(math.degrees(end_phi) - 180.0) < 30.0    # near anti-aligned, with the C1 asymmetry
    analysis = analyse_gliders(rec.time, rec.poses,
                               GliderConfig(period=gait90.period, r_bind=1.6 * bl, min_periods=30,
                                            body_length=bl, width=bl),
                               contacts=touching[:, np.newaxis])
    assert len(analysis.gliders) == 1
    glider = analysis.gliders[0]
    assert glider.glider_class is GliderClass.C1
    assert glider.lifetime_periods >= PERIODS and glider.ongoing   # the last sample opens the next period
    com = rec.poses[:, :, :2].mean(axis=1)
    travel = float(np.linalg.norm(com[-1] - com[0])) / bl
    assert travel > MIN_TRAVEL_W, travel
    half = float(np.linalg.norm(com[-1] - com[len(com) // 2])) / bl
    assert half > 0.35 * travel, (half, travel)         # still moving late in the run, not one first push
