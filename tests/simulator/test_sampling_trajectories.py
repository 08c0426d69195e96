"""Walking paths: geometry, timing and hand shake."""

import numpy as np
import pytest

from simulator.trajectories import (
    Area, hand_shake_deg, square_spiral, square_spiral_vertices, walking_yaw_deg, waypoints, zigzag,
    zigzag_vertices,
)

ROOM = Area(0.0, 0.0, 2.4, 3.6)


def test_zigzag_covers_the_area_with_legs_along_x():
    vertices = zigzag_vertices(ROOM, 0.6)
    assert vertices[0].tolist() == [0.0, 0.0] and vertices[-1][1] == pytest.approx(3.6)
    assert np.unique(np.round(vertices[:, 1], 9)).size == 7  # 0, 0.6, ..., 3.6
    legs = np.diff(vertices, axis=0)
    assert np.all((np.abs(legs[:, 0]) < 1e-12) | (np.abs(legs[:, 1]) < 1e-12))  # axis-aligned
    assert vertices[:, 0].min() == 0.0 and vertices[:, 0].max() == 2.4


def test_square_spiral_converges_inwards_and_stays_in_the_area():
    vertices = square_spiral_vertices(ROOM, 0.6)
    assert vertices[:4].tolist() == [[0, 0], [2.4, 0], [2.4, 3.6], [0, 3.6]]
    distance_to_border = np.minimum.reduce([vertices[:, 0], 2.4 - vertices[:, 0], vertices[:, 1], 3.6 - vertices[:, 1]])
    assert distance_to_border.min() >= -1e-9
    assert distance_to_border[-1] == pytest.approx(1.2)  # ends in the middle strip
    assert np.all(np.diff(distance_to_border[1:]) >= -1e-9)  # never moves back out


def test_waypoints_are_walked_at_constant_speed_and_frame_rate():
    path = waypoints(np.array([[0, 0], [3, 0], [3, 4]]), speed_mps=1.0, frame_interval_s=0.5, height_m=1.3)
    times = np.array([p.t_s for p in path])
    positions = np.array([p.position_m for p in path])
    assert len(path) == 15 and times[-1] == pytest.approx(7.0)  # 7 m at 1 m/s
    np.testing.assert_allclose(np.diff(times), 0.5)
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    np.testing.assert_allclose(steps[:5], 0.5)  # straight part: speed x interval
    assert positions[6].tolist() == pytest.approx([3.0, 0.0, 1.3])  # the corner at t = 3 s
    assert np.all(positions[:, 2] == 1.3)


def test_timed_paths_and_yaw():
    path = zigzag(ROOM, 0.6, speed_mps=1.0, frame_interval_s=0.5)
    assert path[0].position_m.tolist() == [0.0, 0.0, 1.32]
    assert walking_yaw_deg(path)[0] == pytest.approx(0.0)  # first leg goes east
    spiral = square_spiral(ROOM, 0.6, speed_mps=0.8, frame_interval_s=0.5)
    assert spiral[1].t_s == 0.5 and np.linalg.norm(spiral[1].position_m - spiral[0].position_m) == pytest.approx(0.4)


def test_hand_shake_is_smooth_deterministic_and_of_the_asked_size():
    times = np.arange(0, 120, 0.01)
    shake = hand_shake_deg(times, 0.8, seed=4)
    np.testing.assert_array_equal(shake, hand_shake_deg(times, 0.8, seed=4))
    assert np.std(shake, axis=0) == pytest.approx([0.8] * 3, rel=0.1)
    assert np.abs(np.diff(shake, axis=0)).max() < 0.8 * 2 * np.pi * 3.0 * 0.01 * 3  # bounded slope: smooth
    assert not np.allclose(shake, hand_shake_deg(times, 0.8, seed=5))


@pytest.mark.parametrize("call, field", [
    (lambda: zigzag_vertices(Area(1, 0, 0, 1), 0.5), "area"),
    (lambda: zigzag_vertices(ROOM, 0.0), "spacing_m"),
    (lambda: waypoints(np.zeros((2, 2)), 0.0, 0.5, 1.0), "speed_mps"),
    (lambda: waypoints(np.zeros((2, 2)), 1.0, 0.5), "height_m"),
    (lambda: waypoints(np.zeros((2, 4)), 1.0, 0.5), "points_m"),
])
def test_bad_input_names_the_field(call, field):
    with pytest.raises(ValueError, match=field):
        call()
