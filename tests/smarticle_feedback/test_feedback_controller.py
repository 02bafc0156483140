"""The impact policy core: windows, debouncing, one halt per gait period, faces one by one, bad samples."""

from __future__ import annotations

import math

import pytest
from smarticle_common.params import ParameterError
from smarticle_common.topics import FSR_FACES

from smarticle_feedback.controller import FeedbackConfig, ImpactController, ImpactWindow, check_sample
from smarticle_feedback.errors import FeedbackConfigError, FsrSampleError
from smarticle_feedback.parameters import config_from_values, default_values

QUIET = (0.0, 0.0, 0.0, 0.0)


def hit(face: str, force: float) -> tuple[float, ...]:
    """A sample with ``force`` on ``face`` only."""
    return tuple(force if f == face else 0.0 for f in FSR_FACES)


def started(config: FeedbackConfig, t0: float = 0.0) -> ImpactController:
    controller = ImpactController(config)
    controller.start(t0)
    return controller


def test_a_force_inside_the_window_halts_and_one_outside_does_not() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0))
    assert not controller.update(0.10, hit('arm1_back', 0.5)).halt      # below f_min: a light touch
    assert not controller.update(0.11, hit('arm1_back', 8.0)).halt      # above f_max: not an impact
    decision = controller.update(0.12, hit('arm1_back', 3.0))
    assert decision.halt and decision.face == 'arm1_back' and decision.period_index == 0
    assert controller.counters.halts == 1


def test_window_edges_count_as_inside() -> None:
    window = ImpactWindow(1.0, 5.0)
    assert window.contains(1.0) and window.contains(5.0) and not window.contains(5.0001)


def test_debounce_needs_consecutive_samples_of_one_face() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0, debounce=3))
    assert not controller.update(0.10, hit('arm2_front', 2.0)).halt
    assert not controller.update(0.11, hit('arm2_front', 2.0)).halt
    assert not controller.update(0.12, QUIET).halt                      # the run is broken
    assert not controller.update(0.13, hit('arm2_front', 2.0)).halt
    assert not controller.update(0.14, hit('arm2_front', 2.0)).halt
    assert controller.update(0.15, hit('arm2_front', 2.0)).halt


def test_at_most_one_halt_per_gait_period_then_again_in_the_next() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0, period=1.6), t0=10.0)
    assert controller.update(10.2, hit('arm1_front', 2.0)).halt
    assert not any(controller.update(10.2 + 0.01 * i, hit('arm1_front', 2.0)).halt for i in range(1, 100))
    assert controller.counters.suppressed == 99
    assert controller.update(11.6, hit('arm1_front', 2.0)).halt          # period 1 starts at 11.6 s
    assert controller.update(13.3, hit('arm1_front', 2.0)).period_index == 2


def test_period_boundaries_follow_the_gait_phase() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0, period=1.0, phase=0.75))
    assert controller.update(0.1, hit('arm1_front', 2.0)).period_index == 0
    assert controller.update(0.25, hit('arm1_front', 2.0)).halt          # tau = 1.0: the next period


def test_no_halt_before_the_start_and_a_refractory_period_without_one() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0, period=1.0), t0=5.0)
    assert not controller.update(4.9, hit('arm1_front', 2.0)).halt
    assert controller.counters.before_start == 1
    free = ImpactController(FeedbackConfig.uniform(1.0, 5.0, period=1.0))   # no start known
    assert free.update(0.30, hit('arm1_front', 2.0)).halt
    assert not free.update(1.29, hit('arm1_front', 2.0)).halt
    assert free.update(1.30, hit('arm1_front', 2.0)).halt


def test_faces_are_enabled_one_by_one() -> None:
    config = FeedbackConfig.uniform(1.0, 5.0, faces=('arm2_back',))
    assert config.enabled_faces == ('arm2_back',)
    controller = started(config)
    for t, face in enumerate(('arm1_front', 'arm1_back', 'arm2_front')):
        assert not controller.update(0.01 * t, hit(face, 2.0)).halt
    assert controller.update(0.05, hit('arm2_back', 2.0)).face == 'arm2_back'


