"""Adding a trial kind is one file plus a spec: a kind registered from the tests runs through the engine (a real
LocalCluster), the store and the report, with its typed parameters checked when the spec loads."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from smarticle_experiments.errors import SpecError
from smarticle_experiments.harness import RunOptions, run_spec
from smarticle_experiments.kind import KINDS
from smarticle_experiments.kinds import read_result
from smarticle_experiments.report import write_report
from smarticle_experiments.spec import spec_from_mapping

from . import toy_kind

SPEC = {'name': 'toy', 'kind': 'toy', 'periods': 3, 'params': {'scale': 0.5}, 'grid': {'scale': [1.0, 3.0]},
        'seeds': 2, 'report': ['toy']}


@pytest.fixture
def toy() -> Iterator[None]:
    """The toy kind registered (its module did it on import) and forgotten after the test."""
    KINDS.add(toy_kind.TOY)
    yield
    KINDS.remove('toy')


@pytest.mark.slow
def test_a_kind_from_one_file_runs_through_the_engine_the_store_and_the_report(toy: None, tmp_path: Path) -> None:
    spec = spec_from_mapping(SPEC)
    assert 'toy' in KINDS and KINDS['toy'].modules == ('tests.smarticle_experiments.toy_kind',)
    trials, store, code = run_spec(spec, RunOptions(out=tmp_path, workers=1, retries=0, progress=False))
    records = {r['key']: r for r in store.records(t.key for t in trials)}
    assert len(records) == 4 and all(r['status'] == 'ok' for r in records.values())
    for t in trials:   # the worker found the kind, ran its typed parameters and stored them as the trial's
        record = records[t.key]
        assert record['params'] == {'scale': t.params['scale'], 'periods': 3.0}
        assert read_result('toy', record['result']) == toy_kind.ToyResult(t.params['scale'] * t.seed + 3.0, '')
    report = write_report(spec, trials, store, code).read_text()
    assert '## toy' in report and '4 toy trials, mean value 4.00' in report


def test_a_kinds_parameters_check_themselves_when_the_spec_loads(toy: None) -> None:
    with pytest.raises(SpecError, match=r"^toy: kind toy: scale must be > 0, got -1.0 at grid point \{'scale': -1\}$"):
        spec_from_mapping({**SPEC, 'grid': {'scale': [-1]}})
    with pytest.raises(SpecError, match="unknown key params.size for kind 'toy'"):
        spec_from_mapping({**SPEC, 'params': {'size': 1}})
    with pytest.raises(SpecError, match="unknown report section 'p1' for kind 'toy' \\(known: toy\\)"):
        spec_from_mapping({**SPEC, 'report': ['p1']})
