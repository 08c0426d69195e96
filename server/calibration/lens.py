"""A camera lens as calibration sees it: a pinhole with OpenCV's 5-coefficient distortion.

Pixel centres at integers; distortion (k1, k2, p1, p2, k3) in OpenCV's (and the contract's)
order acting on normalised coordinates: x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y +
p2 (r^2 + 2 x^2), y_d likewise with p1 and p2 exchanged; pixel = (fx x_d + cx, fy y_d + cy).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3")
PINHOLE_NAMES = ("fx", "fy", "cx", "cy")
# OpenCV's undistortion is an iteration; the default five rounds leave ~0.1 px at a phone's corners
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


@dataclass(frozen=True)
class Lens:
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def matrix(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def coefficients(self) -> np.ndarray:
        """The distortion as OpenCV takes it, padded to five coefficients."""
        return np.pad(np.asarray(self.distortion, float), (0, max(0, 5 - len(self.distortion))))

    def project(self, points_c: np.ndarray) -> np.ndarray:
        """Camera-frame points (N, 3), z > 0, to distorted pixels (N, 2)."""
        pixels, _ = cv2.projectPoints(
            np.asarray(points_c, float).reshape(-1, 3), np.zeros(3), np.zeros(3), self.matrix, self.coefficients
        )
        return pixels.reshape(-1, 2)

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """Distorted pixels (N, 2) to normalised undistorted coordinates (N, 2)."""
        points = np.asarray(pixels, float).reshape(-1, 1, 2)
        undistorted = cv2.undistortPointsIter(
            points, self.matrix, self.coefficients, np.eye(3), np.eye(3), UNDISTORT_CRITERIA
        )
        return undistorted.reshape(-1, 2)

    def distort(self, ideal_px: np.ndarray) -> np.ndarray:
        """Where the lens puts points (N, 2) that its own pinhole, without distortion, puts at `ideal_px`."""
        ideal = np.asarray(ideal_px, float).reshape(-1, 2)
        normalised = (ideal - [self.cx, self.cy]) / [self.fx, self.fy]
        return self.project(np.column_stack([normalised, np.ones(len(normalised))]))

    def shift_jacobian(self, normalised: np.ndarray) -> np.ndarray:
        """d(pixel) / d(k1, k2, p1, p2, k3) at normalised points (N, 2), shape (N, 2, 5): the shift is linear."""
        x, y = np.asarray(normalised, float).T
        r2 = x * x + y * y
        du = np.column_stack([x * r2, x * r2**2, 2 * x * y, r2 + 2 * x * x, x * r2**3]) * self.fx
        dv = np.column_stack([y * r2, y * r2**2, r2 + 2 * y * y, 2 * x * y, y * r2**3]) * self.fy
        return np.stack([du, dv], axis=1)


def frame_grid_px(width: int, height: int, cells: int = 32) -> np.ndarray:
    """Points (N, 2) of a grid over the whole frame, its border included, `cells` steps along the longer side."""
    step = max(width, height) / cells
    xs = np.linspace(0.0, width - 1.0, max(2, int(np.ceil(width / step)) + 1))
    ys = np.linspace(0.0, height - 1.0, max(2, int(np.ceil(height / step)) + 1))
    return np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)


def distortion_difference_px(true: Lens, fitted: Lens, width: int, height: int) -> float:
    """The largest |distort_true(p) - distort_fit(p)| (px) over the frame, each through its own pinhole.

    p runs over the ideal (pinhole) points of a grid of the frame's pixels as the true lens sees
    them, so the comparison covers exactly the frame: distort_true(p) is the grid point itself.
    """
    grid = frame_grid_px(width, height)
    rays = true.rays(grid)
    ideal = rays * [true.fx, true.fy] + [true.cx, true.cy]
    return float(np.linalg.norm(true.distort(ideal) - fitted.distort(ideal), axis=1).max())
