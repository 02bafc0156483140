"""Reports from stored records (no sim): paper-against-sim rows, intervals, trials left out are listed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from smarticle_experiments.report import write_report
from smarticle_experiments.results import InadmissiblePairResult, P6Result, PairResult, SingleResult
from smarticle_experiments.spec import spec_from_mapping
from smarticle_experiments.store import ResultStore

CODE = {'smarticle_experiments': '0', 'commit': 'abc', 'numpy': '1', 'pybullet': '1'}


def glider(life: int, cls: str, phi: float, ongoing: bool = False, distance: float = 2.9,
           isolated: bool = True) -> dict[str, Any]:
    """A bound pair's record as the dense kind returns it (``GliderRecord``; a glider if ``distance`` W over ``life``
    periods meets the glider rule)."""
    return {'i': 0, 'j': 1, 'class': cls, 'start_period': 0, 'lifetime_periods': life, 'ongoing': ongoing,
            'r_bl': 1.3 if cls == 'C1' else 1.5, 'theta_deg': 10.0, 'phi_deg': phi, 'distance_w': distance,
            'path_w': distance, 'v_com_w_per_period': 0.01, 'beta': 1.8, 'isolated': isolated,
            'isolation': 1.0 if isolated else 0.0, 'com_path_w': [[0.0, 0.0], [0.01, 0.0], [0.02, 0.0]]}


def dense_result(seed: int) -> dict[str, Any]:
    """A synthetic P1 trial: positive for seeds 0..96 (97 of 151), a C1 and a C2 bound pair each (the C2 one and,
    in odd positive seeds, the C1 one travel the glider rule's 1 W per 100 periods)."""
    positive = seed < 97
    gliders = [glider(300 if positive else 40, 'C1', 180.0, ongoing=positive, distance=2.8 + 0.2 * (seed % 2)),
               glider(60 + seed % 40, 'C2', 5.0)]
    return {'periods_run': 300.0, 'trouble': '', 'n_gliders': 2, 'peak_tilt_deg': 0.5 + seed / 100,
            'peak_overlap_mm': 1.0 if seed != 7 else 3.5, 'positive': positive, 'positive_isolated': positive,
            'longest_periods': 300 if positive else 99, 'longest_class': 'C1', 'longest_distance_w': 2.9,
            'gliders': gliders, 'trajectory_bl': [[[0.0, 0.0], [1.0, 0.0]], [[0.1, 0.0], [1.1, 0.0]]],
            'trajectory_dt': 1.6}


def pair_result(gliders: list[dict[str, Any]], **fields: Any) -> dict[str, Any]:
    """A pair trial's stored result (every field of ``PairResult``): a start that stayed apart, with ``fields``
    replaced."""
    base = PairResult(periods_run=75.0, trouble='', peak_tilt_deg=None, peak_overlap_mm=None,
                      n_gliders=len(gliders), positive=False, positive_isolated=False, longest_periods=0,
                      longest_class='', longest_distance_w=None, gliders=[], trajectory_bl=[], trajectory_dt=1.6,
                      r0_bl=1.3, theta0_deg=0.0, phi0_deg=180.0, admissible=True, bound_tail_periods=0,
                      bound_at_end=False, colliding_tail_periods=0, colliding_at_end=False, out_of_reach_at_end=True,
                      late_w=0.0, r_end_bl=3.0, phi_end_deg=180.0).as_dict()
    return {**base, 'gliders': gliders, **fields}


def report_of(spec: Any, folder: Path, result: Any) -> str:
    """The report of ``spec`` with every trial stored as ok with ``result(trial)``."""
    trials = spec.trials(CODE)
    store = ResultStore(folder)
    for t in trials:
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': result(t)})
    return write_report(spec, trials, store, CODE).read_text()


def test_p1_report_puts_the_paper_inside_the_sims_intervals_and_lists_what_it_left_out(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'p1', 'description': 'synthetic', 'kind': 'dense', 'seeds': 153,
                              'report': ['p1', 'trajectories', 'configurations', 'lifetimes'],
                              'paper': {'fraction_bound': 0.64, 'distance_w': 2.9}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'p1')
    for t in trials[:151]:
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': {}, 'status': 'ok',
                     'result': dense_result(t.seed)})
    bad = trials[151]
    store.write({'key': bad.key, 'kind': bad.kind, 'seed': bad.seed, 'point': {}, 'status': 'failed',
                 'error_kind': 'trial', 'error': 'RuntimeError: boom', 'traceback': 'Traceback ...'})
    report = write_report(spec, trials + [], store, CODE).read_text()
    rows = {line.split(' | ')[0].lstrip('| '): line for line in report.splitlines() if line.startswith('| P')}
    fraction = rows['P1 trials with an isolated pair bound >= 100 periods (no third robot within 2 W in >= 90 % '
                    'of its periods)']
    assert '(97/151)' in rows['P1 same, any bound pair (clusters and trains included)']
    assert '64.2% [56.3%, 71.4%] (97/151)' in fraction and '| Wilson |' in fraction and '| yes |' in fraction
    # the paper's claim read with the glider rule: only the odd positive seeds' pairs travel 1 W per 100 periods
    glide = rows['P1 trials with an isolated glider bound >= 100 periods (the pair also travels >= 1 W per 100 '
                 'periods)']
    assert '(48/151)' in glide and '| no |' in glide
    assert '| yes |' in rows['P1 distance travelled by the longest pair bound >= 100 periods (W)']
    assert '| yes |' in rows['P2 both modes present among the bound pairs']
    assert '(102), ' in rows['P2 both modes present among the gliders (bound pairs travelling >= 1 W per 100 periods)']
    assert 'Kaplan-Meier' in rows["P3 C2 bound pairs' median lifetime (periods, Kaplan-Meier)"]
    assert '302 bound pairs (>= 30 periods), 253 of them gliders (>= 1 W per 100 periods)' in report
    assert 'glider: a bound pair whose centre of mass travels >= 1 W per 100 periods' in report
    assert '151 used, 0 ended in sim trouble, 1 failed, 1 not run yet' in report
    assert 'RuntimeError: boom' in report
    assert 'Groups at the end of the run (robots closer than 2 W, single linkage; 151 trials' in report
    assert '| 2 | 151 | 100% [' in report     # the two synthetic robots end 1 W apart: one group of two
    # the 97 positive trials' 300-period C1 gliders (2.8 or 3.0 W); the C2 ones live < 100 periods
    assert '| C1 | 97 | 48 | 1.30 [1.30, 1.30] | 0.93 [0.93, 1.00] | 0 |' in report
    assert '| all | 97 |' in report and '| in a group |' not in report
    assert ('Trouble margins over 151 trials that ran (at their trouble checks): largest body tilt 2.0 deg '
            '(seed 150; median of the trials\' largest 1.2 deg; the limit is 25 deg), deepest contact overlap '
            '3.50 mm (seed 7; trouble is 4 mm at 3 checks in a row)') in report
    for png in ('p1_longest', 'trajectories', 'configurations', 'lifetimes'):
        assert (store.folder / 'report-p1' / f'{png}.png').stat().st_size > 0


