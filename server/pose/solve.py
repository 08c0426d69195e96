"""Stage 8: the camera pose from the beacon's corners and centre (paper Section III-B4).

Vision only: OpenCV's SQPnP on the five points (four corners and the centre), polished
by Levenberg-Marquardt. Beside it IPPE_SQUARE gives the two local minima a planar square
always has; their reprojection-error ratio says how ambiguous the fix is. A high ratio
alone is harmless when both minima put the camera in the same place (a panel seen
face-on), so a fix is refused only when the ratio is high AND the two positions differ.

Gravity prior, two ways:
- "always": the tilt (pitch and roll) is taken from the gravity vector as it is, so the
  rays to the five points can be turned to a level camera, where the panel's image is a
  similarity of its map outline: four unknowns (yaw, height and the camera's x, y), solved
  linearly. Exact when the sensor is; its tilt error moves the fix by height x tilt.
- "auto" (default): a maximum a posteriori fit. Gauss-Newton over the six pose
  parameters minimises the reprojection residuals (divided by the corner noise) plus the
  angle between predicted and measured gravity (divided by the sensor's sigma), started
  from the vision solution (and from the gravity one when the square is nearly ambiguous
  or vision and gravity disagree by over 3 sigma). Each source weighs what it knows: a
  large, near panel fixes the tilt by perspective and gravity hardly moves it; a small,
  far one leans on gravity. The corner noise is the sides' measured position error
  (noise, and the slow pixel-locking wave of sides nearly aligned with the pixel grid;
  `subpixel.py`), with a floor (`corner_sigma_floor_px`) for what one frame cannot show,
  such as the residual of the lens calibration across the panel.

All image points here are undistorted pixel coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import cv2
import numpy as np

from server.geometry import beacon_corners_m, beacon_rotation, beacon_to_world, rotation_z
from server.outcomes import Refusal
from shared_schemas import Beacon, FailureReason


class GravityMode(StrEnum):
    auto = "auto"
    always = "always"
    never = "never"


@dataclass(frozen=True)
class PoseRules:
    max_ambiguity_ratio: float = 0.2
    max_ambiguous_disagreement_m: float = 0.005
    corner_sigma_floor_px: float = 0.01  # unmodelled errors: lens calibration residual across the panel


@dataclass(frozen=True)
class PoseSolution:
    position_m: np.ndarray  # (3,) camera optical centre, map frame
    rotation_wc: np.ndarray  # (3, 3)
    reprojection_error_px: float  # RMS over the five points
    ambiguity_ratio: float
    alternative_distance_m: float  # between the two IPPE minima's camera positions
    gravity_used: bool
    covariance_m2: np.ndarray | None = None  # (3, 3) of position_m, map frame


def _camera_in_map(beacon: Beacon, rvec: np.ndarray, tvec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position, R_wc) of the camera from a beacon-frame PnP solution."""
    rotation_cb, _ = cv2.Rodrigues(rvec)
    position_b = -rotation_cb.T @ tvec.ravel()
    position = beacon_to_world(beacon, position_b[None, :])[0]
    return position, beacon_rotation(beacon) @ rotation_cb.T


def _beacon_in_camera(beacon: Beacon, position: np.ndarray, rotation_wc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec) of the beacon frame in the camera, from the camera's pose in the map."""
    rotation_cw = rotation_wc.T @ beacon_rotation(beacon)
    rvec, _ = cv2.Rodrigues(rotation_cw)
    return rvec, (rotation_wc.T @ (np.asarray(beacon.center_m) - position)).reshape(3, 1)


def _rms(projected: np.ndarray, observed: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - observed) ** 2, axis=1))))


