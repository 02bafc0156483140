"""The demo animation's scale: one physical length in both parts, though W differs between their robots."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from smarticle_bringup.demo_figures import AnimatedPart
from smarticle_common.facts import FEEDBACK, SMALL, RobotSpec


def longest_black_run(image: np.ndarray) -> int:
    """The longest horizontal run of black pixels in the lower quarter of ``image`` (H, W, 3) off the axes'
    frame (rows black across most of the width): the scale bar."""
    lower = image[3 * image.shape[0] // 4:]
    black = np.all(lower.astype(int) < 40, axis=-1)
    best = 0
    for row in black[black.mean(axis=1) < 0.5]:
        run = 0
        for dark in row:
            run = run + 1 if dark else 0
            best = max(best, run)
    return best


def still_part(label: str, spec: RobotSpec) -> AnimatedPart:
    """Two robots standing still 15 cm apart for two periods."""
    times = np.arange(0.0, 3.2, 0.1)
    poses = np.zeros((len(times), 2, 3))
    poses[:, 1, 0] = 0.15   # the same place for both robots: the view is as wide in both parts
    poses[:, :, 2] = math.pi / 2
    return AnimatedPart(label, spec, times, poses, np.zeros((len(times), 2, 2)))


def test_the_scale_bar_keeps_its_length_across_parts_of_different_robots(tmp_path: Path) -> None:
    from PIL import Image
    from smarticle_bringup.demo_figures import SCALE_BAR, scale_label, write_animation

    path = write_animation([still_part('1 small', SMALL), still_part('2 feedback', FEEDBACK)], tmp_path / 'a.gif',
                           step=1.6)
    with Image.open(path) as gif:
        frames = gif.n_frames
        gif.seek(0)
        first = np.asarray(gif.convert('RGB'))
        gif.seek(frames - 1)
        last = np.asarray(gif.convert('RGB'))
    bar_small, bar_feedback = longest_black_run(first), longest_black_run(last)
    assert bar_small > 20
    assert bar_small == pytest.approx(bar_feedback, abs=1)   # a bar of 1 W: 67 against 73 px
    assert SCALE_BAR == 0.05
    assert scale_label(SMALL) == '5 cm   (W = 5.4 cm)'
    assert scale_label(FEEDBACK) == '5 cm   (W = 6.5 cm)'
