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
    ('smarticle_bringup', 'view.yaml', 'smarticle_bringup.view_node', 'NODE_NAME', 'PARAMS'),
]

#: The shared parameter file every launch file loads, and the nodes whose tables it must fit.
STACK = ROOT / 'smarticle_bringup' / 'config' / 'stack.yaml'
STACK_NODES = [('smarticle_driver.gait_node', 'PARAMS'), ('smarticle_sim.bridge', 'PARAMS'),
               ('smarticle_feedback.parameters', 'PARAMS'), ('smarticle_tracking.parameters', 'MONITOR_PARAMS')]


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
        if 'ros__parameters' in path.read_text(encoding='utf-8') and path != STACK:
            assert (folder, path.name) in checked, f'{path.relative_to(ROOT)} is not checked against a table'


def test_the_shared_stack_file_fits_every_node_that_reads_it() -> None:
    """stack.yaml: one /** section; each name is declared by a node that reads it, in range, of its type."""
    import yaml

    data = yaml.safe_load(STACK.read_text(encoding='utf-8'))
    assert list(data) == ['/**'], 'stack.yaml holds only settings shared by every node'
    shared = data['/**']['ros__parameters']
    tables: dict[str, list[ParamSpec]] = {}
    for module, attr in STACK_NODES:
        for spec in getattr(importlib.import_module(module), attr):
            tables.setdefault(spec.name, []).append(spec)
    faces = [f'{face}_{end}' for face in ('arm1_front', 'arm1_back', 'arm2_front', 'arm2_back')
             for end in ('min', 'max', 'enabled')]
    assert {'period', 'alpha_max_deg', 'start_at', *faces} <= set(shared)
    for name, value in shared.items():
        assert name in tables, f'stack.yaml: {name!r} is no parameter of gait, sim_bridge, feedback or glider_monitor'
        for spec in tables[name]:
            assert type(spec.check(value, 'stack.yaml')) is type(spec.default), name   # the node's type exactly
    readers = {name: len(specs) for name, specs in tables.items()}
    assert readers['period'] == 4 and readers['start_at'] == 4 and readers['alpha_max_deg'] == 2
