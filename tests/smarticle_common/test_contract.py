"""The topic contract: one module, one doc page, every entry resolvable and importable."""

from __future__ import annotations

from pathlib import Path

import pytest

from smarticle_common import topics

ROOT = Path(__file__).resolve().parents[2]


def test_doc_page_shows_the_same_table_as_the_module() -> None:
    doc = (ROOT / 'docs' / 'topics.md').read_text()
    assert topics.markdown_table() in doc, 'regenerate with: python -m smarticle_common.topics'


@pytest.mark.parametrize('spec', topics.TOPICS, ids=lambda s: s.key)
def test_every_message_type_imports_and_every_qos_builds(spec: topics.TopicSpec) -> None:
    cls = topics.message_class(spec.type)
    assert cls.__name__ == spec.type.rsplit('/', 1)[1]
    assert topics.qos_profile(spec.qos).depth >= 1


def test_per_robot_names_resolve_and_parse_back() -> None:
    name = topics.topic('fsr', 4)
    assert name == '/smarticle_4/fsr'
    assert topics.parse_robot_topic(name) == (4, 'fsr')
    assert topics.parse_robot_topic('/smarticle_4/unknown') is None
    assert topics.topic('poses') == '/smarticles/poses'


@pytest.mark.parametrize('bad', [-1, 1000, 1.5, '3', None, True])
def test_invalid_robot_ids_are_refused(bad: object) -> None:
    with pytest.raises(topics.ContractError, match='robot id'):
        topics.topic('joint_states', bad)  # type: ignore[arg-type]


def test_unknown_keys_and_malformed_types_are_refused() -> None:
    with pytest.raises(topics.ContractError, match='known'):
        topics.topic('joint_cmds', 0)
    with pytest.raises(topics.ContractError, match='pkg/msg/Name'):
        topics.message_class('JointState')


def test_an_unseen_robot_goes_out_finite_and_comes_back_as_nan() -> None:
    import math

    import numpy as np
    from geometry_msgs.msg import PoseArray
    from smarticle_common.messages import is_unseen, planar_poses, pose_message

    rows = np.array([[0.1, -0.2, 1.0], [np.nan, np.nan, np.nan], [0.0, 0.0, 0.0], [0.3, np.inf, 0.0]])
    msg = PoseArray(poses=[pose_message(row) for row in rows])
    values = [v for p in msg.poses for v in (p.position.x, p.position.y, p.position.z, p.orientation.x,
                                             p.orientation.y, p.orientation.z, p.orientation.w)]
    assert all(math.isfinite(v) for v in values)          # RViz refuses a PoseArray with a NaN in it
    for pose in msg.poses:                                 # every quaternion normalised
        q = pose.orientation
        assert math.isclose(q.x ** 2 + q.y ** 2 + q.z ** 2 + q.w ** 2, 1.0)
    assert [is_unseen(p) for p in msg.poses] == [False, True, False, True]
    assert msg.poses[1].position.z == topics.UNSEEN_Z and msg.poses[1].orientation.w == 1.0
    back = planar_poses(msg)
    assert np.allclose(back[[0, 2]], rows[[0, 2]])        # a robot at the origin is still seen
    assert np.all(np.isnan(back[[1, 3]]))
