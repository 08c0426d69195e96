"""The paper's FOV and grid (Section III-A): 0.8 m x 1.1 m, 16 x 22 cells, 391 points."""

import pytest

from server.fov import fov_grid, grid_points
from shared_schemas import device_profiles


def test_paper_grid_for_the_mi8_front_camera_at_one_metre():
    grid = fov_grid(device_profiles()["xiaomi-mi8-front"], 1.0, 0.05, 0.174)
    assert grid.sensor_m == pytest.approx((3.492e-3, 4.6656e-3))
    assert grid.cells == (16, 22)
    assert grid.grid_m == pytest.approx((0.8, 1.1))
    assert grid.point_count == 391
    labels, positions = grid_points(grid)
    assert labels[0].tolist() == [-8, 11] and labels[-1].tolist() == [8, -11]
    assert positions[0] == pytest.approx([-0.4, 0.55])
    assert len(labels) == 391


def test_odd_cell_counts_are_made_even():
    grid = fov_grid(device_profiles()["xiaomi-mi8-front"], 1.0, 0.05, 0.174)
    # 1.151 m / 0.05 = 23 cells, made 22 by eq. 6
    assert grid.beacon_adjusted_m[1] / 0.05 == pytest.approx(23.03, abs=0.01)


def test_bad_geometry_is_refused():
    with pytest.raises(ValueError, match="positive"):
        fov_grid(device_profiles()["xiaomi-mi8-front"], 0.0, 0.05, 0.174)
