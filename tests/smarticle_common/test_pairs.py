"""Pair coordinates r, theta, phi (paper Fig. 3(a)) on hand-placed poses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from smarticle_common.errors import PairInputError
from smarticle_common.pairs import (BODY_LENGTH, angular_distance, circular_mean, pair_centres,
                                     pair_coordinates, pair_indices, pair_position, to_body_lengths,
                                     one_pair, place_pair, wrap_2pi, wrap_pi)

UP = math.pi / 2    # robot faces +y: body axis (joint 1 -> joint 2) is +x


def coords_of(pose_i: tuple[float, float, float], pose_j: tuple[float, float, float]) -> tuple[float, ...]:
    """r, theta, phi of one hand-placed pair."""
    c = pair_coordinates(np.array([[pose_i, pose_j]]))
    return float(c.r[0, 0]), float(c.theta[0, 0]), float(c.phi[0, 0])


@pytest.mark.parametrize(('xy', 'theta'), [
    ((0.1, 0.0), 0.0),                  # on i's body axis, joint-2 side
    ((0.0, 0.1), math.pi / 2),          # straight ahead, on i's normal
    ((-0.1, 0.0), math.pi),             # joint-1 side
    ((0.0, -0.1), 3 * math.pi / 2),     # behind
    ((0.1, 0.1), math.pi / 4),
])
def test_theta_is_measured_from_the_body_axis_counter_clockwise(xy: tuple[float, float],
                                                                theta: float) -> None:
    r, got, _ = coords_of((0.0, 0.0, UP), (*xy, UP))
    assert r == pytest.approx(math.hypot(*xy))
    assert got == pytest.approx(theta)


def test_theta_follows_robot_i_heading_not_the_arena() -> None:
    # i faces +x, so its body axis points to -y; j at -y is at theta 0, j at +x straight ahead.
    assert coords_of((1.0, 2.0, 0.0), (1.0, 1.9, 0.0))[1] == pytest.approx(0.0, abs=1e-12)
    assert coords_of((1.0, 2.0, 0.0), (1.1, 2.0, 0.0))[1] == pytest.approx(math.pi / 2)


def test_theta_wraps_just_below_the_axis_to_near_two_pi() -> None:
    eps = 1e-3
    _, theta, _ = coords_of((0.0, 0.0, UP), (0.1 * math.cos(-eps), 0.1 * math.sin(-eps), UP))
    assert theta == pytest.approx(2 * math.pi - eps)
    assert 0.0 <= theta < 2 * math.pi


@pytest.mark.parametrize(('h_i', 'h_j', 'phi'), [
    (UP, UP + math.pi, math.pi),                                    # C1: anti-aligned
    (UP, UP, 0.0),                                                  # C2: aligned
    (math.radians(350), math.radians(10), math.radians(20)),        # wraps forward across 0
    (math.radians(10), math.radians(350), math.radians(340)),       # wraps backward: never negative
    (-3 * math.pi, 3 * math.pi, 0.0),                               # whole turns vanish
])
def test_phi_is_heading_difference_wrapped(h_i: float, h_j: float, phi: float) -> None:
    got = coords_of((0.0, 0.0, h_i), (0.1, 0.0, h_j))[2]
    assert 0.0 <= got < 2 * math.pi
    assert float(angular_distance(got, phi)) == pytest.approx(0.0, abs=1e-9)


def test_pair_order_matters_as_defined() -> None:
    pose_i, pose_j = (0.0, 0.0, UP), (0.1, 0.05, UP + 2.0)
    _, theta_ij, phi_ij = coords_of(pose_i, pose_j)
    _, theta_ji, phi_ji = coords_of(pose_j, pose_i)
    assert phi_ij + phi_ji == pytest.approx(2 * math.pi)
    assert theta_ij != pytest.approx(theta_ji)


def test_coordinates_do_not_depend_on_the_arena_frame() -> None:
    rng = np.random.default_rng(3)
    poses = np.concatenate([rng.uniform(-0.3, 0.3, (50, 5, 2)), rng.uniform(-4, 4, (50, 5, 1))], axis=2)
    turn, shift = 1.1, np.array([0.7, -0.2])
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    moved = poses.copy()
    moved[..., :2] = poses[..., :2] @ rot.T + shift
    moved[..., 2] += turn
    a, b = pair_coordinates(poses), pair_coordinates(moved)
    np.testing.assert_allclose(a.r, b.r, atol=1e-12)
    np.testing.assert_allclose(angular_distance(a.theta, b.theta), 0.0, atol=1e-9)
    np.testing.assert_allclose(angular_distance(a.phi, b.phi), 0.0, atol=1e-9)


def test_all_pairs_over_frames_have_shape_t_by_p() -> None:
    poses = np.zeros((4, 7, 3))
    poses[:, :, 0] = np.arange(7) * 0.1
    c = pair_coordinates(poses)
    assert c.r.shape == c.theta.shape == c.phi.shape == (4, 21)
    assert c.pairs.shape == (21, 2)
    p = pair_position(c.pairs, 5, 2)
    assert tuple(c.pairs[p]) == (2, 5)
    assert c.r[0, p] == pytest.approx(0.3)


def test_pair_indices_are_upper_triangle_in_order() -> None:
    assert pair_indices(3).tolist() == [[0, 1], [0, 2], [1, 2]]
    with pytest.raises(PairInputError):
        pair_indices(1)


def test_unseen_robot_gives_nan_only_for_its_pairs() -> None:
    poses = np.array([[[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]]], dtype=float)
    poses[0, 1, 2] = np.nan          # one bad component: the whole pose counts as unseen
    c = pair_coordinates(poses)
    assert np.isnan(c.r[0, 0]) and np.isnan(c.phi[0, 2]) and np.isnan(c.theta[0, 0])
    assert c.r[0, 1] == pytest.approx(0.2)
    assert np.all(np.isnan(pair_centres(poses)[0, [0, 2]]))
    poses[0, 2, 0] = np.inf          # inf is unseen too
    assert np.isnan(pair_coordinates(poses).r[0, 1])


def test_bad_pose_shapes_are_rejected_with_a_value_error() -> None:
    with pytest.raises(PairInputError, match=r'\(T, N, 3\)'):
        pair_coordinates(np.zeros((5, 3, 2)))
    with pytest.raises(ValueError, match='at least 2'):
        pair_coordinates(np.zeros((5, 1, 3)))


def test_wrap_angle_and_units() -> None:
    assert float(wrap_2pi(-1e-18)) == 0.0       # np.mod alone would give exactly 2 pi
    assert float(wrap_2pi(-math.pi / 2)) == pytest.approx(1.5 * math.pi)
    assert np.isnan(wrap_2pi(np.nan))
    assert float(to_body_lengths(0.108)) == pytest.approx(2.0)
    assert BODY_LENGTH == 0.054
    assert float(to_body_lengths(0.1, body_length=0.05)) == pytest.approx(2.0)
    with pytest.raises(PairInputError):
        to_body_lengths(1.0, body_length=0.0)


def test_circular_mean_handles_wrap_and_empty() -> None:
    angles = np.array([0.1, 2 * math.pi - 0.1])
    mean = circular_mean(np.cos(angles).sum(), np.sin(angles).sum(), 2)
    assert float(angular_distance(mean, 0.0)) == pytest.approx(0.0, abs=1e-12)
    assert np.isnan(circular_mean(0.0, 0.0, 0))
    assert np.isnan(circular_mean(0.0, 0.0, 2))    # opposite angles cancel: no mean direction


def test_place_pair_inverts_pair_coordinates() -> None:
    pose1 = (0.1, -0.05, 0.7)
    r, theta, phi = 1.3 * 0.054, math.radians(60), math.radians(200)
    pose2 = place_pair(pose1, r, theta, phi)
    assert np.allclose(one_pair(pose1, pose2), (r, theta, phi))
    assert -math.pi <= pose2[2] < math.pi
    # theta = 0 is along robot 1's body x axis (its arm-2 side), 90 deg straight ahead along its normal
    side = place_pair((0.0, 0.0, math.pi / 2), 1.0, 0.0, 0.0)
    ahead = place_pair((0.0, 0.0, math.pi / 2), 1.0, math.pi / 2, 0.0)
    assert np.allclose(side[:2], (1.0, 0.0)) and np.allclose(ahead[:2], (0.0, 1.0))


def test_wrap_pi_is_the_heading_range() -> None:
    assert wrap_pi(math.pi) == pytest.approx(-math.pi)
    assert wrap_pi(-math.pi) == pytest.approx(-math.pi)
    assert wrap_pi(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
