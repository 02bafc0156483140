"""The Bullet-against-MuJoCo table's rules applied to stores written here
(tools/chrono_reference/bullet_mujoco_table.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _table() -> ModuleType:
    spec = importlib.util.spec_from_file_location('bullet_mujoco_table',
                                                  ROOT / 'tools' / 'chrono_reference' / 'bullet_mujoco_table.py')
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _store(root: Path, row: str, engine: str, rows: list[dict[str, object]]) -> None:
    folder = root / f'xengine_{row}'
    folder.mkdir(parents=True, exist_ok=True)
    frame = pd.DataFrame([{'status': 'ok', 'trouble': '', **r} for r in rows])
    frame.to_parquet(folder / f'summary-xengine_{row}_{engine}.parquet')


def test_p7_agrees_within_a_factor_of_two_or_when_both_are_still(tmp_path: Path) -> None:
    table = _table()
    drift = {'bullet': {90: 100.0, 45: 40.0, 10: 100.0}, 'mujoco': {90: 190.0, 45: 10.0, 10: 250.0}}
    for engine, by_alpha in drift.items():
        _store(tmp_path, 'p7', engine, [{'grid.alpha_max_deg': a, 'drift_um_per_cycle': d + s}
                                        for a, d in by_alpha.items() for s in (-1.0, 0.0, 1.0)])
    rows = table.p7_rows(tmp_path)
    assert [r.split('|')[4].split()[0] for r in rows[:3]] == ['agree', 'agree', 'disagree']   # 90, 45, 10
    assert '**disagrees** (2 of 3 amplitudes agree)' in rows[3]


def test_p6_effect_signs_and_the_rows_that_are_not_decided(tmp_path: Path) -> None:
    table = _table()

    def trials(open_loop: list[int], feedback: list[int], halts: int) -> list[dict[str, object]]:
        return ([{'grid.feedback': False, 'lifetime_periods': x, 'censored': x >= 200, 'halts': 0} for x in open_loop]
                + [{'grid.feedback': True, 'lifetime_periods': x, 'censored': x >= 200, 'halts': halts}
                   for x in feedback])

    _store(tmp_path, 'p6', 'bullet', trials([50, 55, 60, 52], [50, 56, 59, 53], 3))
    _store(tmp_path, 'p6', 'mujoco', trials([40, 42, 41, 43], [90, 95, 92, 94], 2))
    rows = table.p6_rows(tmp_path)
    assert 'disagree' in rows[1] and '**effect disagrees**' in rows[2]         # 0 in Bullet's interval only
    _store(tmp_path, 'p6', 'mujoco', trials([40, 42, 41, 43], [40, 43, 41, 42], 0))
    assert 'not decided (mujoco: no halt)' in table.p6_rows(tmp_path)[2]


def test_p1_share_by_fisher_and_a_missing_run(tmp_path: Path) -> None:
    table = _table()
    assert table.p1_rows(tmp_path) == ['| P1 reduced | not run | | |']
    _store(tmp_path, 'p1', 'bullet', [{'positive': k < 3, 'n_gliders': 1} for k in range(30)])
    _store(tmp_path, 'p1', 'mujoco', [{'positive': k < 20, 'n_gliders': 3} for k in range(30)])
    share, pairs = table.p1_rows(tmp_path)
    assert '3/30' in share and '20/30' in share and '**share disagrees**' in share
    assert pairs.endswith('| disagree |')


def test_a_row_with_too_many_troubled_trials_is_not_decided(tmp_path: Path) -> None:
    table = _table()
    for engine in ('bullet', 'mujoco'):
        _store(tmp_path, 'p1', engine, [{'positive': True, 'n_gliders': 1, 'trouble': 'tilt' if k < 4 else ''}
                                        for k in range(30)])
    assert 'not decided (bullet: 4 of 30 in trouble; mujoco: 4 of 30 in trouble)' in table.p1_rows(tmp_path)[0]


@pytest.mark.parametrize('values, expected', [([1.0, 1.0, 1.0], (1.0, 1.0, 1.0)), ([], None)])
def test_bootstrap_mean_is_seeded(values: list[float], expected: tuple[float, float, float] | None) -> None:
    table = _table()
    got = table.bootstrap_mean(values)
    if expected is None:
        assert all(x != x for x in got)
    else:
        assert got == expected and table.bootstrap_mean([1.0, 2.0, 5.0]) == table.bootstrap_mean([1.0, 2.0, 5.0])
