"""`smarticle-bag clocks` on the sample bags (no DDS): true clocks inside their intervals, bad input one line."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from smarticle_bags import cli

SAMPLES = Path(__file__).resolve().parents[2] / 'bags' / 'samples'
ROW = re.compile(r'^\s+(\d+)\s+(\w+)\s+(\d+)\s+([\d.]+)\s+\[([\d.]+), ([\d.]+)\]\s+\S+\s+([\d.]+)\s+([\d.]+)')


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as done:
        cli.main(argv)
    out, err = capsys.readouterr()
    return int(done.value.code or 0), out, err


@pytest.mark.parametrize(('sample', 'source', 'robots'), [('pair_c1', 'commands', 2), ('pair_c1', 'states', 2),
                                                          ('dense7', 'auto', 7)])
def test_the_samples_clocks_are_true(sample: str, source: str, robots: int,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """The samples' gait nodes keep the sim's time: rate 1 inside every interval, phase 0 at the start."""
    code, out, err = run(['clocks', str(SAMPLES / sample), '--source', source], capsys)
    assert code == 0, err
    assert 'phase at 0.500 s, the gait start (/smarticles/start)' in out
    rows = [m for m in map(ROW.match, out.splitlines()) if m]
    assert len(rows) == robots, out
    for m in rows:
        lo, hi = float(m.group(5)), float(m.group(6))
        phase, halfwidth = float(m.group(7)), float(m.group(8))
        assert lo <= 1.0 <= hi and hi - lo < 0.005, out
        assert min(phase, 1.0 - phase) <= max(halfwidth, 1e-3), out


def test_missing_topics_and_bad_options_are_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(['clocks', str(SAMPLES / 'dense7'), '--source', 'commands'], capsys)
    assert code == 2 and out == ''
    assert err.strip() == (f'smarticle-bag clocks: {SAMPLES / "dense7"} holds no /smarticle_<k>/joint_commands: '
                           'nothing to estimate')
    code, out, err = run(['clocks', str(SAMPLES / 'pair_c1'), '--period', '0'], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and '--period must be a positive' in err
