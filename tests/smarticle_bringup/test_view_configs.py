"""The shipped RViz config and Foxglove layout draw the robot models: the names they use are the contract's."""

from __future__ import annotations

import json
from pathlib import Path

import yaml
from smarticle_common import topics
from smarticle_common.robot_model import BODY_LINK, JOINTS, frame

from smarticle_bringup.view_node import SCENE_TOPIC, TF_CHANNEL

CONFIG = Path(__file__).resolve().parents[2] / 'smarticle_bringup' / 'config'


def _displays(displays: list[dict]) -> list[dict]:
    out = []
    for display in displays:
        out.append(display)
        out += _displays(display.get('Displays', []))
    return out


def test_rviz_robot_models_read_each_robots_description_with_its_tf_prefix() -> None:
    config = yaml.safe_load((CONFIG / 'smarticles.rviz').read_text())
    displays = _displays(config['Visualization Manager']['Displays'])
    models = [d for d in displays if d['Class'] == 'rviz_default_plugins/RobotModel']
    assert len(models) >= 2
    latched = topics.spec_of('robot_description').qos is topics.Qos.LATCHED
    for k, model in enumerate(models):
        assert model['Description Source'] == 'Topic'
        assert model['Description Topic']['Value'] == topics.topic('robot_description', k)
        assert (model['Description Topic']['Durability Policy'] == 'Transient Local') == latched
        # RViz names link L of the URDF "<TF prefix>/L": the frames robot_tf publishes
        for link in (BODY_LINK, *(link for _, link in JOINTS)):
            assert f'{model["TF Prefix"]}/{link}' == frame(k, link)
    assert any(d['Class'] == 'rviz_default_plugins/TF' for d in displays)
    assert config['Visualization Manager']['Global Options']['Fixed Frame'] == topics.ARENA_FRAME


def test_foxglove_layout_shows_the_scene_and_the_frames_of_the_live_view() -> None:
    layout = json.loads((CONFIG / 'foxglove_layout.json').read_text())
    panel = layout['configById']['3D!smarticles']
    assert panel['followTf'] == topics.ARENA_FRAME
    assert panel['topics'][SCENE_TOPIC]['visible'] and panel['topics'][TF_CHANNEL]['visible']
