"""Unit tests of the square-gait core: corners, order, timing, speed limit, phase, halt and resume."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_common.facts import SERVO_SPEED

from smarticle_common.gait import CORNER_SIGNS, GaitConfig, GaitError, SquareGait, board_time, open_loop_angles

A = math.radians(90.0)


def trace(gait: SquareGait, t0: float, t1: float, dt: float = 0.001) -> tuple[np.ndarray, np.ndarray]:
    """Sample the gait's reference positions on [t0, t1)."""
    times = np.arange(t0, t1, dt)
    return times, np.array([gait.command(float(t)).positions for t in times])


def test_corners_are_visited_in_documented_order() -> None:
    gait = SquareGait(GaitConfig(alpha_max=A, period=1.6))
    gait.start(0.0)
    ends = [gait.command(0.4 * q + 0.4 - 1e-7).positions for q in range(4)]   # the arm arrives at the quarter's end
    expected = [(s1 * A, s2 * A) for s1, s2 in CORNER_SIGNS[1:] + CORNER_SIGNS[:1]]
    assert np.allclose(ends, expected)


def test_one_arm_moves_at_a_time_and_never_faster_than_servo_speed() -> None:
    config = GaitConfig(alpha_max=A, period=1.6, servo_speed=SERVO_SPEED)
    gait = SquareGait(config)
    gait.start(0.0)
    times, pos = trace(gait, 0.0, 3.2)
    speed = np.abs(np.diff(pos, axis=0)) / np.diff(times)[:, None]
    assert speed.max() <= config.servo_speed * (1 + 1e-6)
    assert not np.any((speed[:, 0] > 1e-9) & (speed[:, 1] > 1e-9))
    # in quarter 0 arm 1 moves, in quarter 1 arm 2 moves
    assert speed[10:300, 0].max() > 0 and speed[10:300, 1].max() == 0
    assert speed[410:700, 1].max() > 0 and speed[410:700, 0].max() == 0


def test_stroke_takes_twice_alpha_over_speed() -> None:
    config = GaitConfig(alpha_max=A, period=1.6, servo_speed=10.0)
    gait = SquareGait(config)
    gait.start(2.0)
    arrival = 2.0 + 2 * A / 10.0
    assert gait.command(arrival - 0.01).positions[0] > -A + 0.05
    assert gait.command(arrival + 1e-6).positions[0] == pytest.approx(-A)


def test_gait_is_periodic_and_matches_closed_form() -> None:
    config = GaitConfig.from_degrees(60.0, period=1.2, phase=0.3)
    gait = SquareGait(config)
    gait.start(5.0)
    for t in np.arange(5.0, 9.8, 0.0137):
        tau = (t - 5.0) / 1.2 + 0.3
        assert gait.command(float(t)).positions == pytest.approx(open_loop_angles(config, tau))
    assert open_loop_angles(config, 0.3) == pytest.approx(open_loop_angles(config, 1.3))


def test_phase_offset_shifts_the_gait() -> None:
    base = SquareGait(GaitConfig(alpha_max=A))
    shifted = SquareGait(GaitConfig(alpha_max=A, phase=0.25))
    base.start(0.0)
    shifted.start(0.0)
    assert shifted.command(0.1).positions == pytest.approx(base.command(0.5).positions)


def test_before_start_the_arms_hold_the_start_pose() -> None:
    gait = SquareGait(GaitConfig(alpha_max=A, phase=0.5))
    cmd = gait.command(123.0)
    assert not cmd.started and cmd.targets == cmd.positions == pytest.approx((-A, -A))
    gait.start(200.0)
    assert not gait.command(199.0).started


