"""docs/own_controller.md says what is true: its test is the repository's, its arguments are the launch files'."""

from __future__ import annotations

import re
import shlex

from smarticle_bringup.launch_files import parse_arguments, resolve

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
    assert [n.executable for n in plan.nodes] == ['smarticle-compose', 'square_stop', 'square_stop']


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