def single(drift: float, trouble: str = '') -> dict[str, Any]:
    """A lone robot's stored result (``SingleResult``) with this drift (um per cycle)."""
    return SingleResult(heading_deg=0.0, trouble=trouble, cycles=20, drift_um_per_cycle=drift,
                        step_um_per_cycle=drift).as_dict()


def test_trials_in_sim_trouble_are_counted_and_listed_not_used(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'drift', 'kind': 'single', 'seeds': 4, 'report': ['drift'],
                              'paper': {'drift_um': 75.0}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'drift')
    for t, drift, trouble in zip(trials, [70.0, 74.0, 78.0, 9999.0], ['', '', '', 'sim trouble: robot 0 flipped'],
                                 strict=True):
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': {}, 'status': 'ok',
                     'result': single(drift, trouble)})
    report = write_report(spec, trials, store, CODE).read_text()
    assert '3 used, 1 ended in sim trouble' in report and 'robot 0 flipped' in report
    assert '| 90 | 3 | 74.0 [' in report       # the trouble trial's 9999 is not in the mean


def test_drift_is_reported_per_amplitude_and_per_other_grid_setting(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'amp', 'kind': 'single', 'seeds': 3, 'report': ['drift'],
                              'grid': {'alpha_max_deg': [10, 90], 'physics.tilt_inertia_scale': [1.0, 100.0]}})

    def result(t: Any) -> dict[str, Any]:
        scale = t.point['physics.tilt_inertia_scale']
        drift = (115.0 if scale == 1.0 else 18.0) if t.point['alpha_max_deg'] == 10 else 114.0
        return single(drift + t.seed)

    report = report_of(spec, tmp_path / 'amp', result)
    assert '| physics.tilt_inertia_scale | alpha_max (deg) | robots | drift (um / cycle) [95 %] |' in report
    assert '| 1.0 | 10 | 3 | 116.0 [' in report and '| 100.0 | 10 | 3 | 19.0 [' in report
    assert '| 100.0 | 90 | 3 | 115.0 [' in report
    assert 'P7 drift per cycle at 90 deg (um) (physics.tilt_inertia_scale 1.0)' in report
    assert 'P7 drift per cycle at 90 deg (um) (physics.tilt_inertia_scale 100.0)' in report
    assert (tmp_path / 'amp' / 'report-amp' / 'drift.png').stat().st_size > 0


