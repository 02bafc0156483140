"""P4's quadrants: one rule for the paper-against-sim row, the basin table and its Fisher tests."""

from __future__ import annotations

from pathlib import Path

from smarticle_experiments.report import antiparallel_band, theta_quadrants, write_report
from smarticle_experiments.spec import spec_from_mapping
from smarticle_experiments.store import ResultStore

from .test_report import CODE, pair_result


def test_theta_on_an_axis_counts_in_the_quadrant_pair_either_side_of_it() -> None:
    assert [theta_quadrants(t) for t in (0, 45, 360, -30, 315)] == ['1, 4'] * 5
    assert [theta_quadrants(t) for t in (180, 135, 225, -180)] == ['2, 3'] * 4
    assert [theta_quadrants(t) for t in (90, 270, -90, 450)] == [None] * 4     # the line between the pairs
    assert antiparallel_band(90) and antiparallel_band(270) and antiparallel_band(-180)
    assert not antiparallel_band(0) and not antiparallel_band(300)


def test_the_p4_row_the_table_and_the_fisher_test_count_theta_0_alike(tmp_path: Path) -> None:
    """Starts at theta 0, 45, 90, 180 and 270 (phi 180): all bound but the one at 180. theta 0 is in quadrants
    1, 4 in the row (2 of the 4 bound starts) and in the table (2 of 2) alike; 90 and 270 in neither."""
    spec = spec_from_mapping({'name': 'p4', 'kind': 'pair', 'seeds': [0], 'report': ['basin'],
                              'analysis': {'bound_tail': 5},
                              'grid': {'phase2': [0.0], 'theta_deg': [0, 45, 90, 180, 270], 'phi_deg': [180]}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'p4')
    for t in trials:
        bound = int(t.params['theta_deg']) != 180
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': pair_result([], colliding_at_end=bound, out_of_reach_at_end=not bound)})
    report = write_report(spec, trials, store, CODE).read_text()
    row = next(line for line in report.splitlines() if line.startswith('| P4 bound starts with theta in quadrants'))
    assert '(2/4)' in row, row
    assert '| theta in quadrants 1, 4 | 2/2 (' in report and '| theta in quadrants 2, 3 | 0/1 (' in report
    assert 'phase 0: quadrants p = 0.33' in report        # Fisher's exact test of 2/2 against 0/1
    assert 'theta 0 counts in quadrants 1, 4 and theta 180 in 2, 3' in report
