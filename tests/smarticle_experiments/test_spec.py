"""Specs as data: the shipped specs load, bad specs are refused naming the field, keys are stable."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from smarticle_experiments.errors import SpecError
from smarticle_experiments.spec import builtin_names, load_spec, spec_from_mapping

CODE = {'smarticle_experiments': '0', 'commit': 'abc', 'numpy': '1', 'pybullet': '1'}
TINY = {'name': 'tiny', 'kind': 'dense', 'periods': 2, 'params': {'robots': 3}, 'seeds': 2}


def test_every_shipped_spec_loads_and_expands() -> None:
    names = builtin_names()
    assert {'p1', 'p2', 'p3', 'p4', 'p5', 'p6', 'p7', 'accuracy'} <= set(names)
    counts = {name: len(load_spec(name).trials(CODE)) for name in names}
    assert counts['p1'] == 151
    assert counts['p4'] == 2 * 24 * 24
    assert counts['p6'] == (4 + 1) * 40          # two grid blocks: open loop 70/80/85/90, feedback 90
    assert counts['p6_sensitivity'] == 9 * 10    # the preset and eight assumed values, one at a time


def test_every_shipped_spec_is_tagged_and_current_and_cites_no_issue() -> None:
    from smarticle_experiments.spec import TAGS, builtin_dir

    for name in builtin_names():
        spec = load_spec(name)
        assert spec.status == 'current' and spec.tags and set(spec.tags) <= set(TAGS), name
        text = (builtin_dir() / f'{name}.yaml').read_text()
        assert 'issue #' not in text and 'smarticle-p6 ' not in text and 'smarticle-c2-' not in text, name
    assert [n for n in builtin_names() if 'paper' in load_spec(n).tags] == ['p1', 'p2', 'p3', 'p4', 'p5', 'p6', 'p7']


def test_seeds_take_the_stacks_seed_syntax() -> None:
    spec = spec_from_mapping({'name': 's', 'kind': 'single', 'seeds': '3..5,9'})
    assert spec.seeds == (3, 4, 5, 9)


def test_p2_and_p3_reuse_the_p1_trials() -> None:
    keys = {name: [t.key for t in load_spec(name).trials(CODE)] for name in ('p1', 'p2', 'p3')}
    assert keys['p1'] == keys['p2'] == keys['p3']
    assert load_spec('p2').store == load_spec('p3').store == 'p1'


def test_a_users_yaml_file_is_a_spec(tmp_path: Path) -> None:
    path = tmp_path / 'mine.yaml'
    path.write_text(yaml.safe_dump({**TINY, 'grid': {'alpha_max_deg': [60, 90], 'physics.solver_iterations': [5]}}))
    spec = load_spec(str(path))
    trials = spec.trials(CODE)
    assert len(trials) == 4
    assert {t.params['alpha_max_deg'] for t in trials} == {60.0, 90.0}
    assert all(t.params['physics'] == {'solver_iterations': 5} for t in trials)


@pytest.mark.parametrize(('change', 'named'), [
    ({'gird': {}}, "'gird'"),
    ({'params': {'robotz': 3}}, 'params.robotz'),
    ({'analysis': {'min_period': 3}}, 'analysis.min_period'),
    ({'physics': {'time_stepp': 0.01}}, 'physics.time_stepp'),
    ({'grid': {'theta_deg': []}}, 'grid.theta_deg'),
    ({'grid': []}, 'grid'),
    ({'grid': {'nonsense': [1]}}, 'grid.nonsense'),
    ({'seeds': 0}, 'seeds'),
    ({'seeds': -3}, 'seeds'),
    ({'seeds': []}, 'seeds'),
    ({'seeds': {'count': 0}}, 'seeds.count'),
    ({'seeds': '9..3'}, 'backwards'),
    ({'tags': ['papers']}, 'tags'),
    ({'status': 'old'}, 'status'),
    ({'periods': 0}, 'periods'),
    ({'periods': -5}, 'periods'),
    ({'kind': 'nope'}, 'nope'),
    ({'report': ['figure9']}, 'figure9'),
    ({'physics': {'contact_erp': 2.0}}, 'contact_erp'),
    ({'noise': 'loud'}, 'noise'),
    ({'noise': {'clock_rate': 0.01}}, 'noise.clock_rate'),
    ({'noise': {'clock_rate_sd': -0.01}}, 'clock_rate_sd'),
    ({'noise': {'friction_sd': 0.5}}, 'friction_sd'),
    ({'grid': {'noise.servo_jiter': [0.01]}}, 'grid.noise.servo_jiter'),
    ({'kind': 'p6', 'params': {'start': 'somewhere'}}, 'params.start'),
    ({'kind': 'pair_mujoco', 'params': {}, 'grid': {'mujoco.servo_kvv': [1.0]}}, 'grid.mujoco.servo_kvv'),
    ({'kind': 'pair', 'params': {}, 'grid': {'mujoco.servo_kv': [1.0]}},
     'need engine: mujoco, the trial runs on bullet'),
    ({'kind': 'pair', 'params': {}, 'grid': {'mujoco.servo_kvv': [1.0]}}, 'grid.mujoco.servo_kvv'),
    ({'kind': 'accuracy', 'params': {}, 'engine': 'mujoco'}, "kind 'accuracy' runs in bullet, not in mujoco"),
    ({'kind': 'pair_mujoco', 'params': {}, 'engine': 'bullet'}, "kind 'pair_mujoco' runs in mujoco, not in bullet"),
    ({'kind': 'pair', 'params': {}, 'engine': 'ode'}, 'engine must be one of bullet, mujoco, chrono'),
    ({'kind': 'pair', 'engine': 'mujoco', 'params': {'hold_first': True}}, 'hold_first: MuJoCo has no held robot'),
    ({'kind': 'single', 'params': {}, 'mujoco': {'time_stepp': 1e-4}}, 'unknown key mujoco.time_stepp'),
    ({'kind': 'single', 'params': {}, 'mujoco': {'time_step': 1e-4}}, 'need engine: mujoco, the trial runs on bullet'),
    ({'kind': 'study_drift', 'params': {}, 'mujoco': {'time_step': 1e-4}},
     'mujoco settings are not supported by kind'),
    ({'kind': 'pair_mujoco', 'params': {'mujoco': {'contact_timeconst': 1e-5}}}, 'contact_timeconst'),
    ({'kind': 'single_mujoco', 'params': {'mujoco': {'servo_gian': 1.0}}}, 'servo_gian'),
])
def test_bad_specs_are_refused_naming_the_field(change: dict, named: str) -> None:
    with pytest.raises(SpecError, match=named.replace('.', r'\.').replace('(', r'\(')):
        spec_from_mapping({**TINY, **change})


def test_trial_overrides_are_checked() -> None:
    spec = spec_from_mapping(TINY)
    with pytest.raises(SpecError, match='trials'):
        spec.with_trial_count(0)
    with pytest.raises(SpecError, match='periods'):
        spec.with_periods(-1.0)
    assert len(spec.with_trial_count(5).trials(CODE)) == 5
    two = spec_from_mapping({**TINY, 'grid': {'alpha_max_deg': [80, 90]}})
    assert [t.seed for t in two.with_trial_count(4).trials(CODE)] == [0, 1, 0, 1]   # trials in all, not per point
    with pytest.raises(SpecError, match='multiple of 2'):
        two.with_trial_count(3)


def test_every_grid_point_keeps_its_own_grouped_values() -> None:
    """A grid key ``group.X`` reaches its own trials only (the trials do not share one mutated mapping)."""
    spec = spec_from_mapping({'name': 'g', 'kind': 'single_mujoco', 'periods': 2, 'seeds': 1,
                              'grid': {'mujoco.servo_kv': [0.03, 0.1], 'robot.servo_torque': [0.05, 1.0],
                                       'noise.clock_rate_sd': [0.0, 0.003]}})
    seen = [(t.params['mujoco']['servo_kv'], t.params['robot']['servo_torque'], t.params['noise']['clock_rate_sd'])
            for t in spec.trials(CODE)]
    assert sorted(seen) == sorted((k, s, n) for k in (0.03, 0.1) for s in (0.05, 1.0) for n in (0.0, 0.003))


def test_keys_follow_settings_seed_and_code_version() -> None:
    spec = spec_from_mapping(TINY)
    first = [t.key for t in spec.trials(CODE)]
    assert first == [t.key for t in spec_from_mapping(TINY).trials(CODE)]     # stable
    assert len(set(first)) == 2                                                # one per seed
    assert first != [t.key for t in spec.trials({**CODE, 'commit': 'def'})]    # code version
    other = spec_from_mapping({**TINY, 'physics': {'solver_iterations': 7}})
    assert set(first).isdisjoint(t.key for t in other.trials(CODE))            # settings
    whole = spec_from_mapping({**TINY, 'params': {'robots': 3, 'alpha_max_deg': 90}})
    assert first == [t.key for t in whole.trials(CODE)]                        # 90 and 90.0 hash alike


def test_noise_is_written_out_and_left_out_of_keys_when_off() -> None:
    from smarticle_sim.settings import NoiseConfig

    plain = [t.key for t in spec_from_mapping(TINY).trials(CODE)]
    assert plain == [t.key for t in spec_from_mapping({**TINY, 'noise': 'none'}).trials(CODE)]
    assert 'noise' not in spec_from_mapping(TINY).trials(CODE)[0].params
    paper = spec_from_mapping({**TINY, 'noise': 'paper'}).trials(CODE)
    expected = NoiseConfig.paper()
    assert paper[0].params['noise'] == {'clock_rate_sd': expected.clock_rate_sd,
                                        'servo_jitter': expected.servo_jitter,
                                        'friction_sd': expected.friction_sd,
                                        'friction_length': expected.friction_length}
    assert set(plain).isdisjoint(t.key for t in paper)
    grid = spec_from_mapping({**TINY, 'grid': {'noise.clock_rate_sd': [0.0, 0.003]}}).trials(CODE)
    assert [t.params['noise'] for t in grid[::2]] == [{'clock_rate_sd': 0.0}, {'clock_rate_sd': 0.003}]