def test_the_report_draws_every_section_a_built_in_kind_feeds_and_no_other() -> None:
    from smarticle_experiments.kinds import KINDS
    from smarticle_experiments.report import SECTIONS

    fed = {s for kind in KINDS.values() if kind.modules[0].startswith('smarticle_experiments.kinds.')
           for s in kind.all_sections()}
    assert fed == set(SECTIONS)


def test_seeds_are_listed_as_runs() -> None:
    from smarticle_experiments.report import seed_ranges

    assert seed_ranges([]) == '-'
    assert seed_ranges([7]) == '7'
    assert seed_ranges([0, 1]) == '0, 1'
    assert seed_ranges([1000, 1001, *range(1003, 1022), 1023]) == '1000, 1001, 1003..1021, 1023'
    assert seed_ranges(list(range(151))) == '0..150'


def test_the_contacts_section_counts_touching_gliders(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'touch', 'kind': 'dense', 'seeds': 4, 'report': ['contacts'],
                              'params': {'contacts': True}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'touch')
    for t, share in zip(trials, [0.0, 0.2, 0.9, 1.0], strict=True):
        result = dense_result(t.seed)
        for g in result['gliders']:
            g['contact_fraction'] = share
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': {}, 'status': 'ok', 'result': result})
    report = write_report(spec, trials, store, CODE).read_text()
    assert '| all | 8 | 6 | 50% [' in report       # 4 of 8 bound pairs touch in >= 50 % of their periods, 6 glide
    assert '| C2 | 4 | 4 | 50% [' in report and '| 25% |' in report   # one trial's pairs never touched
    assert '| any | 100.0% [' in report and '| touching | 50.0% [' in report
    assert (store.folder / 'report-touch' / 'contacts.png').stat().st_size > 0


