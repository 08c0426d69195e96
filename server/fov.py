"""The paper's field of view and test grid (Section III-A, equations 1-7)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shared_schemas import DeviceProfile


@dataclass(frozen=True)
class FovGrid:
    """Sizes are (width, height) in metres: width along image x / map X, height along y / Y."""

    sensor_m: tuple[float, float]  # eq. 2: S = R * P
    fov_m: tuple[float, float]  # eq. 3: S * D / f
    beacon_adjusted_m: tuple[float, float]  # eq. 4: S * D / f - B
    cells: tuple[int, int]  # eq. 5-6: floor(FOV / delta), made even
    grid_m: tuple[float, float]  # eq. 7: cells * delta
    cell_m: float

    @property
    def point_count(self) -> int:
        return (self.cells[0] + 1) * (self.cells[1] + 1)


def fov_grid(profile: DeviceProfile, distance_m: float, cell_m: float, beacon_side_m: float) -> FovGrid:
    """The beacon-adjusted FOV of `profile` at `distance_m`, paved with `cell_m` cells."""
    if distance_m <= 0 or cell_m <= 0 or beacon_side_m < 0:
        raise ValueError("distance and cell must be positive and the beacon side not negative")
    sensor = (profile.width * profile.pixel_size_m, profile.height * profile.pixel_size_m)
    fov = (sensor[0] * distance_m / profile.focal_length_m, sensor[1] * distance_m / profile.focal_length_m)
    adjusted = (fov[0] - beacon_side_m, fov[1] - beacon_side_m)
    cells = []
    for extent in adjusted:
        count = max(0, math.floor(extent / cell_m + 1e-9))
        cells.append(count - count % 2)
    return FovGrid(
        sensor_m=sensor,
        fov_m=fov,
        beacon_adjusted_m=adjusted,
        cells=(cells[0], cells[1]),
        grid_m=(cells[0] * cell_m, cells[1] * cell_m),
        cell_m=cell_m,
    )


def grid_points(grid: FovGrid) -> tuple[np.ndarray, np.ndarray]:
    """The test-bench points in the paper's order, from (-8, 11) to (8, -11).

    Returns (labels (N, 2) int cell coordinates, positions (N, 2) metres, origin at the centre).
    """
    half_x, half_y = grid.cells[0] // 2, grid.cells[1] // 2
    labels = np.array([(i, j) for j in range(half_y, -half_y - 1, -1) for i in range(-half_x, half_x + 1)])
    return labels, labels * grid.cell_m
