#!/usr/bin/env python3
"""Draw the pair-coordinate figure of docs/gliders.md (r, theta, phi of paper Fig. 3(a))."""

from __future__ import annotations

import argparse
from pathlib import Path

from smarticle_tracking.glider_plots import draw_pair_coordinates

DEFAULT_OUT = Path(__file__).resolve().parents[2] / 'docs' / 'gliders-pair-coordinates.png'


def main(argv: list[str] | None = None) -> None:
    """Write the PNG (default: docs/gliders-pair-coordinates.png)."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('out', nargs='?', type=Path, default=DEFAULT_OUT, help='PNG file to write')
    args = parser.parse_args(argv)
    print(draw_pair_coordinates(args.out))


if __name__ == '__main__':
    main()
