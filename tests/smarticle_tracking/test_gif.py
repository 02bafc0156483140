"""The blitting GIF writer: frames as drawn, on one fixed palette, read back by Pillow."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image
from smarticle_tracking.gif import BlitGifWriter, fixed_palette


def test_frames_are_the_canvas_as_drawn_in_the_palettes_colours(tmp_path: Path) -> None:
    fig = Figure(figsize=(2, 2), dpi=50)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, 4)
    ax.set_ylim(0, 1)
    ax.axis('off')
    dot, = ax.plot([], [], 's', ms=12, color='#2a8cff', animated=True)
    writer = BlitGifWriter(fps=10, palette=fixed_palette(['#2a8cff']))
    path = tmp_path / 'moving.gif'
    with writer.saving(fig, str(path), 50):
        canvas.draw()
        background = canvas.copy_from_bbox(fig.bbox)
        for x in (0.5, 1.5, 2.5, 3.5):
            dot.set_data([x], [0.5])
            canvas.restore_region(background)
            ax.draw_artist(dot)
            writer.grab_frame()
    with Image.open(path) as gif:
        assert gif.n_frames == 4
        columns = []
        for i in range(4):
            gif.seek(i)
            rgb = np.asarray(gif.convert('RGB')).astype(int)
            blue = np.all(np.abs(rgb - (0x2a, 0x8c, 0xff)) <= 1, axis=-1)   # the exact colour, from the palette
            assert blue.sum() > 20
            columns.append(np.flatnonzero(blue.any(axis=0)).mean())
    assert columns == sorted(columns) and columns[-1] - columns[0] > 40   # the square moved right, frame by frame


def test_a_figure_without_an_agg_canvas_is_refused(tmp_path: Path) -> None:
    fig = Figure(figsize=(1, 1), dpi=20)
    writer = BlitGifWriter()
    with pytest.raises(TypeError, match='Agg canvas'):
        with writer.saving(fig, str(tmp_path / 'x.gif'), 20):
            writer.grab_frame()
