"""The restitution Bullet really gives: a head-on impact of two robot bodies, measured (docs/sim_calibration.md).

Bullet's multibody solver resolves a contact with one velocity target per step: the restitution bounce
(``restitution`` x the approach speed) *plus* the contact ERP's push-out of the overlap found at that step
(``contact_erp`` x overlap / step; split impulse does not exist in the multibody solver). An impact is found
after the bodies have moved into each other by up to one step's travel, so the push-out adds up to
a good part of ``contact_erp`` x the approach speed to the bounce. Where in the step the bodies meet decides
how much: the effective restitution spreads over about [e, e + 0.8 x contact_erp] (mean about
e + 0.37 x contact_erp) at every step, because the overlap and the push-out both scale with the step.
``impact_sweep`` measures that spread.

The probe: two free boxes of the robot's body size and the robot's whole mass, no gravity, no friction,
one moving at ``speed`` along its length into the other at rest, with the ``PhysicsConfig``'s step,
solver iterations, contact ERP, breaking threshold, restitution and restitution velocity threshold, or its
soft contact (``contact_stiffness``) if set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from smarticle_common.facts import RobotSpec

from smarticle_sim.physics import configure_engine, quiet_client, robot_link_contact
from smarticle_sim.quiet import pybullet
from smarticle_sim.settings import PhysicsConfig


@dataclass(frozen=True)
class Impact:
    """One measured impact."""

    gap: float             # m between the faces at the start
    restitution: float     # separation speed after / approach speed before
    overlap: float         # m, deepest overlap Bullet reported


def impact(physics: PhysicsConfig, spec: RobotSpec, speed: float = 0.3, gap: float = 0.0005) -> Impact:
    """Head-on impact of two robot bodies (``spec``'s body box, its total mass) at ``speed`` (m/s), the
    faces ``gap`` apart at the start; returns the effective restitution and the deepest overlap."""
    if speed <= 0.0 or gap < 0.0:
        raise ValueError(f'impact: speed must be > 0 and gap >= 0, got speed {speed}, gap {gap}')
    c = quiet_client()
    try:
        configure_engine(c, physics, n_robots=2)
        c.setGravity(0.0, 0.0, 0.0)
        half = [spec.body_width / 2.0, spec.body_depth / 2.0, spec.body_height / 2.0]
        shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
        moving = c.createMultiBody(spec.total_mass, shape, basePosition=[0.0, 0.0, 1.0])
        still = c.createMultiBody(spec.total_mass, shape, basePosition=[spec.body_width + gap, 0.0, 1.0])
        contact = robot_link_contact(physics, spec.total_mass)   # as every robot link in a run
        for body in (moving, still):
            c.changeDynamics(body, -1, lateralFriction=0.0, linearDamping=0.0, angularDamping=0.0,
                             activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING, **contact)
        c.resetBaseVelocity(moving, [speed, 0.0, 0.0])
        overlap = 0.0
        steps = math.ceil((gap / speed + 0.03) / physics.time_step)   # the meeting and 30 ms after it
        for _ in range(steps):
            c.stepSimulation()
            for point in c.getContactPoints(moving, still):
                overlap = max(overlap, -point[8])
        v_moving = c.getBaseVelocity(moving)[0][0]
        v_still = c.getBaseVelocity(still)[0][0]
    finally:
        c.disconnect()
    return Impact(gap, (v_still - v_moving) / speed, overlap)


def impact_sweep(physics: PhysicsConfig, spec: RobotSpec, speed: float = 0.3, phases: int = 16,
                 start_gap: float = 0.0005) -> list[Impact]:
    """``phases`` impacts whose start gaps step through one physics step's travel, so that the bodies meet
    at evenly spread points within a step (the meeting phase is what an impact in a run has no control of)."""
    if phases < 1:
        raise ValueError(f'impact_sweep: phases must be >= 1, got {phases}')
    travel = speed * physics.time_step
    return [impact(physics, spec, speed, start_gap + travel * k / phases) for k in range(phases)]


def summary(impacts: list[Impact]) -> dict[str, float]:
    """Mean, standard deviation, min and max of the effective restitution and the deepest overlap (m)."""
    e = np.array([i.restitution for i in impacts])
    return {'mean': float(e.mean()), 'sd': float(e.std(ddof=1)) if len(e) > 1 else 0.0, 'min': float(e.min()),
            'max': float(e.max()), 'overlap_max': max(i.overlap for i in impacts)}
