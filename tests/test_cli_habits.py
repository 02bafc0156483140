"""Command-line habits of every console script outside smarticle_experiments.

Each answers ``--version``; each node executable answers ``--help`` with its parameters (names, defaults,
descriptions from its ParamSpec table) instead of starting; no help text names an issue; a script that
prints lists ends quietly (exit code 141, no traceback) when its reader has gone.
"""

from __future__ import annotations

import ast
import importlib
import os
import re
import subprocess
from pathlib import Path

import pytest
from smarticle_common.launching import executable
from smarticle_common.params import ParamSpec

ROOT = Path(__file__).resolve().parents[1]
SETUPS = sorted(p for p in [*ROOT.glob('*/setup.py'), *ROOT.glob('bags/*/setup.py'), *ROOT.glob('examples/*/setup.py')]
                if p.parent.name != 'smarticle_experiments')

#: Node executable -> (module, its parameter table).
NODES = {
    'gait': ('smarticle_driver.gait_node', 'PARAMS'),
    'servo_bridge': ('smarticle_driver.servo_bridge_core', 'PARAMS'),
    'feedback': ('smarticle_feedback.parameters', 'PARAMS'),
    'sim_bridge': ('smarticle_sim.bridge', 'PARAMS'),
    'tracker': ('smarticle_tracking.parameters', 'TRACKER_PARAMS'),
    'glider_monitor': ('smarticle_tracking.parameters', 'MONITOR_PARAMS'),
    'recorder': ('smarticle_bags.parameters', 'RECORDER_PARAMS'),
    'player': ('smarticle_bags.parameters', 'PLAYER_PARAMS'),
    'smarticle-view': ('smarticle_bringup.view_node', 'PARAMS'),
}
#: What no help text may carry: issue references and notes about this machine.
NOT_IN_HELP = re.compile(r'#\d|\bissue\b|at most 2 here', re.IGNORECASE)


def console_scripts() -> list[str]:
    """Every console script declared by the setup.py files (smarticle_experiments excepted)."""
    names = []
    for setup in SETUPS:
        for node in ast.walk(ast.parse(setup.read_text(encoding='utf-8'))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and re.fullmatch(
                    r'[\w-]+ = [\w.]+:\w+', node.value):
                names.append(node.value.split(' = ')[0])
    return sorted(names)


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([executable(args[0]), *args[1:]], capture_output=True, text=True, timeout=60,
                          env={**os.environ, 'ROS_DOMAIN_ID': os.environ.get('ROS_DOMAIN_ID', '0')})


def test_the_node_list_is_every_node_executable() -> None:
    scripts = set(console_scripts())
    assert set(NODES) <= scripts
    assert len(scripts) >= 18, scripts


@pytest.mark.parametrize('script', console_scripts())
def test_every_console_script_answers_version_and_help(script: str) -> None:
    version = run(script, '--version')
    assert version.returncode == 0, version.stderr
    assert re.fullmatch(rf'{re.escape(script)} \d+\.\d+\.\d+\S*\n', version.stdout), version.stdout   # the name typed
    shown = run(script, '--help')
    assert shown.returncode == 0, shown.stderr
    assert 'usage' in shown.stdout.lower()
    assert not NOT_IN_HELP.search(shown.stdout), NOT_IN_HELP.search(shown.stdout)


@pytest.mark.parametrize('node', sorted(NODES))
def test_a_node_executable_prints_its_parameters_instead_of_starting(node: str) -> None:
    module, table = NODES[node]
    specs: tuple[ParamSpec, ...] = getattr(importlib.import_module(module), table)
    shown = run(node, '--help')
    assert shown.returncode == 0 and '[INFO]' not in shown.stdout + shown.stderr, shown.stdout + shown.stderr
    for spec in specs:
        line = next((line for line in shown.stdout.splitlines() if line.startswith(f'  {spec.name} (')), None)
        assert line is not None, f'{node} --help does not list {spec.name}'
        assert type(spec.default).__name__ in line and 'default' in line
        assert spec.description.split()[0] in shown.stdout
    assert not NOT_IN_HELP.search(shown.stdout)


def test_a_listing_ends_quietly_when_its_reader_has_gone() -> None:
    """``smarticle-launch ... --show | head -0``: the pipe is closed before the first line."""
    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run([executable('smarticle-launch'), 'smarticle_bringup', 'sim.launch.xml', 'robots:=2',
                               '--show'], stdout=write, stderr=subprocess.PIPE, text=True, timeout=60)
    finally:
        os.close(write)
    assert done.returncode == 141 and 'Traceback' not in done.stderr, done.stderr
