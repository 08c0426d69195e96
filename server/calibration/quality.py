"""How good a calibration set is: where its corners fall, how its views are tilted, and how
uncertain the fitted distortion remains over the frame."""

from __future__ import annotations

import numpy as np

from server.calibration.lens import Lens, frame_grid_px

CORNER_CELLS = {"top-left": (0, 0), "top-right": (0, -1), "bottom-left": (-1, 0), "bottom-right": (-1, -1)}


def coverage_grid(points_px: np.ndarray, width: int, height: int, long_cells: int, short_cells: int) -> np.ndarray:
    """Corners per cell (rows, cols) of the image: `long_cells` along its longer side, rows top to bottom."""
    cols, rows = (long_cells, short_cells) if width >= height else (short_cells, long_cells)
    points = np.asarray(points_px, float).reshape(-1, 2)
    col = np.clip((points[:, 0] + 0.5) * cols // width, 0, cols - 1).astype(int)
    row = np.clip((points[:, 1] + 0.5) * rows // height, 0, rows - 1).astype(int)
    counts = np.zeros((rows, cols), int)
    np.add.at(counts, (row, col), 1)
    return counts


def tilt_deg(rotation: np.ndarray) -> float:
    """Angle between the board's normal (its rotation's third column) and the optical axis."""
    return float(np.degrees(np.arccos(np.clip(abs(rotation[2, 2]), 0.0, 1.0))))


def distortion_sigma_px(
    lens: Lens, distortion_covariance: np.ndarray, width: int, height: int
) -> tuple[float, np.ndarray]:
    """The largest 1-sigma image shift (px) the distortion's covariance (5, 5) leaves over a grid of the frame,
    and the grid point (x, y px) where it is largest.

    The shift is linear in (k1, k2, p1, p2, k3) (`Lens.shift_jacobian`); at each grid point the
    2x2 covariance J C J^T gives the largest sigma along any direction (its larger eigenvalue).
    """
    grid = frame_grid_px(width, height)
    jacobian = lens.shift_jacobian(lens.rays(grid))
    covariance = np.einsum("nij,jk,nlk->nil", jacobian, distortion_covariance, jacobian)
    largest = np.linalg.eigvalsh(covariance)[:, -1]
    worst = int(np.argmax(largest))
    return float(np.sqrt(max(0.0, float(largest[worst])))), grid[worst]


def image_part(point_px: np.ndarray, width: int, height: int) -> str:
    """Where a point lies, in words: "the top-left corner", "the left edge", "the centre" (thirds of the image)."""
    column = ("left", "", "right")[min(2, int(3 * point_px[0] // width))]
    row = ("top", "", "bottom")[min(2, int(3 * point_px[1] // height))]
    if row and column:
        return f"the {row}-{column} corner"
    return f"the {row or column} edge" if row or column else "the centre"