def test_halt_holds_then_resumes_from_held_position_at_next_period() -> None:
    config = GaitConfig(alpha_max=A, period=1.6, servo_speed=SERVO_SPEED)
    gait = SquareGait(config)
    gait.start(0.0)
    t_halt = 0.4 + 0.05  # quarter 1: arm 2 moving from +A toward -A
    assert gait.halt(t_halt)
    held = gait.command(t_halt).positions
    assert held[1] == pytest.approx(A - config.servo_speed * 0.05)
    assert not gait.halt(t_halt + 0.1)  # already halted
    for t in (0.6, 1.0, 1.5, 1.599):
        cmd = gait.command(t)
        assert cmd.halted and cmd.positions == pytest.approx(held) and cmd.targets == pytest.approx(held)
    # next period: quarter 0 moves arm 1 toward -A (it already is there), quarter 1 moves arm 2 from held
    assert not gait.command(1.6 + 1e-9).halted
    assert gait.command(1.6 + 0.3).positions == pytest.approx(held)
    mid = gait.command(1.6 + 0.4 + 0.05).positions
    assert mid[1] == pytest.approx(held[1] - config.servo_speed * 0.05)
    assert gait.command(1.6 + 0.79).positions == pytest.approx((-A, -A))


def test_halt_result_does_not_depend_on_sampling_rate() -> None:
    coarse, fine = SquareGait(GaitConfig(alpha_max=A)), SquareGait(GaitConfig(alpha_max=A))
    for gait in (coarse, fine):
        gait.start(0.0)
    fine_times = np.arange(0.0, 1.0, 0.001)
    for t in fine_times:
        fine.command(float(t))
    coarse.command(0.5)
    coarse.halt(1.0)
    fine.halt(1.0)
    for t in (1.2, 2.0, 2.5, 3.3):
        assert coarse.command(t).positions == pytest.approx(fine.command(t).positions)


def test_halt_before_start_is_refused_and_time_must_not_go_back() -> None:
    gait = SquareGait(GaitConfig(alpha_max=A))
    assert not gait.halt(1.0)
    gait.start(1.0)
    gait.command(2.0)
    with pytest.raises(GaitError, match='backwards'):
        gait.command(1.5)


