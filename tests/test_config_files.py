"""Every node's shipped parameter file equals its declared parameter table (one check, every node)."""

from __future__ import annotations

import importlib
from pathlib import Path

import pytest
from smarticle_common.params import ParamSpec, read_defaults_yaml

ROOT = Path(__file__).resolve().parents[1]

#: (package folder, shipped YAML, module, node-name attribute, parameter-table attribute)
TABLES = [
    ('smarticle_driver', 'gait.yaml', 'smarticle_driver.gait_node', 'NODE_NAME', 'PARAMS'),
    ('smarticle_driver', 'servo_bridge.yaml', 'smarticle_driver.servo_bridge_core', 'NODE_NAME', 'PARAMS'),
    ('smarticle_sim', 'sim_bridge.yaml', 'smarticle_sim.bridge', 'NODE_NAME', 'PARAMS'),
    ('smarticle_feedback', 'feedback.yaml', 'smarticle_feedback.parameters', 'NODE_NAME', 'PARAMS'),
    ('smarticle_tracking', 'tracker.yaml', 'smarticle_tracking.parameters', 'TRACKER_NODE', 'TRACKER_PARAMS'),
    ('smarticle_tracking', 'glider_monitor.yaml', 'smarticle_tracking.parameters', 'MONITOR_NODE',
     'MONITOR_PARAMS'),
    ('bags/smarticle_bags', 'recorder.yaml', 'smarticle_bags.parameters', 'RECORDER_NODE', 'RECORDER_PARAMS'),
    ('bags/smarticle_bags', 'player.yaml', 'smarticle_bags.parameters', 'PLAYER_NODE', 'PLAYER_PARAMS'),
]


@pytest.mark.parametrize('folder, yaml_name, module, node_attr, params_attr', TABLES,
                         ids=[f'{t[0].split("/")[-1]}/{t[1]}' for t in TABLES])
def test_shipped_yaml_equals_declared_defaults(folder: str, yaml_name: str, module: str, node_attr: str,
                                               params_attr: str) -> None:
    mod = importlib.import_module(module)
    node: str = getattr(mod, node_attr)
    specs: tuple[ParamSpec, ...] = getattr(mod, params_attr)
    shipped = read_defaults_yaml(str(ROOT / folder / 'config' / yaml_name), node)
    assert shipped == {spec.name: spec.default for spec in specs}


def test_every_shipped_node_file_is_checked() -> None:
    """A new node's YAML cannot slip past: every config/*.yaml with ros__parameters is in TABLES."""
    checked = {(folder, name) for folder, name, *_ in TABLES}
    for path in sorted(ROOT.glob('*/config/*.yaml')) + sorted(ROOT.glob('bags/*/config/*.yaml')):
        folder = str(path.parent.parent.relative_to(ROOT))
        if 'ros__parameters' in path.read_text(encoding='utf-8'):
            assert (folder, path.name) in checked, f'{path.relative_to(ROOT)} is not checked against a table'
