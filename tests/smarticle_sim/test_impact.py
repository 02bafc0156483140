"""The impact probe: the restitution Bullet gives two robot bodies meeting head on (docs/sim_calibration.md)."""

from __future__ import annotations

import pytest

from smarticle_sim.impact import impact, impact_sweep, summary
from smarticle_sim.settings import NotConvergedWarning, SimConfig


def test_the_contact_erp_adds_to_the_bounce_by_where_in_the_step_the_bodies_meet(config: SimConfig) -> None:
    """At the previous default (ERP 0.6, restitution 0.85) impacts rebound with 0.85 to ~1.4 of the approach."""
    config = config.with_physics(contact_erp=0.6, restitution=0.85)
    default = summary(impact_sweep(config.physics, config.robot, speed=0.3, phases=8))
    assert default['min'] == pytest.approx(0.85, abs=0.02)       # meeting at a step boundary: the bounce alone
    assert default['mean'] > 1.05 and default['max'] > 1.3         # inside a step: the push-out adds to it
    assert default['overlap_max'] == pytest.approx(0.3 * config.physics.time_step, rel=0.1)   # one step's travel
    finer = summary(impact_sweep(config.with_physics(time_step=1 / 1920).physics, config.robot, 0.3, phases=8))
    assert finer['mean'] == pytest.approx(default['mean'], abs=0.02)   # the same at half the step


def test_the_default_gives_the_authors_restitution(config: SimConfig) -> None:
    """ERP 0.1 with restitution 0.80 (the default): impacts rebound with 0.85 on average, 0.79-0.89."""
    stats = summary(impact_sweep(config.physics, config.robot, speed=0.3, phases=8))
    assert stats['mean'] == pytest.approx(0.85, abs=0.02) and stats['max'] - stats['min'] < 0.12
    none = config.with_physics(restitution=0.0, contact_erp=0.01).physics
    assert impact(none, config.robot, speed=0.3).restitution < 0.05   # inelastic when nothing bounces


def test_impact_refuses_a_speed_or_gap_that_is_no_impact(config: SimConfig) -> None:
    for speed, gap in ((0.0, 0.001), (0.3, -0.001)):
        with pytest.raises(ValueError, match='speed must be > 0 and gap >= 0'):
            impact(config.physics, config.robot, speed, gap)
    with pytest.raises(ValueError, match='phases'):
        impact_sweep(config.physics, config.robot, phases=0)


def test_soft_contacts_lose_their_rebound_to_the_integrator_unless_the_step_is_fine(config: SimConfig) -> None:
    """An undamped contact spring (restitution 1) rebounds with 0.92 at 1/12000 s and with less than half at 1/960 s."""
    with pytest.warns(NotConvergedWarning):
        coarse = config.with_physics(contact_stiffness=2000.0, restitution=1.0)
    fine = config.with_physics(contact_stiffness=2000.0, restitution=1.0, time_step=1 / 12000)
    at_fine = summary(impact_sweep(fine.physics, config.robot, speed=0.3, phases=4))
    assert at_fine['mean'] == pytest.approx(0.92, abs=0.02) and at_fine['max'] - at_fine['min'] < 0.01
    assert summary(impact_sweep(coarse.physics, config.robot, speed=0.3, phases=4))['max'] < 0.55
