"""The study commands (p6, c2-harvest, c2-collisions) on tiny runs: through the engine into the store, the
report and files written, bad input refused with one line and exit code 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from smarticle_experiments import p6
from smarticle_experiments.cli import main
from smarticle_experiments.store import ResultStore

ENGINE = ['--workers', '1', '--no-progress']


def stored_results(folder: Path) -> list[dict]:
    """Every stored record of a store folder."""
    return ResultStore(folder).records()


def test_p6_runs_its_conditions_into_the_store_and_prints_the_report(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'store'
    argv = ['p6', '--seeds', '0', '--periods', '2', '--open-loop', '90', '--feedback', '90', '--start', 'colliding',
            '--noise', 'none', '--contacts', '--out', str(out), *ENGINE]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert '| open loop 90 deg | 1 |' in text and '| feedback 90 deg | 1 |' in text and 'Log-rank' in text
    assert 'travel while bound' in text
    records = stored_results(out / 'p6_runs')
    assert len(records) == 2 and {r['params']['feedback'] for r in records} == {False, True}
    feedback = next(r['result'] for r in records if r['params']['feedback'])
    assert feedback['halts'] > 0 and isinstance(feedback['contact_periods'], list)
    assert (out / 'p6_runs' / 'report-p6_run-seeds-0' / 'p6_lifetimes.png').stat().st_size > 0
    assert main(argv) == 0   # a second run finds every trial stored
    assert '2 already stored, 0 done now' in capsys.readouterr().out


@pytest.mark.parametrize(('argv', 'says'), [
    (['--start', 'nowhere'], 'nowhere'), (['--noise', 'loud'], 'loud'), (['--seeds', '9..3'], 'backwards'),
    (['--open-loop', '--feedback'], 'no condition'), (['--set', 'restitution=2'], 'restitution'),
    (['--set', 'no_such_field=1'], 'no_such_field'), (['--set', 'restitution'], 'NAME=VALUE'),
])
def test_p6_refuses_bad_input_in_one_line_and_writes_nothing(argv: list[str], says: str, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    try:
        code = main(['p6', *argv, '--out', str(tmp_path / 'store'), *ENGINE])
    except SystemExit as exc:   # argparse's own refusals
        code = int(exc.code or 0)
    err = capsys.readouterr().err.strip()
    assert code == 2 and says in err and len(err.splitlines()) == 1
    assert not (tmp_path / 'store').exists()


def test_p6_takes_windows_from_a_parameter_file_or_the_calibration_output(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """--windows: the shipped parameter file gives the shipped windows; a flat mapping (what
    smarticle-feedback-calibrate prints) changes them; a file without windows is refused with exit code 2."""
    root = Path(__file__).resolve().parents[2]
    assert p6.windows_file(root / 'smarticle_feedback' / 'config' / 'feedback.yaml') == p6.default_feedback_config()
    flat = tmp_path / 'calibrated.yaml'
    flat.write_text('arm1_back_min: 0.15\narm1_back_max: 10.31\narm1_back_enabled: true\n', encoding='utf-8')
    config = p6.windows_file(flat)
    assert config != p6.default_feedback_config()
    assert 'arm1_back' in config.enabled_faces and 'arm1_back' not in p6.default_feedback_config().enabled_faces
    empty = tmp_path / 'empty.yaml'
    empty.write_text('period: 1.6\n', encoding='utf-8')
    typo = tmp_path / 'typo.yaml'
    typo.write_text('arm1_bak_min: 1.0\narm1_back_max: 10.0\n', encoding='utf-8')
    for bad, says in ((empty, 'no impact windows'), (tmp_path / 'missing.yaml', 'missing.yaml'),
                      (typo, 'arm1_bak_min')):
        assert main(['p6', '--windows', str(bad), '--out', str(tmp_path / 'store'), *ENGINE]) == 2
        assert says in capsys.readouterr().err
    assert not (tmp_path / 'store').exists()


def test_p6_set_and_windows_reach_the_trials(tmp_path: Path) -> None:
    """--set NAME=VALUE replaces PhysicsConfig fields (the trajectory changes); --windows reaches the feedback."""
    out = tmp_path / 'store'
    common = ['p6', '--seeds', '0', '--periods', '3', '--start', 'colliding', '--noise', 'none', '--out', str(out),
              *ENGINE]
    assert main([*common, '--open-loop', '90', '--feedback']) == 0
    assert main([*common, '--open-loop', '90', '--feedback', '--set', 'restitution=0.3']) == 0
    results = {json.dumps(r['params']['physics']): r['result'] for r in stored_results(out / 'p6_runs')}
    assert set(results) == {'{}', '{"restitution": 0.3}'}
    assert results['{}']['final_r_bl'] != results['{"restitution": 0.3}']['final_r_bl']


def test_c2_collisions_records_the_colliding_start(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'c2'
    assert main(['c2-collisions', '--start', 'colliding', '--noise', 'none', '--periods', '1', '--out',
                 str(out)]) == 0
    assert 'compression' in capsys.readouterr().out
    for name in ('c2_steps.npz', 'c2_events.csv', 'c2_events.png'):
        assert (out / name).stat().st_size > 0


def test_c2_harvest_stores_its_trials_and_says_when_nothing_was_harvested(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'store'
    assert main(['c2-harvest', '--seeds', '5000', '--periods', '2', '--out', str(out), *ENGINE]) == 1
    assert 'no C2 samples' in capsys.readouterr().err
    (record,) = stored_results(out / 'c2_harvest')
    assert record['kind'] == 'c2_harvest' and record['result']['samples'] == [] and record['seed'] == 5000
    try:
        code = main(['c2-harvest', '--seeds', '9..3', '--out', str(out)])
    except SystemExit as exc:
        code = int(exc.code or 0)
    assert code == 2
