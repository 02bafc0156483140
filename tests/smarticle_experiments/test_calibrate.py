"""smarticle-calibrate: preset files in the builder, the sim bridge and a spec; a fit on a sim bag; bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from smarticle_common.gait import GaitConfig
from smarticle_experiments import calibrate as cal
from smarticle_experiments.calibrate_cli import main
from smarticle_sim.batch import run_trial
from smarticle_sim.config_builder import build_config
from smarticle_sim.errors import ConfigError
from smarticle_sim.scenes import dense_scene, pair_scene


def _preset_file(tmp_path: Path, friction: float = 0.42) -> Path:
    path = tmp_path / 'lab.yaml'
    path.write_text(yaml.safe_dump({'preset': 'small', 'physics': {'friction_body_plate': friction},
                                    'robot': {'servo_speed': 9.5}, 'calibration': {'bags': ['x']}}))
    return path


def test_build_config_loads_a_preset_file_and_overrides_apply_on_top(tmp_path: Path) -> None:
    path = _preset_file(tmp_path)
    config = build_config(str(path))
    assert config.physics.friction_body_plate == 0.42
    assert config.robot.servo_speed == 9.5
    assert config.robot.name == 'small'
    assert build_config(str(path), physics={'friction_body_plate': 0.5}).physics.friction_body_plate == 0.5


def test_a_bad_preset_file_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / 'bad.yaml'
    bad.write_text(yaml.safe_dump({'physics': {'friction_plate': 0.3}}))
    with pytest.raises(ConfigError, match='friction_plate is not a PhysicsConfig field'):
        build_config(str(bad))
    with pytest.raises(ConfigError, match='cannot be read'):
        build_config(str(tmp_path / 'missing.yaml'))


def test_the_sim_bridge_takes_a_preset_file(tmp_path: Path) -> None:
    from smarticle_sim.bridge import PARAMS, BridgeSettings

    values = {p.name: p.default for p in PARAMS}
    values['preset'] = str(_preset_file(tmp_path))
    settings = BridgeSettings.from_values(values)
    assert settings.sim.physics.friction_body_plate == 0.42
    assert settings.sim.robot.servo_speed == 9.5


def test_an_experiment_trial_takes_a_preset_file(tmp_path: Path) -> None:
    from smarticle_experiments.configs import config_of

    config = config_of({'preset': str(_preset_file(tmp_path)), 'physics': {'restitution': 0.5}})
    assert (config.physics.friction_body_plate, config.physics.restitution) == (0.42, 0.5)


def _pair_bag(tmp_path: Path, friction: float, periods: int = 8) -> Path:
    config = build_config('small', physics={'friction_body_plate': friction})
    scene = pair_scene(config.robot, GaitConfig.from_degrees(90.0), 1.3, 0.0, math.pi)
    rec = run_trial(config, scene, periods)
    return cal.write_pose_bag(rec.time, rec.poses, tmp_path / 'pair', 'test pair')


def test_a_sim_bags_own_value_is_far_nearer_than_the_default(tmp_path: Path) -> None:
    """Each segment restarts at rest from the bag's poses, so even the bag's own value leaves a small gap."""
    bag = _pair_bag(tmp_path, 0.45)
    run = cal.load_run(bag)
    assert run.robots == 2 and run.periods == 8
    assert cal.segment_starts(run) == [0, 2, 4]
    problem = cal.Problem([run], 'small', cal.parse_fit('friction_body_plate'))
    assert problem.distance([0.30]) > 10.0 * problem.distance([0.45])


@pytest.mark.slow
def test_the_cli_recovers_a_friction_inside_its_interval(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The sim bag is rebuilt exactly, so its value is a sharp minimum; the grid of the bounds holds it."""
    bag = _pair_bag(tmp_path, 0.45)
    with pytest.raises(SystemExit) as done:
        main([str(bag), '--fit', 'friction_body_plate=0.25:0.65', '--out', str(tmp_path / 'out')])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert 'fitted (95 % bootstrap interval over segments)' in text
    data = yaml.safe_load((tmp_path / 'out' / 'preset.yaml').read_text())
    fitted = data['calibration']['fitted']['friction_body_plate']
    lo, hi = fitted['interval_95']
    assert lo <= 0.45 <= hi
    assert abs(fitted['value'] - 0.45) < 0.02
    assert data['physics']['friction_body_plate'] == fitted['value']
    assert build_config(str(tmp_path / 'out' / 'preset.yaml')).physics.friction_body_plate == fitted['value']
    assert (tmp_path / 'out' / 'gaps.png').stat().st_size > 0