@pytest.mark.parametrize('kwargs, field', [
    ({'alpha_max': math.radians(4.0)}, 'alpha_max'),
    ({'alpha_max': math.radians(121.0)}, 'alpha_max'),
    ({'alpha_max': float('nan')}, 'alpha_max'),
    ({'period': 0.0}, 'period'),
    ({'servo_speed': -1.0}, 'servo_speed'),
    ({'phase': 1.0}, 'phase'),
    ({'alpha_max': math.radians(120.0), 'servo_speed': 5.0}, 'stroke'),
])
def test_invalid_configs_are_refused_with_the_field_named(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(GaitError, match=field):
        GaitConfig(**kwargs)


def test_full_amplitude_range_fits_default_speed() -> None:
    for deg in (5.0, 45.0, 90.0):                  # the paper's amplitudes: up to 90 deg at its motor speed
        config = GaitConfig.from_degrees(deg)
        gait = SquareGait(config)
        gait.start(0.0)
        assert gait.command(0.4 + 1e-6).positions[0] == pytest.approx(-config.alpha_max)
    with pytest.raises(GaitError, match='longer than a quarter'):
        GaitConfig.from_degrees(120.0)             # a 240 degree stroke needs a faster servo
    assert GaitConfig.from_degrees(120.0, servo_speed=math.radians(60.0) / 0.1).alpha_max == pytest.approx(
        math.radians(120.0))


def test_board_time_runs_at_its_rate_from_the_start() -> None:
    """A board clock 0.5 % fast reads 0.5 % more time since the start; before a start, the reference time."""
    assert board_time(7.0, None, 1.005) == 7.0
    assert board_time(7.0, 2.0, 1.0) == 7.0
    assert board_time(2.0, 2.0, 1.005) == 2.0
    assert board_time(82.0, 2.0, 1.005) == pytest.approx(2.0 + 80.0 * 1.005)
    gait = SquareGait(GaitConfig.from_degrees(90.0))
    gait.start(0.0)
    assert gait.gait_time(board_time(50 * gait.config.period, 0.0, 1.005)) == pytest.approx(50.25)


def test_a_new_amplitude_starts_at_the_next_period_and_never_jumps() -> None:
    import math

    from smarticle_common.gait import GaitConfig, GaitError, SquareGait

    old, new = math.radians(90.0), math.radians(45.0)
    gait = SquareGait(GaitConfig(old, period=1.6))
    gait.start(0.0)
    times = [i * 0.01 for i in range(501)]                     # 0 .. 5 s: periods start at 1.6, 3.2, 4.8
    before = [gait.command(t) for t in times[:201]]            # up to t = 2.0 s, inside period 1
    gait.set_alpha_max(new)
    assert gait.pending is not None and gait.config.alpha_max == old
    after = [gait.command(t) for t in times[201:]]
    assert max(abs(v) for c in before for v in c.targets) == pytest.approx(old)
    late = [c for t, c in zip(times[201:], after, strict=True) if t < 3.2 - 1e-9]   # rest of period 1: old square
    assert {round(abs(v), 6) for c in late for v in c.targets} == {round(old, 6)}
    last = [c for t, c in zip(times[201:], after, strict=True) if t >= 3.6]
    assert {round(abs(v), 6) for c in last for v in c.targets} == {round(new, 6)}
    assert gait.pending is None and gait.config.alpha_max == new
    steps = [abs(b - a) for x, y in zip([*before, *after], [*before, *after][1:], strict=False) for a, b in
             zip(x.positions, y.positions, strict=True)]
    assert max(steps) <= gait.config.servo_speed * 0.01 + 1e-9          # never faster than the servo
    with pytest.raises(GaitError):
        gait.set_alpha_max(math.radians(200.0))
    assert gait.pending is None and gait.config.alpha_max == new        # unchanged
    idle = SquareGait(GaitConfig(old))
    idle.set_alpha_max(new)                                             # before the start: at once
    assert idle.config.alpha_max == new and idle.command(0.0).targets == pytest.approx((new, new))


def _history(gait: SquareGait, until: float) -> None:
    """Drive ``gait`` tick by tick (10 ms) to ``until``: a halt at 2.45 s, a new amplitude at 4.0 s."""
    for i in range(round(until / 0.01) + 1):
        t = i * 0.01
        if i == 245:
            assert gait.halt(t)
        if i == 400:
            gait.set_alpha_max(math.radians(60.0))
        gait.command(t)


@pytest.mark.parametrize('phase', [0.0, 0.3])
@pytest.mark.parametrize('jump_from', [2.5, 4.1, 5.0])       # halted; a new amplitude pending; both behind
def test_a_jump_over_many_periods_lands_where_ticking_there_does(phase: float, jump_from: float) -> None:
    """One call far ahead gives what a tick every 10 ms gives, from a halt, a pending amplitude or neither."""
    ticked, jumped = (SquareGait(GaitConfig.from_degrees(90.0, period=1.6, phase=phase)) for _ in range(2))
    for gait in (ticked, jumped):
        gait.start(0.0)
        _history(gait, jump_from)
    for t in np.arange(jump_from, 60.0, 0.01):               # tick by tick to 60 s
        ticked.command(float(t))
    for t in (60.0 + 0.003, 61.1, 63.33):                    # the jump: straight to 60 s, then on
        got, want = jumped.command(t), ticked.command(t)
        assert (got.period_index, got.quarter, got.halted) == (want.period_index, want.quarter, want.halted)
        assert got.targets == pytest.approx(want.targets, abs=1e-12)
        assert got.positions == pytest.approx(want.positions, abs=1e-12)
    assert jumped.config == ticked.config and jumped.pending is None


def test_a_time_a_billion_seconds_after_the_start_is_reached_at_once() -> None:
    """No loop over the elapsed quarters: 1e9 s (2.5e9 quarters) after the start costs what one tick costs."""
    import time

    config = GaitConfig.from_degrees(60.0, period=1.2, phase=0.3)
    gait = SquareGait(config)
    t0 = 1.7e9                                                # a wall-clock start (epoch seconds)
    gait.start(t0)
    gait.command(t0 + 1.0)
    assert gait.halt(t0 + 1.0)
    began = time.perf_counter()
    command = gait.command(t0 + 1e9)
    assert time.perf_counter() - began < 0.05
    tau = 1e9 / 1.2 + 0.3
    assert command.period_index == math.floor(tau) and not command.halted
    assert command.positions == pytest.approx(open_loop_angles(config, tau), abs=1e-6)