def test_bad_values_are_reported_and_read_as_no_impact() -> None:
    checked = check_sample(list(FSR_FACES), [math.nan, -1.0, math.inf, 2.0])
    assert len(checked.warnings) == 3 and 'negative' in checked.warnings[1]
    controller = started(FeedbackConfig.uniform(1.0, 5.0))
    decision = controller.update(0.1, checked.forces)
    assert decision.halt and decision.face == 'arm2_back'
    assert controller.counters.bad_values == 3


def test_samples_are_ordered_by_name_and_wrong_faces_are_refused() -> None:
    names = ['arm2_back', 'arm2_front', 'arm1_back', 'arm1_front']
    assert check_sample(names, [4.0, 3.0, 2.0, 1.0]).forces == (1.0, 2.0, 3.0, 4.0)
    assert check_sample([], [1.0, 2.0, 3.0, 4.0]).forces == (1.0, 2.0, 3.0, 4.0)
    with pytest.raises(FsrSampleError, match='3 forces, expected 4') as err:
        check_sample(names[:3], [1.0, 2.0, 3.0])
    assert err.value.kind == 'wrong_faces'
    with pytest.raises(FsrSampleError, match='not the faces'):
        check_sample(['a', 'b', 'c', 'd'], [1.0, 2.0, 3.0, 4.0])


def test_time_going_backwards_is_refused() -> None:
    controller = started(FeedbackConfig.uniform(1.0, 5.0))
    controller.update(1.0, QUIET)
    with pytest.raises(FsrSampleError, match='backwards'):
        controller.update(0.5, QUIET)


@pytest.mark.parametrize('kwargs, message', [
    ({'f_min': 5.0, 'f_max': 1.0}, 'above f_max'),
    ({'f_min': -1.0, 'f_max': 1.0}, 'finite force >= 0'),
    ({'f_min': math.nan, 'f_max': 1.0}, 'finite force >= 0'),
    ({'f_min': 1.0, 'f_max': 2.0, 'debounce': 0}, 'debounce'),
    ({'f_min': 1.0, 'f_max': 2.0, 'period': 0.0}, 'period'),
    ({'f_min': 1.0, 'f_max': 2.0, 'faces': ('arm3_front',)}, 'unknown FSR face'),
])
def test_nonsense_settings_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(FeedbackConfigError, match=message):
        FeedbackConfig.uniform(**kwargs)


def test_parameters_build_the_config() -> None:
    config = config_from_values(default_values(arm1_back_enabled=False, debounce_samples=2))
    assert 'arm1_back' not in config.enabled_faces and config.debounce == 2
    with pytest.raises(ParameterError, match='node feedback: impact window f_min'):
        config_from_values(default_values(arm1_front_min=7.0, arm1_front_max=6.0))


def test_new_windows_apply_from_the_next_sample_and_keep_the_state() -> None:
    from smarticle_feedback.errors import FeedbackConfigError

    controller = ImpactController(FeedbackConfig.uniform(1.0, 5.0, period=1.6))
    controller.start(0.0)
    assert controller.update(0.1, [3.0, 0.0, 0.0, 0.0]).halt
    controller.set_windows(FeedbackConfig.uniform(1.0, 2.0, period=1.6))
    assert controller.start_time == 0.0 and controller.counters.halts == 1
    assert not controller.update(2.0, [3.0, 0.0, 0.0, 0.0]).halt      # 3 N is outside [1, 2] now
    assert controller.update(2.1, [1.5, 0.0, 0.0, 0.0]).halt
    with pytest.raises(FeedbackConfigError, match='period and phase'):
        controller.set_windows(FeedbackConfig.uniform(1.0, 2.0, period=1.0))
