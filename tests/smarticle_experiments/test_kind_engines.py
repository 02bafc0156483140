"""Any simulated kind in Bullet or MuJoCo: a spec's ``engine`` (or ``--engine``) is part of its trials' parameters
and keys (left out for the kind's default engine, so Bullet keys stay), a kind is refused in an engine it does not
run in, and P7 and P6 run in MuJoCo from the experiments command."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from smarticle_experiments.cli import main
from smarticle_experiments.errors import SpecError
from smarticle_experiments.kinds import KINDS, run_kind
from smarticle_experiments.results import P6Result
from smarticle_experiments.spec import load_spec, spec_from_mapping

CODE = {'smarticle_experiments': '0', 'source': 'abc'}
LONE = {'name': 'lone', 'kind': 'single', 'periods': 2, 'seeds': 2}


def test_the_engine_is_in_a_trial_s_key_only_when_it_is_not_the_kind_s_default() -> None:
    bullet = spec_from_mapping(LONE)
    assert bullet.engine == 'bullet' and 'engine' not in bullet.base
    same = spec_from_mapping({**LONE, 'engine': 'bullet'})
    assert [t.key for t in same.trials(CODE)] == [t.key for t in bullet.trials(CODE)]
    mujoco = spec_from_mapping({**LONE, 'engine': 'mujoco', 'mujoco': {'time_step': 1.0 / 4800.0}})
    assert mujoco.engine == 'mujoco' and mujoco.base['engine'] == 'mujoco'
    assert set(t.key for t in mujoco.trials(CODE)).isdisjoint(t.key for t in bullet.trials(CODE))
    typed = KINDS['single'].parse(mujoco.trials(CODE)[0].params)
    assert typed.as_dict()['engine'] == 'mujoco' and typed.mujoco_settings().time_step == 1.0 / 4800.0
    assert 'engine' not in KINDS['single'].parse(bullet.trials(CODE)[0].params).as_dict()
    # the kinds that always ran in MuJoCo keep theirs: no engine parameter, their settings stored as before
    old = spec_from_mapping({**LONE, 'kind': 'single_mujoco'})
    assert old.engine == 'mujoco' and 'engine' not in old.base and old.base['mujoco'] == {}


def test_every_simulated_paper_kind_runs_in_both_engines_and_the_others_say_where_they_run() -> None:
    for name in ('dense', 'pair', 'single', 'p6'):
        assert KINDS[name].engines == ('bullet', 'mujoco'), name
    for name, engines in (('accuracy', 'bullet'), ('c2_harvest', 'bullet'), ('study_drift', 'bullet'),
                          ('single_mujoco', 'mujoco')):
        other = 'mujoco' if engines == 'bullet' else 'bullet'
        with pytest.raises(SpecError, match=f"kind '{name}' runs in {engines}, not in {other}"):
            spec_from_mapping({'name': 'x', 'kind': name, 'engine': other})


def test_engine_option_names_the_spec_apart_in_the_same_store() -> None:
    spec = load_spec('p7', 'mujoco')
    assert (spec.name, spec.store, spec.engine) == ('p7-mujoco', 'p7', 'mujoco')
    assert load_spec('p7', 'bullet').name == 'p7'
    assert [t.key for t in load_spec('p7', 'bullet').trials(CODE)] == [t.key for t in load_spec('p7').trials(CODE)]
    assert load_spec('single_mujoco', 'mujoco').name == 'single_mujoco'


def test_a_bad_engine_on_the_command_line_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(['run', 'p7', '--engine', 'ode'])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'ode'" in err and len(err.strip().splitlines()) == 1
    assert main(['status', 'p1', '--engine', 'chrono', '--out', '/nonexistent']) == 2
    err = capsys.readouterr().err
    assert "kind 'dense' runs in bullet or mujoco, not in chrono" in err and len(err.strip().splitlines()) == 1


def test_a_mujoco_p6_pair_with_feedback_halts_at_the_colliding_start() -> None:
    params = {**KINDS['p6'].defaults, 'periods': 3.0, 'start': 'colliding', 'feedback': True, 'engine': 'mujoco'}
    result = P6Result.from_dict(run_kind('p6', params, 0))
    assert result.trouble == ''
    assert result.halts > 0
    open_loop = P6Result.from_dict(run_kind('p6', {**params, 'feedback': False}, 0))
    assert open_loop.halts == 0


def test_p7_runs_and_reports_in_mujoco(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / 'p7short.yaml'
    data = yaml.safe_load(Path(load_spec('p7').source).read_text())
    data.update(name='p7short', seeds=2, periods=2)
    spec.write_text(yaml.safe_dump(data))
    out = tmp_path / 'out'
    assert main(['run', str(spec), '--engine', 'mujoco', '--workers', '1', '--no-progress', '--report',
                 '--out', str(out)]) == 0
    said = capsys.readouterr().out
    assert 'p7short-mujoco: 6 trials (3 grid points x 2 seeds) in mujoco' in said
    report = out / 'p7short' / 'report-p7short-mujoco' / 'report.md'
    assert report.is_file(), said
    assert 'drift' in report.read_text().lower()
    records = [yaml.safe_load(p.read_text()) for p in (out / 'p7short' / 'trials').glob('*.json')]
    assert len(records) == 6 and all(r['status'] == 'ok' for r in records)
    assert all(r['params']['engine'] == 'mujoco' for r in records)
    assert all(r['result']['drift_um_per_cycle'] > 0 for r in records)
