"""Undo the rolling shutter's skew of a turning camera (issue 13 item 3), from the frame's gyroscope rate.

A rolling shutter reads row r at r * skew / (rows - 1) after the first. A camera turning at omega
(its own frame, `FrameMeta.angular_velocity_camera_dps`) sees a fixed direction d at time t as
Rot(-omega t) d: a square on the ceiling comes out sheared and stretched by ~omega * fy * row time
per row, which the pose fit reads as a tilt (1 deg/s of hand tremor: 2-4 mm at 1 m on the
robustness bench). Turning each measured point's ray back by omega * (t(row) - t(reference row))
gives the panel as the camera saw it at the reference row's instant: the row of the points'
centre, so that the pose is the camera's when the panel's middle was read. The camera's travel
during the readout is not undone (no sensor gives it).
"""

from __future__ import annotations

import numpy as np

from shared_schemas import FrameMeta

# Beyond this turn over the points' rows (a 30 ms readout at ~400 deg/s) the frame is a smear and
# the small-turn model of a ray seen from one camera pose meaningless: the points are left alone.
MAX_TURN_RAD = 0.2


def row_time_s(meta: FrameMeta) -> float | None:
    """Seconds between the exposure starts of neighbouring rows of the full frame, or None when
    the frame does not say (no skew, or a single row)."""
    rows = meta.full_size[1]
    if not meta.rolling_shutter_skew_s or rows < 2:
        return None
    return meta.rolling_shutter_skew_s / (rows - 1)


def undo_readout_turn(points_px: np.ndarray, camera_matrix: np.ndarray, meta: FrameMeta) -> np.ndarray:
    """`points_px` (N, 2), undistorted pixels of this frame, as the camera would have seen them
    all at the instant its rolling shutter read their mean row; unchanged when the frame has no
    rotation rate or readout time."""
    points = np.asarray(points_px, dtype=float).reshape(-1, 2)
    rate = meta.angular_velocity_camera_dps
    step_s = row_time_s(meta)
    if rate is None or step_s is None or len(points) == 0 or not any(rate):
        return points
    omega = np.radians(np.asarray(rate, dtype=float))
    rays = np.column_stack([points, np.ones(len(points))]) @ np.linalg.inv(camera_matrix).T
    # rows of a crop are rows of the full frame shifted by its offset: only differences matter
    angles = (points[:, 1] - points[:, 1].mean()) * step_s * float(np.linalg.norm(omega))
    if np.abs(angles).max() > MAX_TURN_RAD:  # rates the contract allows, but no readable frame has
        return points
    axis = omega / np.linalg.norm(omega)
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    turned = rays * cos + np.cross(axis, rays) * sin + np.outer(rays @ axis, axis) * (1 - cos)  # Rodrigues
    projected = turned @ np.asarray(camera_matrix, dtype=float).T
    return projected[:, :2] / projected[:, 2:3]
