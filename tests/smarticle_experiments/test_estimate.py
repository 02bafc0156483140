"""The run-time estimate of ``list`` and ``run``: the cost model of docs/experiments.md, applied to specs."""

from __future__ import annotations

import pytest
from smarticle_common.facts import GAIT_PERIOD
from smarticle_experiments.estimate import (BULLET_SPEED, MUJOCO_SPEED, duration_text, run_seconds,
                                            trial_cpu_seconds)
from smarticle_experiments.spec import load_spec, spec_from_mapping
from smarticle_experiments.kinds import KINDS


def test_a_trial_costs_robot_seconds_over_the_engines_speed() -> None:
    dense = {**KINDS['dense'].defaults, 'robots': 7, 'periods': 300.0}
    assert trial_cpu_seconds('dense', dense) == pytest.approx(7 * 300 * GAIT_PERIOD / BULLET_SPEED)
    pair = dict(KINDS['pair'].defaults)
    assert trial_cpu_seconds('pair', pair) == pytest.approx(2 * 75 * GAIT_PERIOD / BULLET_SPEED)
    mujoco = dict(KINDS['pair_mujoco'].defaults)
    assert trial_cpu_seconds('pair_mujoco', mujoco) == pytest.approx(2 * 75 * GAIT_PERIOD / MUJOCO_SPEED)


def test_a_finer_step_costs_in_proportion_and_unknown_engines_have_no_estimate() -> None:
    pair = dict(KINDS['pair'].defaults)
    base = trial_cpu_seconds('pair', pair)
    assert base is not None
    assert trial_cpu_seconds('pair', {**pair, 'physics': {'time_step': 1 / 1920}}) == pytest.approx(2 * base)
    assert trial_cpu_seconds('pair_chrono', dict(KINDS['pair_chrono'].defaults)) is None
    assert trial_cpu_seconds('my_module:my_trial', {}) is None


def test_a_specs_run_time_shares_its_trials_over_the_cores() -> None:
    p1 = load_spec('p1')
    one = trial_cpu_seconds(p1.kind, p1.base)
    assert one is not None
    assert run_seconds(p1, cores=2) == pytest.approx(151 * one / 2)
    assert run_seconds(p1, cores=2, trials=0) == 0.0
    assert run_seconds(p1, cores=300) == pytest.approx(one)   # never less than one trial
    tiny = spec_from_mapping({'name': 'mine', 'kind': 'pair_chrono', 'seeds': 1})
    assert run_seconds(tiny) is None and duration_text(None) == 'unknown'


@pytest.mark.parametrize(('seconds', 'text'), [(0.2, '1 s'), (40, '40 s'), (720, '12 min'), (4680, '1.3 h'),
                                               (3 * 86400, '3.0 days')])
def test_durations_read_as_people_say_them(seconds: float, text: str) -> None:
    assert duration_text(seconds) == text