def _tilt_to_level(gravity_camera: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the measured gravity (camera frame) to map -Z."""
    g = np.asarray(gravity_camera, dtype=float) / np.linalg.norm(gravity_camera)
    down = np.array([0.0, 0.0, -1.0])
    axis = np.cross(g, down)
    sin_angle, cos_angle = np.linalg.norm(axis), float(g @ down)
    if sin_angle < 1e-12:
        return np.eye(3) if cos_angle > 0 else np.diag([1.0, -1.0, -1.0])
    rotation, _ = cv2.Rodrigues(axis / sin_angle * np.arctan2(sin_angle, cos_angle))
    return rotation


def pose_with_gravity(
    points_px: np.ndarray, beacon: Beacon, camera_matrix: np.ndarray, gravity_camera: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(position, R_wc) with pitch and roll fixed by gravity; points (5, 2) in model order.

    With R_wc = Rz(yaw) T (T levels the camera), a ray r_c hits the ceiling plane at
    P_xy = C_xy + h Rz(yaw) q with q = (T r_c)_xy / (T r_c)_z and h the panel's height
    above the camera: a 2D similarity from q to the map, linear in (h cos yaw, h sin yaw, C_xy).
    """
    tilt = _tilt_to_level(gravity_camera)
    rays = np.linalg.solve(camera_matrix, np.vstack([points_px.T, np.ones(len(points_px))]))
    level = tilt @ rays
    q = (level[:2] / level[2]).T
    model = np.vstack([beacon_corners_m(beacon), np.zeros(3)])
    world = beacon_to_world(beacon, model)
    # [Px, Py] = [[a, -b], [b, a]] q + C_xy, with a = h cos(yaw), b = h sin(yaw)
    design = np.zeros((2 * len(q), 4))
    design[0::2] = np.column_stack([q[:, 0], -q[:, 1], np.ones(len(q)), np.zeros(len(q))])
    design[1::2] = np.column_stack([q[:, 1], q[:, 0], np.zeros(len(q)), np.ones(len(q))])
    (a, b, cx, cy), *_ = np.linalg.lstsq(design, world[:, :2].ravel(), rcond=None)
    height = float(np.hypot(a, b))
    yaw_deg = float(np.degrees(np.arctan2(b, a)))
    position = np.array([cx, cy, world[0, 2] - height])
    return position, rotation_z(yaw_deg) @ tilt


def _orthonormal_pair(vector: np.ndarray) -> np.ndarray:
    """Two unit vectors (2, 3) orthogonal to `vector` and to each other."""
    x, y, z = vector
    # the cross product with the axis least aligned with `vector`, written out (np.cross is slow)
    first = (
        np.array([0.0, z, -y])
        if abs(x) <= min(abs(y), abs(z))
        else (np.array([-z, 0.0, x]) if abs(y) <= abs(z) else np.array([y, -x, 0.0]))
    )
    first /= np.linalg.norm(first)
    fx, fy, fz = first
    return np.array([first, [y * fz - z * fy, z * fx - x * fz, x * fy - y * fx]])


def _map_residuals(params, object_points, image_points, camera_matrix, across_gravity, weights):
    """Weighted residuals (2 N + 2,) and their Jacobian (2 N + 2, 6) of the MAP fit.

    params = (rvec, tvec) of the beacon frame in the camera; gravity is predicted as
    R_cb (0, 0, -1) (the beacon frame is level) and compared across the measured one.
    """
    pixel_weight, gravity_weight = weights
    projected, jacobian = cv2.projectPoints(object_points, params[:3], params[3:], camera_matrix, None)
    image = (projected.reshape(-1) - image_points.reshape(-1)) * pixel_weight
    rotation, rotation_jacobian = cv2.Rodrigues(params[:3])  # d R / d rvec, (3, 9) row-major R
    down_column = -rotation[:, 2]
    d_down = -rotation_jacobian.reshape(3, 3, 3)[:, :, 2].T  # (3 components, 3 rvec)
    tilt = across_gravity @ down_column * gravity_weight
    d_tilt = np.hstack([across_gravity @ d_down, np.zeros((2, 3))]) * gravity_weight
    return np.concatenate([image, tilt]), np.vstack([jacobian[:, :6] * pixel_weight, d_tilt])


def fuse_gravity(
    object_points: np.ndarray,
    image_points: np.ndarray,
    start: tuple[np.ndarray, np.ndarray],
    camera_matrix: np.ndarray,
    gravity_camera: np.ndarray,
    corner_sigma_px: float,
    gravity_sigma_deg: float,
    iterations: int = 6,
) -> tuple[np.ndarray, np.ndarray, float]:
    """(rvec, tvec, cost) minimising reprojection error / corner_sigma_px and gravity angle / sigma.

    Gauss-Newton from `start` (rvec, tvec); cost is the sum of squared weighted residuals
    (chi-square with 2 N + 2 terms), so that two starts can be compared.
    """
    g = np.asarray(gravity_camera, dtype=float)
    across = _orthonormal_pair(g / np.linalg.norm(g))
    weights = (1.0 / corner_sigma_px, 1.0 / np.radians(gravity_sigma_deg))
    params = np.concatenate([np.ravel(start[0]), np.ravel(start[1])]).astype(float)
    for _ in range(iterations):
        residuals, jacobian = _map_residuals(params, object_points, image_points, camera_matrix, across, weights)
        step = np.linalg.solve(jacobian.T @ jacobian, -(jacobian.T @ residuals))
        params = params + step
        if np.abs(step).max() < 1e-8:
            break
    residuals, _ = _map_residuals(params, object_points, image_points, camera_matrix, across, weights)
    return params[:3].reshape(3, 1), params[3:].reshape(3, 1), float(residuals @ residuals)


def _gravity_angle_deg(rvec: np.ndarray, gravity_camera: np.ndarray) -> float:
    """Angle between the gravity a pose predicts in the camera and the measured one."""
    predicted = -cv2.Rodrigues(rvec)[0][:, 2]
    measured = np.asarray(gravity_camera, dtype=float) / np.linalg.norm(gravity_camera)
    return float(np.degrees(np.arccos(np.clip(predicted @ measured, -1.0, 1.0))))


def _level_start(image_points, beacon: Beacon, camera_matrix, gravity_camera) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec) of the closed-form pose with the sensor's tilt."""
    return _beacon_in_camera(beacon, *pose_with_gravity(image_points, beacon, camera_matrix, gravity_camera))


