"""robot_tf's pure part: the transforms of every robot from poses and arm angles, and bad input refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from smarticle_common.facts import SMALL
from smarticle_common.robot_model import robot_frames
from smarticle_common.robot_tf import body_position, robot_transforms, transform_messages


def test_each_seen_robot_gets_its_three_frames_and_an_unseen_one_none() -> None:
    poses = np.array([[0.1, -0.05, 0.4], [math.nan, math.nan, math.nan], [-0.2, 0.03, -2.0]])
    arms = np.array([[0.5, -1.0], [0.0, 0.0], [math.nan, 1.2]])
    frames = robot_transforms(poses, arms, SMALL)
    assert [t.child for t in frames] == [f'smarticle_{k}/{link}' for k in (0, 2)
                                         for link in ('body', 'arm1_link', 'arm2_link')]
    expected = robot_frames(2, body_position(SMALL, -0.2, 0.03), (0.0, 0.0, math.sin(-1.0), math.cos(-1.0)),
                            (0.0, 1.2), SMALL)   # a non-finite arm angle counts as 0
    assert frames[3:] == expected
    assert frames[0].translation == pytest.approx((0.1, -0.05, SMALL.body_height / 2.0))


def test_messages_carry_the_same_transforms_and_the_stamp() -> None:
    from builtin_interfaces.msg import Time

    poses, arms = np.array([[0.02, 0.01, 1.0]]), np.array([[0.3, 0.7]])
    stamp = Time(sec=3, nanosec=250)
    messages = transform_messages(poses, arms, SMALL, stamp)
    for msg, t in zip(messages, robot_transforms(poses, arms, SMALL), strict=True):
        assert (msg.header.frame_id, msg.child_frame_id, msg.header.stamp) == (t.parent, t.child, stamp)
        r, v = msg.transform.rotation, msg.transform.translation
        assert (v.x, v.y, v.z) == t.translation and (r.x, r.y, r.z, r.w) == t.rotation


def test_mismatched_rows_are_refused_with_the_counts() -> None:
    with pytest.raises(ValueError, match='2 poses but 1 rows'):
        robot_transforms(np.zeros((2, 3)), np.zeros((1, 2)), SMALL)
    with pytest.raises(ValueError, match='two arm angles'):
        robot_transforms(np.zeros((1, 3)), np.zeros((1, 3)), SMALL)