def test_step_convergence_compares_each_step_with_the_finest(tmp_path: Path) -> None:
    """A bound pair's r and travel per 100 periods against the time step; off by more than 10 % and outside
    the intervals is not converged, the finest step is the reference."""
    steps = [1 / 480, 1 / 960, 1 / 1920]
    spec = spec_from_mapping({'name': 'conv', 'kind': 'pair', 'seeds': 6, 'report': ['step_convergence'],
                              'grid': {'physics.time_step': steps}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'conv')
    travel = {1 / 480: 2.0, 1 / 960: 3.85, 1 / 1920: 4.0}     # W per 100 periods
    for t in trials:
        dt = t.params['physics']['time_step']
        g = {**glider(150, 'C1', 180.0), 'r_bl': 1.50 + 0.01 * (t.seed % 3),
             'v_com_w_per_period': travel[dt] / 100.0 + 0.0005 * (t.seed % 3)}
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': pair_result([g])})
    report = write_report(spec, trials, store, CODE).read_text()
    rows = {line.split(' | ')[0].lstrip('| '): line for line in report.splitlines() if line.startswith('| 1/')}
    assert all(' | 10 | 1e-07 | ' in row for row in rows.values())    # the default's solver and Bullet's threshold
    assert rows['1/1920 s'].endswith('| (reference) |')
    assert '| -3.7% |' in rows['1/960 s'] and rows['1/960 s'].endswith('| yes |')
    assert '| -49.4% |' in rows['1/480 s'] and rows['1/480 s'].endswith('| no |')
    assert '| 6/6 |' in rows['1/480 s'] and '| +0.0% |' in rows['1/480 s']      # r is the same at every step
    assert (store.folder / 'report-conv' / 'step_convergence.png').stat().st_size > 0


def test_step_convergence_takes_the_strictest_residual_threshold_as_the_reference(tmp_path: Path) -> None:
    """At one step and one iteration cap, a solver that stops early (a residual threshold) is compared with
    the one that does not (Bullet's own threshold), which is the reference."""
    spec = spec_from_mapping({'name': 'early', 'kind': 'pair', 'seeds': 4, 'report': ['step_convergence'],
                              'grid': {'physics.solver_residual_threshold': [1e-4, 1e-5]}})
    extra = spec_from_mapping({'name': 'early', 'kind': 'pair', 'seeds': 4, 'report': ['step_convergence']})
    trials = spec.trials(CODE) + extra.trials(CODE)
    store = ResultStore(tmp_path / 'early')
    travel = {1e-4: 4.0, 1e-5: 3.1, None: 3.0}
    for t in trials:
        threshold = t.params.get('physics', {}).get('solver_residual_threshold')
        g = {**glider(150, 'C1', 180.0), 'r_bl': 1.50, 'v_com_w_per_period': travel[threshold] / 100.0}
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': pair_result([g])})
    report = write_report(spec, trials, store, CODE).read_text()
    rows = [line for line in report.splitlines() if line.startswith('| 1/960 s')]
    assert [row.split(' | ')[2] for row in rows] == ['1e-04', '1e-05', '1e-07']
    assert rows[0].endswith('| no |') and '| +33.3% |' in rows[0]
    assert rows[1].endswith('| yes |') and rows[2].endswith('| (reference) |')


def test_step_convergence_gives_each_other_setting_its_own_reference(tmp_path: Path) -> None:
    """A grid over more than the solver (here the restitution) gives one block per setting, each compared with
    its own finest step, not with another setting's."""
    spec = spec_from_mapping({'name': 'parts', 'kind': 'pair', 'seeds': 4, 'report': ['step_convergence'],
                              'grid': {'physics.restitution': [0.0, 0.8], 'physics.time_step': [1 / 960, 1 / 3840]}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'parts')
    travel = {(0.0, 1 / 960): 1.66, (0.0, 1 / 3840): 1.59, (0.8, 1 / 960): 4.12, (0.8, 1 / 3840): 3.29}
    for t in trials:
        physics = t.params['physics']
        g = {**glider(150, 'C1', 180.0), 'r_bl': 1.50,
             'v_com_w_per_period': travel[(physics['restitution'], physics['time_step'])] / 100.0}
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': pair_result([g])})
    report = write_report(spec, trials, store, CODE).read_text()
    assert '| physics.restitution | time step | solver iterations |' in report
    rows = [line for line in report.splitlines() if line.startswith(('| 0.0 |', '| 0.8 |'))]
    assert [row.split(' | ')[:2] for row in rows] == [['| 0.0', '1/960 s'], ['| 0.0', '1/3840 s'],
                                                      ['| 0.8', '1/960 s'], ['| 0.8', '1/3840 s']]
    assert '| +4.4% |' in rows[0] and rows[0].endswith('| yes |') and rows[1].endswith('| (reference) |')
    assert '| +25.2% |' in rows[2] and rows[2].endswith('| no |') and rows[3].endswith('| (reference) |')
    assert 'of each setting' in report
    assert (store.folder / 'report-parts' / 'step_convergence.png').stat().st_size > 0


def test_end_groups_link_robots_through_their_neighbours() -> None:
    import numpy as np

    from smarticle_experiments.report import end_groups

    # a chain 0-1-2 (each link 1.5 W, the ends 3 W apart), a pair 3-4, a loner 5, a robot off the plate (NaN)
    xy = np.array([[0.0, 0.0], [1.5, 0.0], [3.0, 0.0], [10.0, 0.0], [10.0, 1.9], [20.0, 20.0], [np.nan, np.nan]])
    assert end_groups(xy, 2.0) == (3, 2, 1)
    assert end_groups(xy, 1.0) == (1, 1, 1, 1, 1, 1)


def test_the_basin_counts_a_start_bound_only_if_it_keeps_colliding_and_repelled_only_out_of_reach(
        tmp_path: Path) -> None:
    """P4's rule: bound = in contact in each of the last periods; repelled = out of reach at the
    end; a pair within reach that does not collide every period (e.g. two in-phase robots drifting side by
    side) is neither, though the earlier rule (r < r_bind or contact) counted it bound."""
    from smarticle_experiments.report import basin_outcome

    spec = spec_from_mapping({'name': 'p4', 'kind': 'pair', 'seeds': [0], 'report': ['basin'],
                              'analysis': {'bound_tail': 5},
                              'grid': {'phase2': [0.0], 'theta_deg': [30, 150], 'phi_deg': [0, 180]}})
    trials = spec.trials(CODE)
    outcomes = {(30, 180): dict(colliding_at_end=True, out_of_reach_at_end=False, bound_at_end=True),
                (30, 0): dict(colliding_at_end=False, out_of_reach_at_end=False, bound_at_end=True),
                (150, 180): dict(colliding_at_end=False, out_of_reach_at_end=True, bound_at_end=False),
                (150, 0): None}
    store = ResultStore(tmp_path / 'p4')
    for t in trials:
        fields = outcomes[(int(t.params['theta_deg']), int(t.params['phi_deg']))]
        result = InadmissiblePairResult(r0_bl=1.3, theta0_deg=150.0, phi0_deg=0.0, admissible=False, why='overlap',
                                        trouble='', gliders=[]).as_dict() if fields is None else \
            pair_result([], r_end_bl=1.4, **fields)
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': result})
    report = write_report(spec, trials, store, CODE).read_text()
    assert ('4 starts, 3 admissible: 1 bound (in contact in each of the last 5 periods: the pair keeps colliding '
            'to the end), 1 repelled') in report and '1 neither' in report
    assert 'By the earlier rule (r < r_bind or contact in each of the last 5 periods) 2 were bound.' in report
    assert '| theta in quadrants 1, 4 | 1/2 (' in report and '| theta in quadrants 2, 3 | 0/1 (' in report
    assert '| parallel normals (phi 0) | 0/1 (' in report
    # Fisher's exact test of 1/2 against 0/1, for the quadrants and for the normal bands alike
    assert 'phase 0: quadrants p = 1, normals p = 1; all phases: quadrants p = 1, normals p = 1.' in report
    within_reach = PairResult.from_dict(pair_result([], bound_at_end=True, out_of_reach_at_end=False))
    assert basin_outcome(within_reach) == 'neither'   # the earlier rule's 'bound' is not enough


def test_the_p6_report_gives_means_and_a_log_rank_test_of_open_loop_against_feedback(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'p6x', 'description': 'synthetic', 'kind': 'p6', 'periods': 200, 'seeds': 6,
                              'grid': [{'alpha_max_deg': [90], 'feedback': [False, True]}], 'report': ['p6']})

    def result(t: Any) -> dict[str, Any]:
        feedback = bool(t.params['feedback'])
        life = 200 if feedback and t.seed < 4 else 20 + 10 * t.seed     # feedback: 4 of 6 reach the end
        return {'lifetime_periods': life, 'censored': life == 200, 'halts': 3 if feedback else 0, 'trouble': '',
                'r0_bl': 1.0, 'theta0_deg': 90.0, 'phi0_deg': 5.0, 'final_r_bl': 1.0}

    report = report_of(spec, tmp_path / 'p6x', result)
    assert '| open loop 90 deg | 6 | 0 |' in report and '| 45.0 +- 7.6 | 0.0 |' in report
    assert '| feedback 90 deg | 6 | 4 |' in report and '| 155.0 +- 28.5 | 3.0 |' in report
    line = next(x for x in report.splitlines() if x.startswith('Log-rank'))
    assert 'at 90 deg' in line and 'mean lifetime ratio feedback / open loop 3.44' in line
    p = float(line.split('p = ')[1].split(';')[0])
    assert p < 0.01, line
    assert 'Travel is not stored for these trials (run without `details`)' in report


def test_the_p6_report_gives_one_row_per_grid_setting_and_compares_within_it(tmp_path: Path) -> None:
    spec = spec_from_mapping({'name': 'p6y', 'description': 'synthetic', 'kind': 'p6', 'periods': 100, 'seeds': 4,
                              'noise': {'clock_rate_sd': 0.003},
                              'grid': [{'alpha_max_deg': [90], 'feedback': [False, True],
                                        'noise.clock_rate_sd': [0.0, 0.003]}], 'report': ['p6']})
    # no clock noise: every pair reaches the end; with it, feedback lives 5 periods longer in every seed
    lives = {t.key: 100 if t.point['noise.clock_rate_sd'] == 0.0 else 30 + t.seed + 5 * bool(t.params['feedback'])
             for t in spec.trials(CODE)}
    report = report_of(spec, tmp_path / 'p6y', lambda t: P6Result(
        lifetime_periods=lives[t.key], censored=lives[t.key] == 100, halts=0, trouble='', r0_bl=1.47, theta0_deg=99.0,
        phi0_deg=7.0, final_r_bl=1.5).as_dict())
    assert '| noise.clock_rate_sd | condition | trials |' in report
    assert '| 0.0 | open loop 90 deg | 4 | 4 |' in report and '| 0.003 | open loop 90 deg | 4 | 0 |' in report
    assert '| 0.003 | open loop 90 deg | 4 | 0 | 31 [30, ?] | 31.5 +- 0.6 |' in report
    assert '| 0.003 | feedback 90 deg | 4 | 0 | 36 [35, ?] | 36.5 +- 0.6 |' in report
    assert 'at 90 deg, noise.clock_rate_sd 0.0: every pair reached the end, no test.' in report
    logranks = [x for x in report.splitlines() if x.startswith('Log-rank')]
    assert len(logranks) == 1 and 'noise.clock_rate_sd 0.003: ' in logranks[0]
    assert 'ratio feedback / open loop 1.16' in logranks[0]


def test_pair_paths_show_which_setting_makes_pairs_travel(tmp_path: Path) -> None:
    """One row and one panel per grid setting: the pair centre's net travel and how the pairs ended."""
    spec = spec_from_mapping({'name': 'paths', 'kind': 'pair', 'seeds': 3, 'report': ['pair_paths'],
                              'grid': {'phase2': [0.0, 0.1]}})

    def result(t: Any) -> dict[str, Any]:
        step = 0.03 if t.point['phase2'] else 0.0       # W per period of the pair's centre
        path = [[[k * step, 0.0], [k * step, 1.5]] for k in range(101)]   # two robots 1.5 BL apart
        return pair_result([], trajectory_bl=path, r_end_bl=1.5, phi_end_deg=180.0)

    report = report_of(spec, tmp_path / 'paths', result)
    rows = {line.split(' | ')[0].lstrip('| '): line for line in report.splitlines() if line.startswith('| 0.')}
    assert '| 3 | 3.00 [3.00, 3.00] | 3.00, 3.00, 3.00 |' in rows['0.1']
    assert '| 3 | 0.00 [0.00, 0.00] | 0.00, 0.00, 0.00 | 1.50, 1.50, 1.50 | 180.0, 180.0, 180.0 |' in rows['0.0']
    assert (tmp_path / 'paths' / 'report-paths' / 'pair_paths.png').stat().st_size > 0


def test_step_convergence_reads_a_mujoco_trial_s_own_step(tmp_path: Path) -> None:
    """The MuJoCo kinds are stepped at ``MujocoSettings.time_step`` with no Bullet solver: their rows give
    that step (the finest the reference), not the Bullet physics' step and iterations the spec also carries."""
    spec = spec_from_mapping({'name': 'mj', 'kind': 'pair_mujoco', 'seeds': 2, 'report': ['step_convergence'],
                              'grid': {'mujoco.time_step': [1 / 4800, 1 / 9600]}})
    trials = spec.trials(CODE)
    store = ResultStore(tmp_path / 'mj')
    travel = {1 / 4800: 5.8, 1 / 9600: 1.5}
    for t in trials:
        g = {**glider(100, 'C1', 180.0), 'r_bl': 1.50,
             'v_com_w_per_period': travel[t.params['mujoco']['time_step']] / 100.0}
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': dict(t.point), 'status': 'ok',
                     'result': pair_result([g])})
    report = write_report(spec, trials, store, CODE).read_text()
    rows = [line for line in report.splitlines() if line.startswith('| 1/')]
    assert [row.split(' | ')[0] for row in rows] == ['| 1/4800 s', '| 1/9600 s']
    assert all(' | - (MuJoCo) | - | ' in row for row in rows)
    assert rows[0].endswith('| no |') and rows[1].endswith('| (reference) |')


