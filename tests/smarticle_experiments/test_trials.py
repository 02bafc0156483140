"""Each built-in trial kind runs a tiny trial and returns its documented fields (guards the imports of the
other packages, which live in trials.py only); the isolation rule of gliders."""

from __future__ import annotations

import json

import pytest

from smarticle_experiments.spec import apply_point
from smarticle_experiments.kinds import KINDS, run_kind


def params(kind: str, **changes: object) -> dict:
    """The kind's defaults with changes."""
    return apply_point(dict(KINDS[kind].defaults), changes)


@pytest.mark.parametrize(('kind', 'changes', 'fields'), [
    ('dense', {'robots': 3, 'periods': 2.0, 'min_periods': 1}, {'gliders', 'positive', 'positive_isolated',
                                                                 'trajectory_bl', 'trouble', 'periods_run'}),
    ('pair', {'periods': 2.0, 'min_periods': 1}, {'admissible', 'bound_at_end', 'bound_tail_periods', 'r_end_bl',
                                                 'colliding_at_end', 'colliding_tail_periods',
                                                 'out_of_reach_at_end', 'gliders', 'trouble'}),
    ('single', {'periods': 2.0}, {'drift_um_per_cycle', 'trouble', 'cycles'}),
    ('pair_mujoco', {'periods': 1.0, 'min_periods': 1}, {'admissible', 'bound_at_end', 'r_end_bl', 'gliders',
                                                        'colliding_tail_periods', 'trouble'}),
    ('single_mujoco', {'periods': 1.0}, {'drift_um_per_cycle', 'trouble', 'cycles'}),
    ('p6', {'periods': 2.0, 'feedback': True}, {'lifetime_periods', 'censored', 'halts', 'trouble'}),
    ('p6', {'periods': 2.0, 'start': 'held'}, {'lifetime_periods', 'censored', 'r0_bl', 'trouble'}),
    ('accuracy', {'periods': 2.0, 'single_periods': 2.0}, {'wall_per_sim_s', 'r_mean_bl', 'drift_um_per_cycle',
                                                          'xy1_bl', 'trouble'}),
])
def test_every_kind_runs_a_tiny_trial(kind: str, changes: dict, fields: set[str]) -> None:
    result = run_kind(kind, params(kind, **changes), 1)
    assert fields <= set(result)
    assert result['trouble'] == ''
    json.dumps(result, allow_nan=True)   # JSON-ready (NaN becomes null in the store)


def test_a_pair_start_that_overlaps_is_inadmissible_not_an_error() -> None:
    result = run_kind('pair', params('pair', r_bl=0.3, periods=2.0), 0)
    assert result['admissible'] is False and 'overlap' in result['why']


def test_the_seed_jitters_the_pair_start_only_when_asked() -> None:
    from smarticle_experiments.trials import pair_start

    p = params('pair')
    assert pair_start(p, 1) == pair_start(p, 2) == (1.3, 0.0, 180.0)
    jittered = params('pair', start_jitter=[0.04, 4.0, 4.0])
    a, b = pair_start(jittered, 1), pair_start(jittered, 2)
    assert a != b and a == pair_start(jittered, 1)
    assert abs(a[0] - 1.3) <= 0.04 and abs(a[1]) <= 4.0 and abs(a[2] - 180.0) <= 4.0


def test_a_dense_trial_reports_isolation_from_the_glider_analysis() -> None:
    result = run_kind('dense', params('dense', robots=3, periods=4.0, min_periods=1), 2)
    for g in result['gliders']:
        assert 0.0 <= g['isolation'] <= 1.0
        assert g['isolated'] == (g['isolation'] >= 0.9)


def test_a_dense_trial_says_how_close_it_came_to_the_trouble_limits() -> None:
    """The largest tilt and deepest overlap at the trouble checks: small, positive, inside the limits."""
    result = run_kind('dense', params('dense', robots=3, periods=4.0, min_periods=1), 2)
    assert result['trouble'] == ''
    assert 0.0 <= result['peak_tilt_deg'] < 25.0
    assert 0.0 < result['peak_overlap_mm'] < 4.0   # the bodies rest on the plate: a small overlap, never none


