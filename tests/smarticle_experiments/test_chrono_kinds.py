"""The Chrono kinds (``pair_chrono``, ``single_chrono``) as built-in kinds: their spec fields, the one line
with which a spec of them is skipped when Chrono is not built, and (with the build) a short run end to end."""

from __future__ import annotations

from pathlib import Path

import pytest

from smarticle_experiments.cli import main
from smarticle_experiments.errors import SpecError
from smarticle_experiments.harness import RunOptions, run_spec
from smarticle_experiments.spec import apply_point, load_spec, spec_from_mapping
from smarticle_experiments.kinds import CHRONO_KINDS, KINDS, engine_missing, run_kind
from smarticle_sim.chrono_reference import DRIVER_ENV, chrono_available

CHRONO_SPECS = ('pair_chrono_ring', 'single_chrono')


@pytest.fixture
def no_chrono(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """Point the driver's environment variable at a file that does not exist."""
    missing = tmp_path / 'no-build' / 'smarticle_chrono'
    monkeypatch.setenv(DRIVER_ENV, str(missing))
    return missing


def engine_args(out: Path) -> RunOptions:
    """The engine options of ``run`` (one worker, no progress bar)."""
    return RunOptions(out=out, workers=1, retries=0, progress=False)


def test_chrono_kinds_are_built_in() -> None:
    assert CHRONO_KINDS <= set(KINDS)
    for kind in CHRONO_KINDS:
        assert 'chrono' in KINDS[kind].defaults
    assert engine_missing('pair') is None
    assert engine_missing('single_mujoco') is None


def test_missing_build_names_itself(no_chrono: Path) -> None:
    for kind in CHRONO_KINDS:
        why = engine_missing(kind)
        assert why is not None and why.startswith('Chrono is not built') and str(no_chrono) in why
        assert '\n' not in why


@pytest.mark.parametrize('name', CHRONO_SPECS)
def test_spec_is_skipped_with_one_line_without_the_build(name: str, no_chrono: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    spec = load_spec(name)
    trials, store, _ = run_spec(spec, engine_args(tmp_path / 'store'))
    out = capsys.readouterr().out.strip().splitlines()
    assert out == [f'{name}: skipped, {len(trials)} trials not run: {engine_missing(spec.kind)}']
    assert trials and not store.folder.exists()   # no cluster, nothing written


def test_cli_run_skips_and_exits_zero(no_chrono: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['run', 'single_chrono', '--out', str(tmp_path), '--workers', '1', '--no-progress']) == 0
    plan, *rest = capsys.readouterr().out.strip().splitlines()   # the run's plan, then the one skip line
    assert plan.startswith('single_chrono: 4 trials') and len(rest) == 1
    assert rest[0].startswith('single_chrono: skipped, 4 trials not run: Chrono is not built')


def test_chrono_settings_are_spec_fields() -> None:
    spec = spec_from_mapping({'name': 'c', 'kind': 'pair_chrono', 'periods': 2,
                              'grid': {'chrono.time_step': [1e-4, 5e-5], 'theta_deg': [0, 30]}, 'seeds': 1}, 'c')
    steps = sorted({t.params['chrono']['time_step'] for t in spec.trials({'code': 'x'})})
    assert steps == [5e-5, 1e-4]
    with pytest.raises(SpecError, match='chrono.bogus'):
        spec_from_mapping({'name': 'c', 'kind': 'pair_chrono', 'grid': {'chrono.bogus': [1]}}, 'c')
    with pytest.raises(SpecError, match='contact'):
        spec_from_mapping({'name': 'c', 'kind': 'pair_chrono', 'params': {'chrono': {'contact': 'soft'}}}, 'c')
    with pytest.raises(SpecError, match='chrono'):
        spec_from_mapping({'name': 'c', 'kind': 'pair', 'grid': {'chrono.time_step': [1e-4]}}, 'c')


@pytest.mark.skipif(not chrono_available(), reason='Chrono is not built (tools/chrono_reference/build_chrono.sh): '
                    'the Chrono kinds are skipped')
def test_pair_chrono_kind_runs_end_to_end() -> None:
    result = run_kind('pair_chrono', apply_point(dict(KINDS['pair_chrono'].defaults), {'periods': 1.0}), 0)
    assert result['admissible'] and result['trouble'] == '' and result['periods_run'] == 1
    assert 1.0 < result['r_end_bl'] < 3.0 and 0.0 <= result['phi_end_deg'] < 360.0