def test_a_still_bound_pair_and_a_travelling_one_are_one_bound_pair_and_one_glider(tmp_path: Path) -> None:
    """The report's words are the glider analysis's: a pair bound >= K periods that travels less than 1 W per 100
    periods is a bound pair, not a glider; P1's paper row asks its isolated pair to be a glider."""
    spec = spec_from_mapping({'name': 'words', 'kind': 'dense', 'seeds': 1,
                              'report': ['p1', 'configurations', 'lifetimes']})
    still = glider(200, 'C1', 180.0, distance=0.2)                          # 0.1 W per 100 periods, isolated
    travelling = {**glider(150, 'C2', 5.0, distance=3.0, isolated=False), 'i': 2, 'j': 3}   # 2 W per 100 periods

    def result(t: Any) -> dict[str, Any]:
        return {**dense_result(t.seed), 'positive': True, 'positive_isolated': True, 'longest_periods': 200,
                'gliders': [still, travelling]}

    report = report_of(spec, tmp_path / 'words', result)
    assert report.count('2 bound pairs (>= 30 periods), 1 of them glider (>= 1 W per 100 periods)') == 3
    assert '| all | 2 | 1 | ' in report and '| C1 | 1 | 0 | ' in report and '| C2 | 1 | 1 | ' in report
    rows = {line.split(' | ')[0].lstrip('| '): line for line in report.splitlines() if line.startswith('| P')}
    assert '(1/1)' in rows['P1 trials with an isolated pair bound >= 100 periods (no third robot within 2 W in >= 90 % '
                           'of its periods)']
    assert '(0/1)' in rows['P1 trials with an isolated glider bound >= 100 periods (the pair also travels >= 1 W '
                           'per 100 periods)']     # the isolated pair is still, the glider is in a group
    assert 'C1 (0), ' in rows['P2 both modes present among the gliders (bound pairs travelling >= 1 W per 100 '
                              'periods)'] and 'C2 (1) of 1 glider |' in report