def test_a_trial_with_noise_differs_and_repeats() -> None:
    """The spec's noise reaches the physics: seeded, so the same seed repeats, and it moves the robots."""
    base = params('dense', robots=3, periods=3.0, min_periods=1)
    noisy = {**base, 'noise': {'clock_rate_sd': 0.01, 'servo_jitter': 0.02, 'friction_sd': 0.1}}
    quiet = run_kind('dense', base, 4)
    first, again = run_kind('dense', noisy, 4), run_kind('dense', noisy, 4)
    assert first['trajectory_bl'] == again['trajectory_bl']
    assert first['trajectory_bl'] != quiet['trajectory_bl']
    assert first['trajectory_bl'][0] == quiet['trajectory_bl'][0]   # the same start: noise has its own streams


def test_a_dense_trial_can_say_how_often_its_gliders_touch() -> None:
    """``contacts: true`` watches every physics step: each glider gets the share of its periods with contact."""
    p = params('dense', robots=3, periods=4.0, min_periods=1)
    plain = run_kind('dense', p, 2)
    watched = run_kind('dense', {**p, 'contacts': True}, 2)
    assert watched['trajectory_bl'] == plain['trajectory_bl']          # watching does not change the run
    assert watched['gliders'], 'seed 2 binds a pair of 3 dense robots'
    for g in watched['gliders']:
        assert 0.0 <= g['contact_fraction'] <= 1.0
    assert max(g['contact_fraction'] for g in watched['gliders']) == 1.0   # packed robots touch every period
    assert all('contact_fraction' not in g for g in plain['gliders'])


def test_contact_fractions_count_the_glider_span_only() -> None:
    from smarticle_experiments.trials import add_contact_fractions

    gliders = [{'i': 2, 'j': 0, 'start_period': 10, 'lifetime_periods': 4}]
    add_contact_fractions(gliders, {(0, 2): {9, 10, 12, 14}})
    assert gliders[0]['contact_fraction'] == 0.5                         # periods 10 and 12 of 10-13


def test_a_pair_trials_noise_follows_its_seed() -> None:
    """The pair scene carries the trial seed, so two seeds of the same (unjittered) start draw different noise."""
    p = {**params('pair', periods=3.0, min_periods=1), 'noise': {'clock_rate_sd': 0.01}}
    one, other = run_kind('pair', p, 1), run_kind('pair', p, 2)
    assert one['trajectory_bl'][0] == other['trajectory_bl'][0]       # the same start
    assert one['trajectory_bl'] != other['trajectory_bl']             # different clocks


def test_a_p6_trial_takes_the_specs_robot_and_physics_changes() -> None:
    """A ``p6`` spec may change the feedback robot (``robot.servo_torque``) or its physics: they reach the pair."""
    from smarticle_experiments.spec import spec_from_mapping

    spec = spec_from_mapping({'name': 'p6z', 'description': 'synthetic', 'kind': 'p6', 'periods': 3, 'seeds': 1,
                              'grid': [{'feedback': [False], 'robot.servo_torque': [0.3, 0.9]}], 'report': ['p6']})
    assert len(spec.points()) == 2
    base = params('p6', periods=3.0, start='held')
    plain = run_kind('p6', base, 1)
    heavy = run_kind('p6', {**base, 'robot': {'arm_mass': 0.03}}, 1)
    again = run_kind('p6', {**base, 'robot': {'arm_mass': 0.03}}, 1)
    finer = run_kind('p6', {**base, 'physics': {'time_step': 1.0 / 1920.0}}, 1)
    assert heavy == again
    assert heavy['final_r_bl'] != plain['final_r_bl'] and finer['final_r_bl'] != plain['final_r_bl']
