"""Contact events of a pair record and the per-face windows calibrated from the compression signature."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from smarticle_feedback import impact_window
from smarticle_feedback.collisions import CollisionRecord, find_events, format_events, load_record, signature
from smarticle_feedback.errors import CalibrationInputError

DT = 1.0 / 480.0


def synthetic_record(kicks: list[tuple[float, int, float, float]], seconds: float = 3.2) -> CollisionRecord:
    """A pair record with one-step kicks (time s, face index of robot 0, force N, dr BL after the kick)."""
    times = np.arange(int(seconds / DT)) * DT
    fsr = np.zeros((times.size, 2, 4))
    links = np.zeros((times.size, 3, 3), dtype=bool)
    r = np.full(times.size, 1.4)
    for t, face, force, dr in kicks:
        i = int(round(t / DT))
        fsr[i, 0, face] = force
        links[i, 1 + face // 2, 0] = True         # robot 0's arm on robot 1's body
        r[i + 1:] += dr
    return CollisionRecord(times, fsr, links, r, 1.6, (0.0, 0.25))


def test_events_carry_quarter_links_peaks_and_dr() -> None:
    rec = synthetic_record([(0.1, 0, 9.0, 0.03), (0.5, 2, 3.0, -0.02), (0.505, 2, 2.0, 0.0), (1.0, 2, 1.0, 0.0)])
    events = find_events(rec)
    assert len(events) == 3                             # the kicks 5 ms apart are one event
    first, second, third = events
    assert first.kind == 'compression' and first.quarters == (0, 1) and first.links == ('arm1>body',)
    assert first.peaks[0, 0] == 9.0 and first.dr == pytest.approx(0.03) and first.steps == 1
    assert second.steps == 2
    assert second.kind == 'bracing' and second.quarters == (1, 2) and second.peaks[0, 2] == 3.0
    assert third.kind == 'neutral' and third.quarters == (2, 3)
    sig = signature(events)
    assert sig.counts == {'compression': 1, 'bracing': 1, 'neutral': 1}
    assert 'compression' in format_events(events)


def test_quarters_follow_each_robots_own_clock(tmp_path: Path) -> None:
    """With clock-rate noise a robot's gait time is (t - start) * rate: its quarter is read on its own clock."""
    base = synthetic_record([(0.1, 0, 9.0, 0.03)], seconds=0.5)
    rec = CollisionRecord(base.times, base.fsr, base.links, base.r, 1.6, (0.0, 0.0), clock_rates=(1.0, 5.0))
    (event,) = find_events(rec)
    assert event.quarters == (0, 1)          # robot 1's clock reads 0.5 s = 0.3125 periods at t = 0.1 s
    again = load_record(rec.save(tmp_path / 'rates.npz'))
    assert again.clock_rates == (1.0, 5.0)
    assert load_record(base.save(tmp_path / 'plain.npz')).clock_rates == (1.0, 1.0)


def test_windows_separate_compression_from_bracing(tmp_path: Path) -> None:
    kicks = [(0.1 + 0.4 * i, 2, 8.0 + 0.1 * i, 0.02) for i in range(4)]        # hard compression kicks
    kicks += [(0.3 + 0.4 * i, 2, 3.0 + 0.1 * i, -0.02) for i in range(4)]      # light bracing kicks, same face
    path = synthetic_record(kicks).save(tmp_path / 'c2_steps.npz')
    windows = impact_window.windows_from_events(find_events(load_record(path)))
    face = windows.faces[2]
    assert face.enabled and 3.3 < face.f_min <= 8.0 and face.f_max == pytest.approx(8.3 * impact_window.HEADROOM)
    assert (windows.compression_caught, windows.bracing_caught) == (4, 0)
    assert not windows.faces[0].enabled and not windows.problems
    assert impact_window.main([str(path)]) == 0


def test_a_window_that_catches_bracing_is_refused_with_counts(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    kicks = [(0.1 + 0.4 * i, 2, 3.0, 0.02) for i in range(2)]                  # compression no harder ...
    kicks += [(0.3 + 0.4 * i, 2, 3.0, -0.02) for i in range(4)]                # ... than bracing
    path = synthetic_record(kicks).save(tmp_path / 'c2_steps.npz')
    assert impact_window.main([str(path)]) == 3
    err = capsys.readouterr().err
    assert 'not shipping' in err and 'no recorded compression event' in err and '0 of 2' in err


def test_a_record_that_is_not_one_is_refused(tmp_path: Path) -> None:
    np.savez(tmp_path / 'other.npz', x=np.zeros(3))
    with pytest.raises(CalibrationInputError, match='smarticle-experiments c2-collisions'):
        load_record(tmp_path / 'other.npz')
    with pytest.raises(CalibrationInputError, match='links'):
        CollisionRecord(np.zeros(3), np.zeros((3, 2, 4)), np.zeros((3, 2, 2), dtype=bool), np.zeros(3), 1.6, (0, 0))


def test_the_shipped_windows_can_be_checked_on_a_record(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from smarticle_common.topics import FSR_FACES
    from smarticle_feedback.parameters import DEFAULT_WINDOWS

    face = next(n for n, name in enumerate(FSR_FACES) if DEFAULT_WINDOWS[name][2])   # a face the config enables
    f_min, f_max, _ = DEFAULT_WINDOWS[FSR_FACES[face]]
    hard, light = 0.5 * (f_min + f_max), 0.5 * f_min                         # inside and below its window
    kicks = [(0.1 + 0.4 * i, face, hard, 0.02) for i in range(3)]
    kicks += [(0.3 + 0.4 * i, face, light, -0.02) for i in range(3)]
    path = synthetic_record(kicks).save(tmp_path / 'c2_steps.npz')
    assert impact_window.main([str(path), '--check-shipped']) == 0
    assert 'compression 3 of 3, bracing 0 of 3' in capsys.readouterr().out
    checked = impact_window.check_windows(find_events(load_record(path)), [
        (name, 1.0, 2.0, True) if n == face else (name, 0.0, 0.0, False) for n, name in enumerate(FSR_FACES)])
    assert checked.compression_caught == 0 and checked.problems
