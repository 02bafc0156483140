"""A GIF writer for animations drawn by blitting: matplotlib's ``PillowWriter``, frames taken as drawn.

``PillowWriter.grab_frame`` redraws the whole figure for every frame and Pillow then picks an adaptive
palette per frame; for an animation whose moving artists are blitted onto a saved background (the robots
of the demo's animation) both cost about ten times the frame itself. ``BlitGifWriter`` takes each frame
from the Agg canvas as it was last drawn and maps it onto one fixed palette (``fixed_palette``: the
figure's own colours, a grey ramp for anti-aliased text and a 6 x 6 x 6 colour cube), without dithering.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.animation import PillowWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from PIL import Image


def fixed_palette(colours: Sequence[str] = ()) -> Image.Image:
    """A 256-colour palette image: ``colours`` (matplotlib colour specs) first, then white, black, a grey ramp
    and a 6 x 6 x 6 colour cube (the rest of the 256 entries)."""
    named = [*colours, '#ffffff', '#000000']
    entries = [tuple(round(255 * c) for c in to_rgb(name)) for name in named]
    entries += [(v, v, v) for v in range(0, 256, 7)]
    entries += [(r, g, b) for r in range(0, 256, 51) for g in range(0, 256, 51) for b in range(0, 256, 51)]
    flat = [c for entry in entries[:256] for c in entry]
    image = Image.new('P', (1, 1))
    image.putpalette(flat + [0] * (768 - len(flat)))
    return image


class BlitGifWriter(PillowWriter):
    """``PillowWriter`` whose ``grab_frame`` takes the figure's Agg canvas as last drawn (draw or blit it
    first) and maps it onto ``palette`` (default ``fixed_palette()``)."""

    _frames: list[Any]   # PillowWriter's frames, set up by its ``setup``

    def __init__(self, fps: int = 5, palette: Image.Image | None = None, **kwargs: Any) -> None:
        super().__init__(fps=fps, **kwargs)
        self.palette = fixed_palette() if palette is None else palette

    def grab_frame(self, **savefig_kwargs: Any) -> None:
        """Append the canvas as it is now (no redraw) as a palette frame."""
        canvas = self.fig.canvas
        if not isinstance(canvas, FigureCanvasAgg):
            raise TypeError('BlitGifWriter needs a figure on an Agg canvas (FigureCanvasAgg(fig))')
        rgb = np.ascontiguousarray(np.asarray(canvas.buffer_rgba())[..., :3])
        self._frames.append(Image.fromarray(rgb).quantize(palette=self.palette, dither=Image.Dither.NONE))

    def finish(self) -> None:
        """Write the GIF; with no frame grabbed (an error before the first), write nothing."""
        if self._frames:
            super().finish()
