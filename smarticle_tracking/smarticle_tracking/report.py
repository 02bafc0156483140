"""The glider report of a run, written once: analyse the poses, print the table, draw the figure.

The demo (``smarticle_bringup.demo``) and ``smarticle-bag analyze`` both report through ``glider_report``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .gliders import GliderAnalysis, GliderConfig, analyse_gliders, format_glider_table, glider_table


@dataclass(frozen=True)
class GliderReport:
    """A run's glider analysis, its table as text and the figure written (None without gliders)."""

    analysis: GliderAnalysis
    table: str
    figure: Path | None


def glider_report(times: np.ndarray, poses: np.ndarray, config: GliderConfig,
                  figure: str | Path | None = None) -> GliderReport:
    """Analyse ``poses`` (T, N, 3) at ``times`` (s); write ``figure`` (PNG) when a glider formed."""
    analysis = analyse_gliders(times, poses, config)
    rows = glider_table(analysis.gliders, config)
    written = None
    if figure is not None and analysis.gliders:
        from .glider_plots import plot_glider_analysis

        written = plot_glider_analysis(analysis, Path(figure))
    return GliderReport(analysis, format_glider_table(rows) if rows else '  none', written)
