"""The sim path with the batch core (deterministic): Runner + gait controller + the impact controller through
GaitController.halt, and the calibration tool on a recorded run."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from smarticle_common.topics import FSR_FACES
from smarticle_common.runs import Recording, save_npz

from smarticle_feedback import impact_window
from smarticle_experiments.p6 import C2_START, COLLIDING_START, Condition, c2_start, p6_noise, run_pair_trial, summarize


@pytest.fixture(scope='module')
def feedback_trials() -> tuple:
    """The same seed twice with feedback, once open loop (4 periods each), from the start that collides at once."""
    fb = Condition(90.0, True)
    return (run_pair_trial(fb, 1, 4, base=COLLIDING_START), run_pair_trial(fb, 1, 4, base=COLLIDING_START),
            run_pair_trial(Condition(90.0, False), 1, 4, base=COLLIDING_START))


def test_the_batch_feedback_path_is_deterministic(feedback_trials: tuple) -> None:
    a, b, _ = feedback_trials
    assert a.halts == b.halts
    np.testing.assert_array_equal(a.r, b.r)


def test_c2_collisions_halt_each_robot_at_most_once_per_period(feedback_trials: tuple) -> None:
    fb, _, open_loop = feedback_trials
    assert fb.halts, 'the compressed C2 start must produce impacts inside the default window'
    assert not open_loop.halts
    periods = [(robot, math.floor(t / 1.6 + phase)) for t, robot, _ in fb.halts
               for phase in [COLLIDING_START[3][robot]]]
    assert len(periods) == len(set(periods)), periods
    assert all(face in FSR_FACES for _, _, face in fb.halts)
    assert not np.array_equal(fb.r, open_loop.r), 'halting changes the pair dynamics'
    rows = summarize([fb, open_loop], 4)
    assert [row['n'] for row in rows] == [1, 1]


def test_the_harvested_c2_start_touches_only_when_the_clocks_drift() -> None:
    """In phase and noise-free the harvested C2 pair does not touch; its clocks (noise) bring it into contact,
    and a noisy trial repeats exactly for its seed."""
    quiet = run_pair_trial(Condition(90.0, False), 2, 12, count_contacts=True)
    assert quiet.contact_periods == [] and quiet.censored and quiet.lifetime_periods == 13
    noisy = [run_pair_trial(Condition(90.0, True), 2, 30, count_contacts=True, noise=p6_noise('paper'))
             for _ in range(2)]
    assert noisy[0].contact_periods, 'seed 2: the gait clocks bring the pair into contact within 30 periods'
    np.testing.assert_array_equal(noisy[0].r, noisy[1].r)
    assert noisy[0].halts == noisy[1].halts
    assert C2_START[3] == (0.0, 0.0)


def test_the_held_c2_start_is_a_shipped_glider_state_that_touches_from_its_first_period() -> None:
    """The held start places the pair at a recorded state of a collision-held C2 (seeded pick), bound and in
    contact from period 0, and a trial repeats exactly for its seed."""
    from smarticle_experiments.p6 import HELD, load_held_starts

    starts = load_held_starts()
    assert len(starts) >= 40 and all(s.touched and s.state is not None for s in starts)
    runs = [run_pair_trial(Condition(90.0, False), 3, 3, count_contacts=True, base=HELD) for _ in range(2)]
    trial = runs[0]
    assert trial.start in {(s.r_bl, s.theta_deg, s.phi_deg) for s in starts}
    assert trial.r[0] == pytest.approx(trial.start[0], abs=1e-4)    # placed where the dense trial had it
    assert trial.contact_periods[:1] == [0] and trial.lifetime_periods >= 3
    np.testing.assert_array_equal(trial.r, runs[1].r)
    other = run_pair_trial(Condition(90.0, False), 4, 1, base=HELD)
    assert other.start != trial.start, 'seeds 3 and 4 draw different shipped starts'


def test_seeds_jitter_the_start_slightly() -> None:
    base = c2_start(0)
    for seed in range(1, 6):
        r, theta, phi = c2_start(seed)
        assert abs(r - base[0]) <= 0.04 and abs(theta - base[1]) <= 4.0 and abs(phi - base[2]) <= 4.0
    assert c2_start(3) == c2_start(3) != c2_start(4)
    assert c2_start(0, attempt=1) != c2_start(0) and c2_start(3, attempt=2) == c2_start(3, attempt=2)


def make_recording(forces: np.ndarray, contacts: np.ndarray, fsr_recorded: bool = True) -> Recording:
    s, n = forces.shape[:2]
    poses = np.zeros((s, n, 3))
    return Recording(np.arange(s) * 0.05, poses, np.zeros((s, n, 2)), forces, contacts, 0.065,
                     {'fsr_recorded': fsr_recorded, 'contacts_recorded': fsr_recorded})


def test_calibration_suggests_a_window_from_collision_forces(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    forces = np.zeros((200, 2, 4))
    forces[:100, :, 1] = rng.uniform(1.0, 3.0, size=(100, 2))     # collisions on arm1_back
    forces[100:, :, 2] = 9.0                                       # forces without contact: not counted
    contacts = np.zeros((200, 2, 2), dtype=bool)
    contacts[:100, 0, 1] = contacts[:100, 1, 0] = True
    path = save_npz(make_recording(forces, contacts), tmp_path / 'run.npz')
    suggestion = impact_window.calibrate_recording(path, low=0.0, high=100.0)
    assert suggestion.faces[1].count == 200 and suggestion.faces[2].count == 0
    assert 1.0 <= suggestion.f_min < 1.05 and 2.95 < suggestion.f_max <= 3.0
    png = tmp_path / 'window.png'
    assert impact_window.main([str(path), '--png', str(png)]) == 0
    assert png.stat().st_size > 1000


def test_calibration_refuses_a_run_without_fsr(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    empty = make_recording(np.zeros((5, 2, 4)), np.zeros((5, 2, 2), dtype=bool), fsr_recorded=False)
    path = save_npz(empty, tmp_path / 'nofsr.npz')
    assert impact_window.main([str(path)]) == 2
    assert 'smarticle-sim run ... --fsr' in capsys.readouterr().err
