"""Typed results: the stored dict leaves unset optional fields out, and a stored dict reads back typed."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from smarticle_experiments.errors import ResultError
from smarticle_experiments.kinds import KINDS, read_result
from smarticle_experiments.results import (DenseResult, GliderRecord, InadmissiblePairResult, P6Result,
                                           PairResult, SingleResult, StudyDenseResult, StudyInadmissibleResult,
                                           StudyPairResult)


def test_optional_fields_are_stored_only_when_set_and_read_back() -> None:
    plain = P6Result(lifetime_periods=12, censored=False, halts=3, trouble='', r0_bl=1.47, theta0_deg=99.0,
                     phi0_deg=7.0, final_r_bl=None)
    stored = plain.as_dict()
    assert 'travel_w' not in stored and 'contact_periods' not in stored
    assert stored['final_r_bl'] is None   # a required field that is None stays (null in the store)
    detailed = P6Result(**{**stored, 'travel_w': 0.4, 'contact_periods': [1, 2]})
    assert detailed.as_dict()['contact_periods'] == [1, 2]
    assert P6Result.from_dict(json.loads(json.dumps(detailed.as_dict()))) == detailed
    assert P6Result.from_dict({**stored, 'unknown_key': 1}) == plain   # keys a reader does not know are ignored


def test_a_stored_result_missing_a_required_field_is_refused() -> None:
    with pytest.raises(TypeError):
        SingleResult.from_dict({'drift_um_per_cycle': 75.0})
    bad = InadmissiblePairResult(r0_bl=0.3, theta0_deg=0.0, phi0_deg=180.0, admissible=False, why='overlap',
                                 trouble='', gliders=[])
    assert bad.as_dict() == {'r0_bl': 0.3, 'theta0_deg': 0.0, 'phi0_deg': 180.0, 'admissible': False,
                             'why': 'overlap', 'trouble': '', 'gliders': []}


GLIDER = {'i': 0, 'j': 3, 'class': 'C2', 'start_period': 4, 'lifetime_periods': 120, 'ongoing': False, 'r_bl': 1.52,
          'theta_deg': 331.0, 'phi_deg': 8.5, 'distance_w': 2.9, 'path_w': 3.4, 'v_com_w_per_period': 0.024,
          'beta': None, 'isolated': True, 'isolation': 0.95, 'com_path_w': [[0.0, 0.0], [None, None], [0.05, 0.01]]}
DENSE = {'periods_run': 300.0, 'trouble': '', 'peak_tilt_deg': 1.2, 'peak_overlap_mm': None, 'n_gliders': 2,
         'positive': True, 'positive_isolated': True, 'longest_periods': 120, 'longest_class': 'C2',
         'longest_distance_w': 2.9, 'gliders': [GLIDER, {**GLIDER, 'class': 'C1', 'contact_fraction': 0.4}],
         'trajectory_bl': [[[0.0, 0.0], [1.0, None]]], 'trajectory_dt': 1.6}
PAIR = {**DENSE, 'r0_bl': 1.3, 'theta0_deg': 0.0, 'phi0_deg': 180.0, 'admissible': True, 'bound_tail_periods': 5,
        'bound_at_end': True, 'colliding_tail_periods': 5, 'colliding_at_end': True, 'out_of_reach_at_end': False,
        'late_w': 1.1, 'r_end_bl': 1.4, 'phi_end_deg': 181.0}
#: One stored result of each kind with a type (as the store writes it: JSON of ``as_dict()``).
STORED = {
    'dense': DENSE, 'pair': PAIR, 'pair_mujoco': {**PAIR, 'gliders': []},
    'single': {'heading_deg': -20.0, 'trouble': '', 'cycles': 20, 'drift_um_per_cycle': 75.0,
               'step_um_per_cycle': None},
    'p6': {'lifetime_periods': 40, 'censored': False, 'halts': 2, 'trouble': '', 'r0_bl': 1.47, 'theta0_deg': 99.0,
           'phi0_deg': 7.0, 'final_r_bl': 2.0, 'travel_w': 0.4, 'contact_periods': [1, 2]},
    'c2_harvest': {'samples': [{'seed': 0, 'i': 0, 'j': 1, 'period': 5, 'r_bl': 1.5}], 'gliders': 1, 'trouble': ''},
    'accuracy': {'trouble': '', 'wall_per_sim_s': 0.2, 'xy1_bl': [[0.0, 0.1], [1.3, 0.0]], 'xy10_bl': None,
                 'r_mean_bl': 1.35, 'drift_um_per_cycle': 70.2},
    'study_collision': {'admissible': True, 'collisions': 3, 'r0': 1.3, 'r_end': 1.41, 'J_normal': 0.021,
                        'J_friction': 0, 'J_plate': -0.026, 'dr_contact_BL': 0.05, 'dr_coast_BL': 0.02,
                        'vsep_max': 0.1, 'coast_ms_med': 11.4, 'touch_last10': True, 'depth_max_mm': 0.2,
                        'trouble': ''},
    'study_drift': {'heading': 90.0, 'alpha': 90.0, 'periods': 3, 'net_um': 142.5, 'step_um': 142.6,
                    'step_se_um': 0.008, 'dir_deg': 171.5, 'tilt_max_deg': 0.4, 'tilt_rms_deg': 0.2,
                    'wall_per_sim_s': 0.3, 'trouble': ''},
    'study_pair': {'admissible': True, 'theta0': 330.0, 'phi0': 180.0, 'p1': 0.0, 'p2': 0.05, 'periods': 4, 'ran': 4,
                   'touch': 3, 'bound_run': 3, 'bound_to_end': True, 'touch_last10': True, 'r_end': 1.3,
                   'r_mean_late': 1.31, 'phi_late': 179.0, 'travel_W': 0.05, 'late_travel_W': 0.03,
                   'wall_per_sim_s': 0.3, 'trouble': ''},
    'study_dense': {'seed': 0, 'n': 7, 'jitter': 0.0, 'periods': 300, 'sim_s': 480.0, 'wall_s': 200.0,
                    'x_real_time': 2.4, 'deepest_mm': 0.5, 'trouble': '', 'gliders_30': 4, 'gliders_100': 1,
                    'isolated_100': 0, 'best_dist_W': 2.1, 'c1_lives': '120 40', 'c2_lives': '35 31'},
    'study_impact': {'mean': 0.8618, 'sd': 0.0354, 'min': 0.8368, 'max': 0.8868, 'overlap_mm': 0.281,
                     'restitution_by_phase': [0.8368, 0.8868], 'trouble': ''},
}


@pytest.mark.parametrize('kind', sorted(STORED))
def test_each_kinds_stored_result_reads_back_typed_and_writes_the_same_bytes(kind: str) -> None:
    text = json.dumps(STORED[kind], sort_keys=True, separators=(',', ':'))
    typed = read_result(kind, json.loads(text))
    assert isinstance(typed, KINDS[kind].result)
    assert list(typed.as_dict()) == list(STORED[kind])            # the kind's key order, key for key
    assert json.dumps(typed.as_dict(), sort_keys=True, separators=(',', ':')) == text


def test_gliders_read_back_as_records_with_the_stored_class_key() -> None:
    dense = read_result('dense', DENSE)
    assert isinstance(dense, DenseResult)
    first, second = dense.gliders
    assert isinstance(first, GliderRecord) and first.glider_class == 'C2' and first.contact_fraction is None
    assert second.glider_class == 'C1' and second.contact_fraction == 0.4
    assert first.as_dict() == GLIDER and 'glider_class' not in first.as_dict()
    # a kind without a class rename stores exactly what dataclasses.asdict gives
    single = read_result('single', STORED['single'])
    assert dataclasses.asdict(single) == STORED['single']


def test_a_dense_study_row_without_gliders_leaves_their_fields_out() -> None:
    few = {k: v for k, v in STORED['study_dense'].items() if k in ('seed', 'n', 'jitter', 'periods', 'sim_s',
                                                                     'wall_s', 'x_real_time', 'deepest_mm', 'trouble')}
    typed = read_result('study_dense', few)
    assert isinstance(typed, StudyDenseResult) and typed.gliders_30 is None and typed.as_dict() == few
    refused = {'admissible': False, 'why': 'overlap', 'trouble': ''}
    assert read_result('study_pair', refused) == read_result('study_collision', refused) == \
        StudyInadmissibleResult(**refused)


def test_an_inadmissible_pair_start_reads_as_its_own_type_and_a_misfit_is_refused() -> None:
    stored = {'r0_bl': 0.3, 'theta0_deg': 0.0, 'phi0_deg': 180.0, 'admissible': False, 'why': 'overlap',
              'trouble': '', 'gliders': []}
    assert read_result('pair', stored) == InadmissiblePairResult(**stored)
    with pytest.raises(ResultError, match='does not fit PairResult'):
        read_result('pair', {'admissible': True, 'trouble': '', 'gliders': []})
    assert read_result('tests.smarticle_experiments.fake_trials:flaky', {'value': 3, 'trouble': ''}) == \
        {'value': 3, 'trouble': ''}    # a user's kind stays a dict


def test_a_real_pair_trial_is_stored_and_read_back_unchanged() -> None:
    from smarticle_experiments.kinds import run_kind

    stored = run_kind('pair', {**KINDS['pair'].defaults, 'periods': 3.0, 'min_periods': 1}, 0)
    text = json.dumps(stored, sort_keys=True, separators=(',', ':'))
    typed = read_result('pair', json.loads(text))
    assert isinstance(typed, PairResult) and typed.periods_run > 0
    assert json.dumps(typed.as_dict(), sort_keys=True, separators=(',', ':')) == text


def test_a_report_section_reads_typed_records() -> None:
    from smarticle_experiments.report import basin_outcome, glider_rule, long_pairs_table
    from smarticle_experiments.spec import spec_from_mapping

    spec = spec_from_mapping({'name': 'typed', 'kind': 'dense', 'seeds': [0]})
    trial = spec.trials({})[0]
    dense = read_result('dense', DENSE)
    assert isinstance(dense, DenseResult)
    table = '\n'.join(long_pairs_table([(trial, dense)], 100, glider_rule(spec)))
    assert '| C2 | 1 | 1 | 1.52 [1.52, 1.52] | 2.42 [2.42, 2.42] | 1 |' in table   # 2.42 W per 100 periods: a glider
    assert '| all | 2 |' in table and '| isolated | 2 |' in table
    pair = read_result('pair', PAIR)
    assert isinstance(pair, PairResult) and basin_outcome(pair) == 'bound'


def test_a_section_given_another_kinds_trials_names_the_trial(tmp_path: Path) -> None:
    from smarticle_experiments.errors import SpecError
    from smarticle_experiments.report import write_report
    from smarticle_experiments.spec import spec_from_mapping
    from smarticle_experiments.store import ResultStore

    with pytest.raises(SpecError, match="unknown report section 'p1' for kind 'single' \\(known: drift\\)"):
        spec_from_mapping({'name': 'mixed', 'kind': 'single', 'seeds': [0], 'report': ['p1']})
    kind = 'tests.smarticle_experiments.fake_trials:flaky'   # a plain function may name any section
    spec = spec_from_mapping({'name': 'mixed', 'kind': kind, 'seeds': [0], 'report': ['p1']})
    trials = spec.trials({})
    store = ResultStore(tmp_path / 'mixed')
    store.write({'key': trials[0].key, 'kind': kind, 'seed': 0, 'point': {}, 'status': 'ok',
                 'result': {'value': 0, 'trouble': ''}})
    with pytest.raises(ResultError, match=f"section 'p1' reads DenseResult results; trial {trials[0].key}"):
        write_report(spec, trials, store, {})


def test_the_physics_study_tables_read_typed_rows() -> None:
    from smarticle_experiments.kinds.study import study_row
    from smarticle_experiments.physics_study import dense_lines, pair_table

    def row(kind: str, result: dict, **params: object) -> Any:
        return study_row({'kind': kind, 'seed': 0, 'status': 'ok', 'result': result,
                          'params': {'label': 'shipped', 'settings': {}, **params}})

    start = {'theta_deg': 330.0, 'phi_deg': 180.0, 'phase2': 0.05}
    rows = [row('study_pair', STORED['study_pair'], **start),
            row('study_pair', {'admissible': False, 'why': 'overlap', 'trouble': ''}, **start)]
    assert isinstance(rows[0].result, StudyPairResult) and isinstance(rows[1].result, StudyInadmissibleResult)
    table = pair_table(rows)
    assert len(table) == 3 and '| shipped | 1/960 | 330, 180, 0.05 | 3 / 4 | 3 | 1.310 | 179 | 0.05 |' in table[2]
    lines = dense_lines([row('study_dense', STORED['study_dense'])])
    assert 'trials with a pair bound >= 100 periods 1; ' in lines[0] and 'best travel 2.10 W' in lines[0]
