"""The result store: atomic per-trial files, what a rerun skips, the Parquet summary."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from smarticle_experiments.store import ResultStore, code_version, summary_row


def record(key: str, status: str = 'ok', kind: str = 'trial', **result: object) -> dict:
    """A minimal store record."""
    rec: dict = {'key': key, 'kind': 'dense', 'seed': 0, 'point': {'alpha_max_deg': 90.0}, 'status': status,
                 'result': {'positive': True, 'n': 3, 'gliders': [{'x': 1}], **result}, 'wall_s': 1.5}
    if status != 'ok':
        rec.update(error_kind=kind, error='RuntimeError: boom', traceback='Traceback ...')
    return rec


def test_records_are_written_whole_and_read_back(tmp_path: Path) -> None:
    store = ResultStore(tmp_path / 'exp')
    store.write(record('a', ratio=float('nan')))
    assert store.keys() == {'a'}
    assert store.read('a')['result']['ratio'] is None            # JSON has no NaN
    assert not [p for p in store.trials_dir.iterdir() if not p.name.endswith('.json')]   # no temp left
    (store.trials_dir / '.b.json.123.tmp').write_text('{"half')  # what a kill mid-write could leave
    assert store.keys() == {'a'} and store.read('missing') is None


def test_a_rerun_skips_finished_and_raised_trials_but_not_engine_losses(tmp_path: Path) -> None:
    store = ResultStore(tmp_path / 'exp')
    store.write(record('ok'))
    store.write(record('raised', status='failed', kind='trial'))
    store.write(record('lost', status='failed', kind='engine'))
    assert store.done() == {'ok', 'raised'}
    assert store.done(retry_failed=True) == {'ok'}


def test_summary_is_parquet_with_scalar_columns_and_no_timing(tmp_path: Path) -> None:
    store = ResultStore(tmp_path / 'exp')
    recs = [record('a'), record('b', status='failed')]
    path = store.write_summary(recs)
    frame = pd.read_parquet(path)
    assert list(frame['key']) == ['a', 'b']
    assert 'gliders' not in frame and 'wall_s' not in frame
    assert frame.loc[0, 'grid.alpha_max_deg'] == 90.0
    assert frame.loc[1, 'status'] == 'failed' and 'boom' in frame.loc[1, 'error']
    assert summary_row(recs[0])['positive'] is True


def test_code_version_names_the_package_source_hash_and_libraries() -> None:
    version = code_version()
    assert set(version) >= {'smarticle_experiments', 'source', 'pybullet', 'numpy'}
    assert len(version['source']) == 16 and int(version['source'], 16) >= 0


def test_the_progress_bar_counts_done_running_and_failed(capsys: object) -> None:
    from smarticle_experiments.engine import Progress

    bar = Progress(total=4, slots=2, enabled=True)
    bar.step(failed=False)
    bar.step(failed=True)
    bar.close()
    err = capsys.readouterr().err  # type: ignore[attr-defined]
    assert 'done 1, running 2, failed 1' in err and '2/4' in err