@pytest.mark.slow
def test_two_parameters_from_two_groups_are_recovered_inside_their_intervals(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A plate friction (physics) and a servo speed (robot) fitted at once on a pair bag. The sim bag is rebuilt
    exactly, so the truth is a sharp minimum of a rough distance (a pair in contact: off the minimum, D jumps
    between segments' contact outcomes), which a local search finds only from near it: the bounds put the
    truth on the 7-point grid, a step of 0.05 and 0.5 rad/s. Stated tolerances: half a grid step."""
    truth = {'friction_body_plate': 0.45, 'servo_speed': 10.0}
    tolerance = {'friction_body_plate': 0.025, 'servo_speed': 0.25}
    config = build_config('small', physics={'friction_body_plate': truth['friction_body_plate']},
                          robot={'servo_speed': truth['servo_speed']})
    scene = pair_scene(config.robot, GaitConfig.from_degrees(90.0, servo_speed=truth['servo_speed']), 1.3, 0.0,
                       math.pi)
    rec = run_trial(config, scene, 6)
    bag = cal.write_pose_bag(rec.time, rec.poses, tmp_path / 'pair', 'test pair')
    with pytest.raises(SystemExit) as done:
        main([str(bag), '--fit', 'friction_body_plate=0.3:0.6,servo_speed=8.5:11.5', '--max-evaluations', '20',
              '--out', str(tmp_path / 'out')])
    assert done.value.code == 0
    assert 'servo_speed = ' in capsys.readouterr().out
    data = yaml.safe_load((tmp_path / 'out' / 'preset.yaml').read_text())
    for name, true in truth.items():
        fitted = data['calibration']['fitted'][name]
        lo, hi = fitted['interval_95']
        assert abs(fitted['value'] - true) <= tolerance[name], (name, fitted)
        assert lo <= true <= hi, (name, fitted)
    written = build_config(str(tmp_path / 'out' / 'preset.yaml'))
    assert written.physics.friction_body_plate == data['calibration']['fitted']['friction_body_plate']['value']
    assert written.robot.servo_speed == data['calibration']['fitted']['servo_speed']['value']


def test_bound_share_and_lifetime_of_known_strobes() -> None:
    """Three robots, six periods, bind radius 0.0864 m: robot 1 at x1, robot 2 at y2 from robot 0 at the origin.
    Bound tables (pairs 01, 02, 12): 110101, 001110 (unseen robot 2 in the last period binds nothing), 000100.
    8 of 18 pair-periods bound; runs of 2, 1, 1 (censored at the end), 3 and 1 periods: mean 1.6."""
    x1 = np.array([0.05, 0.05, 0.5, 0.05, 0.5, 0.05])
    y2 = np.array([1.0, 1.0, 0.05, 0.05, 0.05, np.nan])
    strobe = np.zeros((6, 3, 3))
    strobe[:, 1, 0] = x1
    strobe[:, 2, 1] = y2
    strobe[5, 2, :] = np.nan
    table = cal.bound_table(strobe, 1.6 * 0.054)
    assert table.T.astype(int).tolist() == [[1, 1, 0, 1, 0, 1], [0, 0, 1, 1, 1, 0], [0, 0, 0, 1, 0, 0]]
    stats = cal.binding_stats([table])
    assert stats['bound share'] == pytest.approx(8 / 18) and stats['lifetime'] == pytest.approx(1.6)
    apart = np.zeros((4, 2, 3))
    apart[:, 1, 0] = 1.0
    pooled = cal.binding_stats([table, cal.bound_table(apart, 1.6 * 0.054)])
    assert pooled['bound share'] == pytest.approx(8 / 22) and pooled['lifetime'] == pytest.approx(1.6)
    never = cal.binding_stats([cal.bound_table(apart, 1.6 * 0.054)])
    assert never['bound share'] == 0.0 and math.isnan(never['lifetime'])
    # at the radius is not under it
    assert not cal.bound_table(apart, 1.0).any() and cal.bound_table(apart, 1.0 + 1e-9).all()


def test_the_cli_prints_and_draws_the_whole_runs_binding(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Three robots of a dense start that bind and part within 12 periods: the bag's row is the rule applied to
    the bag's strobe; the sim's whole run (one run from the bag's first poses) gives its own."""
    config = build_config('small', physics={'friction_body_plate': 0.45})
    rec = run_trial(config, dense_scene(config.robot, GaitConfig.from_degrees(90.0), 3, seed=1), 12)
    bag = cal.write_pose_bag(rec.time, rec.poses, tmp_path / 'three', 'test three')
    run = cal.load_run(bag)
    expected = cal.binding_stats([cal.bound_table(run.strobe[:run.periods], 1.6 * config.robot.body_length)])
    assert 0.0 < expected['bound share'] < 1.0
    problem = cal.Problem([run], 'small', [])
    assert cal.bag_binding([run], problem.bind_radius()) == expected
    sim = problem.binding([])
    strobe = cal.simulate_whole(run, build_config('small'))
    assert np.array_equal(strobe[0], run.strobe[0] - [*np.nanmean(run.strobe[0, :, :2], axis=0), 0.0])
    assert sim == cal.binding_stats([cal.bound_table(strobe[:run.periods], problem.bind_radius())])
    with pytest.raises(SystemExit) as done:
        main([str(bag), '--out', str(tmp_path / 'out')])
    assert done.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    title = next(k for k, line in enumerate(lines) if line.startswith('binding over whole runs'))
    assert lines[title + 1].split() == ['observable', 'unit', 'bag', 'default']
    for row, name in zip(lines[title + 2:title + 4], ('bound share', 'lifetime'), strict=True):
        assert row.startswith(name)
        bag_value, sim_value = (float(v) for v in row[len(name):].split()[1:])
        assert bag_value == pytest.approx(expected[name], rel=1e-3)
        assert sim_value == pytest.approx(sim[name], rel=1e-3)
    assert (tmp_path / 'out' / 'gaps.png').stat().st_size > 0


def _run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    with pytest.raises(SystemExit) as done:
        main(args)
    err = capsys.readouterr().err
    return int(done.value.code or 0), err


def test_bad_input_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _run_cli([str(tmp_path / 'nothing')], capsys)
    assert code == 2 and err.count('\n') == 1 and 'does not exist' in err

    bag = cal.write_pose_bag(np.arange(0.0, 8.0, 0.05), np.zeros((160, 1, 3)), tmp_path / 'still', 'test')
    code, err = _run_cli([str(bag), '--fit', 'friction_plate'], capsys)
    assert code == 2 and err.count('\n') == 1 and "'friction_plate' is no parameter to fit" in err

    from smarticle_bags.csv_import import SENSOR_QOS, encode_pose_array
    from smarticle_bags.writer import BagWriter

    other = tmp_path / 'no_poses'
    with BagWriter(other) as writer:
        writer.add_topic('/elsewhere', 'geometry_msgs/msg/PoseArray', [SENSOR_QOS])
        writer.write('/elsewhere', encode_pose_array(0, np.zeros((1, 3))), 0)
        writer.close()
    code, err = _run_cli([str(other)], capsys)
    assert code == 2 and err.count('\n') == 1 and 'holds no /smarticles/poses' in err

    code, err = _run_cli([str(bag), '--preset', 'tiny'], capsys)
    assert code == 2 and err.count('\n') == 1 and 'tiny' in err

    code, err = _run_cli([str(bag), '--fit', 'servo_speed=3:15', '--alpha-max-deg', '90'], capsys)
    assert code == 2 and err.count('\n') == 1 and 'too slow for the gait' in err and 'LO >= 7.854' in err


def test_the_demo_takes_a_preset_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from smarticle_bringup.demo import build_parser, main, plan_parts, write_params

    path = _preset_file(tmp_path)
    args = build_parser().parse_args(['--preset', str(path)])
    params = tmp_path / 'params.yaml'
    for part in plan_parts(args):
        assert part.spec.servo_speed == 9.5 and part.spec.name == 'small'
        write_params(part, args, params)
        data = yaml.safe_load(params.read_text(encoding='utf-8'))
        assert data['/sim_bridge']['ros__parameters']['preset'] == str(path)
        assert data['/smarticle_0/gait']['ros__parameters']['servo_speed'] == 9.5
    bad = tmp_path / 'bad.yaml'
    bad.write_text('physics: {friction_plate: 0.3}\n')
    out = tmp_path / 'demo'
    assert main(['--preset', str(bad), '--out', str(out)], prog='demo.sh') == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and '--preset' in err and 'friction_plate' in err
    assert not out.exists()


def test_an_experiment_spec_takes_a_preset_file_and_keys_trials_by_its_values(tmp_path: Path) -> None:
    from smarticle_experiments.errors import SpecError
    from smarticle_experiments.spec import load_spec

    preset = _preset_file(tmp_path)
    spec_path = tmp_path / 'lab_p1.yaml'
    spec_path.write_text(yaml.safe_dump({
        'name': 'lab_p1', 'description': 'p1 with a calibrated preset', 'kind': 'dense', 'preset': str(preset),
        'periods': 10, 'physics': {'restitution': 0.5}, 'params': {'robots': 7, 'alpha_max_deg': 90},
        'seeds': {'start': 0, 'count': 1}}))
    spec = load_spec(str(spec_path))
    assert spec.base['preset'] == 'small'
    assert spec.base['physics'] == {'friction_body_plate': 0.42, 'restitution': 0.5}
    assert spec.base['robot'] == {'servo_speed': 9.5}
    bad = tmp_path / 'bad.yaml'
    bad.write_text('physics: {friction_plate: 0.3}\n')
    spec_path.write_text(spec_path.read_text().replace(str(preset), str(bad)))
    with pytest.raises(SpecError, match='friction_plate'):
        load_spec(str(spec_path))


@pytest.mark.slow
def test_trials_on_dask_give_the_same_gaps(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = _pair_bag(tmp_path, 0.35, periods=5)
    tables = []
    for workers in ('0', '1'):
        with pytest.raises(SystemExit) as done:
            main([str(bag), '--workers', workers, '--out', str(tmp_path / f'out{workers}')])
        assert done.value.code == 0
        out = capsys.readouterr().out
        tables.append(out[out.index('gap per observable'):out.index('drawn:')])
    assert tables[0] == tables[1]
    assert 'speed' in tables[0] and 'phi' in tables[0]


def test_each_robots_measured_clock_rate_drives_its_gait(tmp_path: Path) -> None:
    from dataclasses import replace

    run = cal.load_run(_pair_bag(tmp_path, 0.30, periods=5))
    config = build_config('small')
    same = cal.simulate(run, config)
    fast = cal.simulate(replace(run, rates=(1.0, 1.1)), config)
    assert np.array_equal(same['speed'], cal.simulate(run, config)['speed'])
    assert not np.allclose(same['phi'], fast['phi'])