def test_the_p6_report_counts_the_gliders_among_the_pairs_when_their_travel_is_stored(tmp_path: Path) -> None:
    """With ``details`` a P6 pair stores its travel: a pair bound >= 30 periods that travels 1 W per 100 periods is
    a glider, one that stays put or breaks before 30 periods is not."""
    spec = spec_from_mapping({'name': 'p6d', 'description': 'synthetic', 'kind': 'p6', 'periods': 100, 'seeds': 3,
                              'grid': [{'alpha_max_deg': [90], 'feedback': [False]}], 'report': ['p6']})
    runs = {0: (100, 1.5), 1: (100, 0.2), 2: (20, 1.0)}     # seed: (bound periods, travel W)

    def result(t: Any) -> dict[str, Any]:
        life, travel = runs[t.seed]
        return P6Result(lifetime_periods=life, censored=life == 100, halts=0, trouble='', r0_bl=1.47,
                        theta0_deg=99.0, phi0_deg=7.0, final_r_bl=1.5, travel_w=travel,
                        contact_periods=[1, 2]).as_dict()

    report = report_of(spec, tmp_path / 'p6d', result)
    row = next(x for x in report.splitlines() if x.startswith('| open loop 90 deg | - |'))
    assert '| 1 of 3 |' in row, row
    assert 'Travel is not stored' not in report
