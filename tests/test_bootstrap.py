"""The set-up script sourced into a user's shell: it adds .venv/bin to PATH and changes nothing else.

``source tools/bootstrap.sh`` is what the README tells a user to type. Sourcing it must leave the caller's
shell options (``set -e``, ``set -u``, ``pipefail``) and variables as they were, and a failed set-up must
return non-zero to the caller instead of closing the caller's shell.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOTSTRAP = ROOT / 'tools' / 'bootstrap.sh'


def _bash(script: str, **env: str) -> subprocess.CompletedProcess[str]:
    """Run ``script`` in a fresh non-interactive bash (the environment of this test run plus ``env``)."""
    return subprocess.run(['bash', '-c', script], capture_output=True, text=True, timeout=600,
                          env={**os.environ, **env}, cwd=ROOT)


def test_a_failing_command_after_sourcing_does_not_end_the_shell() -> None:
    """The README's ``source tools/bootstrap.sh`` leaves no ``set -e`` behind."""
    done = _bash(f'source {BOOTSTRAP} >/dev/null; false; echo still here')
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == 'still here'


def test_sourcing_leaves_the_callers_options_and_variables_as_they_were() -> None:
    """Options before and after are the same, in a shell with some set and one without; only PATH changes."""
    for options in ('', 'set -u; set -o noclobber', 'set -e; set -o pipefail'):
        script = (f'{options}\nROOT=mine; before="$(set +o)"\n'
                  f'source {BOOTSTRAP} >/dev/null\n'
                  'after="$(set +o)"\n'
                  '[ "$before" = "$after" ] && echo same-options\n'
                  'echo "ROOT=$ROOT"; echo "VENV=${VENV-unset}"; echo "PACKAGES=${PACKAGES-unset}"\n'
                  'echo "PATH0=${PATH%%:*}"; command -v smarticle-launch')
        done = _bash(script)
        assert done.returncode == 0, (options, done.stderr)
        lines = done.stdout.split()
        assert 'same-options' in lines, (options, done.stdout)
        assert 'ROOT=mine' in lines and 'VENV=unset' in lines and 'PACKAGES=unset' in lines
        venv_bin = Path(os.environ.get('SMARTICLE_VENV', ROOT / '.venv')) / 'bin'
        assert f'PATH0={venv_bin}' in lines
        assert lines[-1] == str(venv_bin / 'smarticle-launch')


def test_a_failed_set_up_returns_non_zero_and_the_shell_goes_on(tmp_path: Path) -> None:
    """A virtual environment whose pip cannot run: one error line, status 1, the caller's next line runs."""
    broken = tmp_path / 'venv'
    (broken / 'bin').mkdir(parents=True)
    python = broken / 'bin' / 'python'
    python.write_text('#!/bin/sh\necho "no pip here" >&2\nexit 3\n')
    python.chmod(0o755)
    done = _bash(f'source {BOOTSTRAP}; echo "status $?"; echo still here; echo "PATH0=${{PATH%%:*}}"',
                 SMARTICLE_VENV=str(broken))
    out = done.stdout.splitlines()
    assert done.returncode == 0 and out[-3:-1] == ['status 1', 'still here'], (done.stdout, done.stderr)
    assert out[-1] != f'PATH0={broken}/bin'  # nothing half-made is put on PATH
    assert '[bootstrap] error: the set-up of' in done.stderr
    assert not (broken / '.smarticle-stamp').exists()