def _map_pose(
    object_points,
    image_points,
    vision,
    beacon,
    camera_matrix,
    gravity_camera,
    corner_sigma_px: float,
    gravity_sigma_deg: float,
    try_level: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The MAP fit from the vision pose; also from the sensor's tilt when `try_level` or when
    the two disagree by over 3 sigma (vision may sit in the wrong one of a small square's two
    minima). The lower cost wins; a fit that puts the beacon behind the camera never does."""

    def fit(start):
        return fuse_gravity(
            object_points, image_points, start, camera_matrix, gravity_camera, corner_sigma_px, gravity_sigma_deg
        )

    candidates = [fit(vision)]
    if try_level or _gravity_angle_deg(candidates[0][0], gravity_camera) > 3 * gravity_sigma_deg:
        candidates.append(fit(_level_start(image_points, beacon, camera_matrix, gravity_camera)))
    in_front = [c for c in candidates if c[1][2, 0] > 0]
    if not in_front:
        return vision
    best = min(in_front, key=lambda c: c[2])
    return best[0], best[1]


def _ippe_square_minima(corners4, image_corners, camera_matrix) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """IPPE_SQUARE's local minima (reprojection error, rvec, tvec), best first; non-finite ones dropped."""
    count, rvecs, tvecs, errors = cv2.solvePnPGeneric(
        corners4, image_corners, camera_matrix, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
    )
    minima = [
        (float(e), r, t)
        for e, r, t in zip(np.ravel(errors)[:count], rvecs, tvecs, strict=False)
        if np.isfinite(e) and np.all(np.isfinite(r)) and np.all(np.isfinite(t))
    ]
    return sorted(minima, key=lambda m: m[0])


def _square_ambiguity(
    corners4, image_corners, beacon: Beacon, camera_matrix, nudge_px: float = 1e-3
) -> tuple[float, float]:
    """(error ratio of IPPE_SQUARE's two minima, distance between their camera positions, m).

    IPPE_SQUARE's closed form divides zero by zero (NaN poses, NaN errors) when the image of
    the square is exactly square and axis-aligned, a face-to-face view with the sides along
    the pixel grid (distance bench at 1.7 m, point (1, 0)). There the ratio is a limit, so
    it is taken a thousandth of a pixel away (a tenth of the corners' noise floor), which
    gives the same minima as any nearby view. If IPPE still finds fewer than two finite
    minima, no second pose was found: ratio and distance 0, as for a single solution.
    """
    minima = _ippe_square_minima(corners4, image_corners, camera_matrix)
    if len(minima) < 2:
        nudged = image_corners + np.array([[nudge_px, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
        minima = _ippe_square_minima(corners4, nudged, camera_matrix)
    if len(minima) < 2:
        return 0.0, 0.0
    (first, r0, t0), (last, r1, t1) = minima[0], minima[-1]
    ratio = (first + 1e-9) / (last + 1e-9)
    positions = [_camera_in_map(beacon, r, t)[0] for r, t in ((r0, t0), (r1, t1))]
    return float(ratio), float(np.linalg.norm(positions[0] - positions[1]))


def solve_pose(
    corners_px: np.ndarray,
    center_px: np.ndarray,
    beacon: Beacon,
    camera_matrix: np.ndarray,
    gravity_camera: np.ndarray | None = None,
    gravity_sigma_deg: float = 0.1,
    gravity_mode: GravityMode = GravityMode.auto,
    corner_sigma_px: float = 0.03,
    rules: PoseRules = PoseRules(),
) -> PoseSolution | Refusal:
    """Camera pose in the map from corners (4, 2) in model order and the centre (2,)."""
    corners4 = beacon_corners_m(beacon)
    object_points = np.vstack([corners4, np.zeros(3)])
    image_points = np.vstack([corners_px, center_px]).astype(np.float64)
    ok, rvec, tvec = cv2.solvePnP(object_points, image_points, camera_matrix, None, flags=cv2.SOLVEPNP_SQPNP)
    if not ok or tvec[2, 0] <= 0:
        return Refusal(FailureReason.pose_failed, "SQPnP found no pose with the beacon in front of the camera")
    rvec, tvec = cv2.solvePnPRefineLM(object_points, image_points, camera_matrix, None, rvec, tvec)

    ratio, disagreement = _square_ambiguity(corners4, image_points[:4], beacon, camera_matrix)

    corner_sigma = max(corner_sigma_px, rules.corner_sigma_floor_px)
    ambiguous = ratio > rules.max_ambiguity_ratio and disagreement > rules.max_ambiguous_disagreement_m
    use_gravity = gravity_camera is not None and gravity_mode is not GravityMode.never
    if ambiguous and not use_gravity:
        return Refusal(
            FailureReason.pose_ambiguous,
            f"two poses fit almost equally (error ratio {ratio:.2f}) and place the camera "
            f"{disagreement * 1000:.0f} mm apart; a gravity vector would decide",
        )
    if use_gravity and gravity_mode is GravityMode.always:
        rvec, tvec = _level_start(image_points, beacon, camera_matrix, gravity_camera)
    elif use_gravity:
        rvec, tvec = _map_pose(
            object_points,
            image_points,
            (rvec, tvec),
            beacon,
            camera_matrix,
            gravity_camera,
            corner_sigma,
            gravity_sigma_deg,
            try_level=ratio > rules.max_ambiguity_ratio / 4,
        )
    position, rotation_wc = _camera_in_map(beacon, rvec, tvec)
    projected, _ = cv2.projectPoints(object_points, rvec, tvec, camera_matrix, None)
    return PoseSolution(
        position_m=position,
        rotation_wc=rotation_wc,
        reprojection_error_px=_rms(projected, image_points),
        ambiguity_ratio=ratio,
        alternative_distance_m=disagreement,
        gravity_used=use_gravity,
    )
