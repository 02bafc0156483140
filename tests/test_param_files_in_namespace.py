"""Every node applies its shipped parameter file when it runs in a robot namespace.

Each node is started as on a board, ``-r __ns:=/smarticle_0 --params-file <its config/*.yaml>``, with one
value of the shipped file changed, and the value is read back over the node's parameter service
(``/smarticle_0/<node>/get_parameters``, as ``ros2 param get`` does). A file with a bare ``<node>:`` key
fails this: rclpy applies it only to a node in the root namespace and the node keeps its default.
"""

from __future__ import annotations

import os
import signal
import socket
from pathlib import Path
from typing import Any

import yaml
from smarticle_common.params import node_key

from tests.helpers.bags import make_bag
from tests.helpers.params import get_parameter
from tests.test_config_files import TABLES

ROOT = Path(__file__).resolve().parents[1]
NAMESPACE = '/smarticle_0'


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return int(sock.getsockname()[1])


def _changes(tmp_path: Path) -> dict[str, tuple[str, str, Any, tuple[str, ...]]]:
    """yaml name -> (executable, parameter, a value other than the shipped one, more arguments the node needs
    to keep running: the recorder writes into tmp_path, the player waits before playing)."""
    bag = tmp_path / 'played'
    make_bag(bag, count=5)
    return {
        'gait.yaml': ('gait', 'heartbeat', 0.35, ()),
        'servo_bridge.yaml': ('servo_bridge', 'port', str(tmp_path / 'no_board'), ()),
        'feedback.yaml': ('feedback', 'arm1_front_max', 15.5, ()),
        'sim_bridge.yaml': ('sim_bridge', 'robots', 2, ()),
        'tracker.yaml': ('tracker', 'tag_size', 0.02, ()),
        'glider_monitor.yaml': ('glider_monitor', 'min_periods', 12, ()),
        'recorder.yaml': ('recorder', 'topics', '/smarticle_0/joint_states', ('-p', f'output:={tmp_path / "rec"}')),
        'player.yaml': ('player', 'bag', str(bag), ('-p', 'delay:=60.0')),
        'view.yaml': ('smarticle-view', 'port', _free_port(), ()),
    }


def test_each_node_in_a_robot_namespace_takes_its_shipped_file(nodes: Any, ros_node: Any, tmp_path: Path) -> None:
    changes = _changes(tmp_path)
    assert set(changes) == {name for _, name, *_ in TABLES}, 'a shipped node file is missing here'
    probe = ros_node('param_probe')
    for folder, yaml_name, module, node_attr, _ in TABLES:     # one node at a time: a busy machine answers
        node_name = getattr(__import__(module, fromlist=[node_attr]), node_attr)
        data = yaml.safe_load((ROOT / folder / 'config' / yaml_name).read_text(encoding='utf-8'))
        assert list(data) == [node_key(node_name)], f'{yaml_name}: the section must be {node_key(node_name)}'
        executable, name, value, more = changes[yaml_name]
        params = data[node_key(node_name)]['ros__parameters']
        assert name in params and params[name] != value
        params[name] = value
        edited = tmp_path / yaml_name
        edited.write_text(yaml.safe_dump(data), encoding='utf-8')
        proc = nodes.start(executable, '--ros-args', '-r', f'__ns:={NAMESPACE}', '--params-file', str(edited), *more)
        target = f'{NAMESPACE}/{node_name}'
        got = get_parameter(probe, target, name)
        assert got == value, f'{target}: {name} = {got!r}, the file says {value!r}\n{nodes.output(proc)}'
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=15)
