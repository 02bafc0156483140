"""docs/own_controller.md says what is true: its test is the repository's, its arguments are the launch files'."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from smarticle_bringup.launch_files import parse_arguments, resolve
from smarticle_common.launching import executable

from tests.helpers.ros import ROOT

GUIDE = ROOT / 'docs' / 'own_controller.md'
LAUNCH = ROOT / 'smarticle_bringup' / 'launch'


def blocks(language: str) -> list[str]:
    return re.findall(rf'```{language}\n(.*?)```', GUIDE.read_text(encoding='utf-8'), flags=re.S)


def test_the_guides_test_is_the_file_in_the_repository() -> None:
    (code,) = blocks('python')
    assert code == (ROOT / 'tests' / 'examples' / 'test_square_stop.py').read_text(encoding='utf-8')


def test_the_guides_launch_command_resolves_to_the_example_controller() -> None:
    command = next(b for b in blocks('bash') if 'smarticle-launch' in b)
    words = shlex.split(command.replace('\\\n', ' '))
    assert words[1:3] == ['smarticle_bringup', 'sim.launch.xml']
    plan = resolve(LAUNCH / 'sim.launch.xml', parse_arguments(words[3:]))
    assert [n.executable for n in plan.nodes] == ['smarticle-compose', 'glider_monitor', 'square_stop', 'square_stop']


def test_every_argument_of_the_table_is_declared_by_the_launch_files() -> None:
    text = GUIDE.read_text(encoding='utf-8')
    table = text[text.index('## 3. Launch arguments'):text.index('## 4.')]
    names = re.findall(r'^\| `(\w+)` \|', table, flags=re.M)
    assert len(names) == 7
    sim = (LAUNCH / 'sim.launch.xml').read_text(encoding='utf-8')
    board = (LAUNCH / 'board.launch.xml').read_text(encoding='utf-8')
    for name in names:
        assert f'<arg name="{name}"' in sim, name
        if name not in ('controller_robots', 'feedback_robots', 'executor'):
            assert f'<arg name="{name}"' in board, name


def renamed_and_built(tmp_path: Path, rename: str) -> dict[str, str]:
    """Run ``rename`` in a workspace holding a copy of the example, colcon-build it; the sourced environment."""
    src = tmp_path / 'ws' / 'src'
    src.mkdir(parents=True)
    shutil.copytree(ROOT / 'examples', src / 'examples', ignore=shutil.ignore_patterns(
        '__pycache__', '*.egg-info', 'build', 'install', 'log'))
    subprocess.run(['bash', '-euo', 'pipefail', '-c', rename], cwd=src, check=True, timeout=60)
    shutil.rmtree(src / 'examples')
    colcon = Path(sys.executable).parent / 'colcon'
    result = subprocess.run([str(colcon), 'build', '--event-handlers', 'console_direct-'], cwd=tmp_path / 'ws',
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    out = subprocess.run(['bash', '-c', f'source {tmp_path}/ws/install/setup.bash && env -0'],
                         capture_output=True, check=True, timeout=60).stdout
    return dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)


def executable_of(env: dict[str, str], controller: str) -> subprocess.CompletedProcess[str]:
    """``smarticle-launch board.launch.xml controller:=CONTROLLER --show`` in ``env``: the program it would run."""
    return subprocess.run([executable('smarticle-launch'), 'smarticle_bringup', 'board.launch.xml',
                           f'controller:={controller}', 'feedback:=none', '--show'],
                          env=env, capture_output=True, text=True, timeout=60)


@pytest.mark.slow
def test_the_guides_rename_gives_a_package_colcon_installs_where_the_launcher_finds_it(tmp_path: Path) -> None:
    """The rename block of section 2, run as written: colcon puts the executable in lib/fold_on_touch and the
    launcher runs it from there; without setup.cfg's lines it lands elsewhere and the launcher says where it
    looked instead of running another program of that name (coreutils' fold)."""
    (rename,) = [textwrap.dedent(b) for b in blocks('bash') if 'sed -i' in b]
    env = renamed_and_built(tmp_path / 'full', rename)
    show = executable_of(env, 'fold_on_touch/fold')
    program = f'{tmp_path}/full/ws/install/fold_on_touch/lib/fold_on_touch/fold'
    assert show.returncode == 0 and show.stdout.splitlines()[1].split()[0] == program, show.stdout + show.stderr
    partial = rename.replace("grep -rl smarticle_example_controller . | xargs",
                             "grep -rl smarticle_example_controller . | grep -v setup.cfg | xargs")
    env = renamed_and_built(tmp_path / 'partial', partial)
    show = executable_of(env, 'fold_on_touch/fold')
    err = show.stderr.strip()
    assert show.returncode == 2 and '\n' not in err and not show.stdout, show.stdout + err
    assert f"executable 'fold' of package 'fold_on_touch' not found (looked in {tmp_path}/partial/ws/install/" \
           'fold_on_touch/lib/fold_on_touch' in err, err
