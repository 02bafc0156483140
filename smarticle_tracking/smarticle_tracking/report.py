"""The glider report of a run, written once: analyse the poses, print the table, draw the figure.

The demo (``smarticle_bringup.demo``) and ``smarticle-bag analyze`` both report through ``glider_report``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .gliders import (GliderAnalysis, GliderConfig, analyse_gliders, format_glider_table, glider_summary, glider_table,
                      rule_text)


@dataclass(frozen=True)
class GliderReport:
    """A run's glider analysis, its table as text, the figure written (None without a bound pair), the count
    line ('2 bound pairs, 1 of them a glider (0-1 C1)') and the definitions with their numbers."""

    analysis: GliderAnalysis
    table: str
    figure: Path | None
    summary: str
    rule: str


def glider_report(times: np.ndarray, poses: np.ndarray, config: GliderConfig,
                  figure: str | Path | None = None) -> GliderReport:
    """Analyse ``poses`` (T, N, 3) at ``times`` (s); write ``figure`` (PNG) when a bound pair formed."""
    analysis = analyse_gliders(times, poses, config)
    rows = glider_table(analysis.gliders, config)
    written = None
    if figure is not None and analysis.gliders:
        from .glider_plots import plot_glider_analysis

        written = plot_glider_analysis(analysis, Path(figure))
    return GliderReport(analysis, format_glider_table(rows) if rows else '  none', written,
                        glider_summary(analysis.gliders), rule_text(config))
