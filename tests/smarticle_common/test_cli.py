"""The shared command-line habits: the seed syntax, --version and a closed pipe."""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from smarticle_common.cli import SeedSyntaxError, add_version, parse_seeds, seeds_argument


@pytest.mark.parametrize('text, seeds', [
    ('7', [7]), ('0..3', [0, 1, 2, 3]), ('0,3,5', [0, 3, 5]), ('0..2,10', [0, 1, 2, 10]),
    (' 4 , 2 ', [4, 2]), ('1..1', [1]), ('2,2,1..3', [2, 1, 3]),
])
def test_seed_syntax(text: str, seeds: list[int]) -> None:
    assert parse_seeds(text) == seeds


@pytest.mark.parametrize('text, word', [
    ('', 'empty'), ('3..1', 'backwards'), ('a', "'a'"), ('0..x', "'0..x'"), ('-1', 'non-negative'), ('1,,2', 'empty'),
])
def test_bad_seeds_name_the_piece(text: str, word: str) -> None:
    with pytest.raises(SeedSyntaxError, match=word):
        parse_seeds(text)
    with pytest.raises(argparse.ArgumentTypeError):
        seeds_argument(text)


def test_version_option_prints_the_installed_version(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser(prog='tool')
    add_version(parser, 'smarticle_common')
    with pytest.raises(SystemExit) as stop:
        parser.parse_args(['--version'])
    assert stop.value.code == 0
    out = capsys.readouterr().out.split()
    assert out[0] == 'tool' and out[1][0].isdigit()


def test_closed_pipe_ends_quietly() -> None:
    code = ('from smarticle_common.cli import closed_pipe_safe\n'
            '@closed_pipe_safe\n'
            'def main():\n'
            '    for i in range(200000):\n'
            '        print("line", i)\n'
            'raise SystemExit(main())\n')
    proc = subprocess.run(f'{sys.executable} -c \'{code}\' | head -1', shell=True, capture_output=True, text=True,
                          timeout=60)
    assert proc.stdout == 'line 0\n'
    assert 'Traceback' not in proc.stderr and 'BrokenPipe' not in proc.stderr


def test_ctrl_c_ends_a_console_main_with_one_line() -> None:
    """A main that has not handled Ctrl-C itself: one line naming the program, exit code 130, no traceback."""
    code = ('import os, signal\n'
            'from smarticle_common.cli import closed_pipe_safe\n'
            '@closed_pipe_safe\n'
            'def main():\n'
            '    os.kill(os.getpid(), signal.SIGINT)\n'
            '    while True:\n'
            '        pass\n'
            'raise SystemExit(main())\n')
    proc = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130
    assert proc.stderr.strip().splitlines() == ['-c: interrupted']
