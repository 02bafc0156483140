"""Gait clocks from arm data (``smarticle_tracking.clocks``): the square gait of a board whose clock runs fast or
slow, sampled as joint commands and joint states: the true rate inside the interval, the phase within its own."""

from __future__ import annotations

import numpy as np
import pytest

from smarticle_common.gait import GaitConfig, SquareGait, TIME_EPS, board_time, open_loop_angles
from smarticle_tracking.clocks import ClockError, estimate_clock, fit_clock, format_clocks

PERIOD = 1.6
START = 0.5


def commands(rate: float, phase: float, tick: float, seconds: float, halts: tuple[float, ...] = ()) -> tuple[
        np.ndarray, np.ndarray]:
    """Joint command targets (T, 2) of a gait node whose clock runs at ``rate``, published every ``tick`` s."""
    gait = SquareGait(GaitConfig(period=PERIOD, phase=phase))
    gait.start(START)
    stamps = np.arange(0.0, seconds, tick)
    targets = np.empty((len(stamps), 2))
    pending = list(halts)
    for i, t in enumerate(stamps):
        if pending and t >= pending[0]:
            gait.halt(board_time(t, START, rate))
            pending.pop(0)
        targets[i] = gait.command(board_time(t, START, rate) + TIME_EPS).targets
    return stamps, targets


def states(rate: float, phase: float, dt: float, seconds: float, noise: float, seed: int) -> tuple[
        np.ndarray, np.ndarray, np.ndarray]:
    """Arm angles (T, 2) and velocities of the open-loop gait at ``rate``, sampled every ``dt`` s with noise (rad)."""
    config = GaitConfig(period=PERIOD, phase=phase)
    rng = np.random.default_rng(seed)
    stamps = np.arange(START, seconds, dt) + rng.uniform(0.0, dt)
    angles = np.array([open_loop_angles(config, (t - START) * rate / PERIOD + phase) for t in stamps])
    return stamps, angles + rng.normal(0.0, noise, angles.shape), np.full(angles.shape, np.nan)


def phase_error(estimate: float, truth: float) -> float:
    """Distance of two phases on the circle (periods)."""
    return abs((estimate - truth + 0.5) % 1.0 - 0.5)


@pytest.mark.parametrize(('rate', 'phase', 'tick'), [(1.0, 0.0, 0.02), (1.004, 0.0, 0.02), (0.997, 0.1, 0.02),
                                                     (1.0025, 0.35, 1 / 60), (0.9985, 0.8, 0.05)])
def test_commands_give_the_true_rate_and_phase(rate: float, phase: float, tick: float) -> None:
    stamps, targets = commands(rate, phase, tick, 60.0)
    clock = estimate_clock(stamps, targets, 'commands', PERIOD, start=START)
    lo, hi = clock.rate_interval
    assert lo <= rate <= hi, clock
    assert hi - lo < 0.002                      # narrow enough to tell a 0.3 % clock error from none
    assert phase_error(clock.phase, phase) <= clock.phase_halfwidth, clock
    assert clock.events >= 140


@pytest.mark.parametrize('seed', range(6))
def test_states_give_the_true_rate_inside_the_interval(seed: int) -> None:
    """Noisy arm angles at a random rate (0.5 % spread) and phase: the interval holds the rate."""
    rng = np.random.default_rng(100 + seed)
    rate, phase = 1.0 + rng.normal(0.0, 0.005), float(rng.uniform(0.0, 1.0))
    stamps, angles, velocity = states(rate, phase, 0.01, 40.0, noise=0.002, seed=seed)
    clock = estimate_clock(stamps, angles, 'states', PERIOD, start=START, velocity=velocity)
    lo, hi = clock.rate_interval
    assert lo <= rate <= hi, (rate, clock)
    assert phase_error(clock.phase, phase) <= max(clock.phase_halfwidth, 0.01), (phase, clock)


def test_halts_drop_off_the_line_but_keep_the_clock() -> None:
    """Halts shift some boundaries to the next period start: the rate still comes out right."""
    stamps, targets = commands(1.003, 0.2, 0.01, 60.0, halts=(10.13, 22.71, 40.05))
    clock = estimate_clock(stamps, targets, 'commands', PERIOD, start=START)
    assert clock.rate_interval[0] <= 1.003 <= clock.rate_interval[1], clock
    assert phase_error(clock.phase, 0.2) <= clock.phase_halfwidth


def test_a_clock_on_the_ticks_is_exact() -> None:
    """Rate 1 with boundaries on the message ticks: no scatter, phase exact."""
    stamps, targets = commands(1.0, 0.25, 0.05, 30.0)
    clock = estimate_clock(stamps, targets, 'commands', PERIOD, start=START)
    assert clock.rate == pytest.approx(1.0, abs=1e-12) and clock.residual_sd < 1e-9
    assert phase_error(clock.phase, 0.25) < 1e-9


def test_the_fit_from_event_times() -> None:
    """Boundaries of a 2 % fast clock, two missing: rate, period and phase from the line."""
    q = np.array([0, 1, 2, 3, 4, 6, 7, 8, 9, 11, 12])
    times = 1.0 + q * PERIOD / 4.0 / 1.02
    clock = fit_clock(times, q % 4, PERIOD, start=1.0)
    assert clock.rate == pytest.approx(1.02) and clock.period == pytest.approx(PERIOD / 1.02)
    assert clock.phase == pytest.approx(0.0, abs=1e-9) and clock.events == 11
    assert 'rate' in format_clocks([clock], PERIOD, 1.0) and '1.020000' in format_clocks([clock], PERIOD, 1.0)


@pytest.mark.parametrize(('stamps', 'angles', 'match'), [
    (np.arange(100) * 0.1, np.zeros((100, 2)), 'do not move'),
    (np.arange(10) * 0.1, np.ones((10, 3)), r'must be \(T, 2\)'),
    (np.array([0.0, 1.0, 0.5]), np.ones((3, 2)), 'must not go backwards'),
])
def test_unusable_data_is_one_clear_error(stamps: np.ndarray, angles: np.ndarray, match: str) -> None:
    with pytest.raises(ClockError, match=match):
        estimate_clock(stamps, angles, 'commands')


def test_too_short_a_recording_is_refused() -> None:
    stamps, targets = commands(1.0, 0.0, 0.02, 1.5)
    with pytest.raises(ClockError, match='at least 6 are needed'):
        estimate_clock(stamps, targets, 'commands', PERIOD, start=START)
    with pytest.raises(ClockError, match='positive number of seconds'):
        fit_clock(np.arange(8.0), np.arange(8) % 4, period=-1.0)
