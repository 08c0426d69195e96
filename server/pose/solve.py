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
  from the vision solution, IPPE_SQUARE's best minimum (SQPnP's only when IPPE has none in
  front of the camera; both lead the fit to the same minimum: the same fixes on the benches),
  and from the gravity one when the square is nearly ambiguous or vision and gravity disagree
  by over 3 sigma. Each source weighs what it knows: a
  large, near panel fixes the tilt by perspective and gravity hardly moves it; a small,
  far one leans on gravity. The corner noise is the sides' measured position error
  (noise, and the slow pixel-locking wave of sides nearly aligned with the pixel grid;
  `subpixel.py`), with a floor (`corner_sigma_floor_px`) for what one frame cannot show,
  such as the residual of the lens calibration across the panel.

The position's covariance (`PoseSolution.covariance_m2`) is that of the fit that gave the pose,
by the chain rule from the corners' noise (`corner_covariance`, see there for what it holds):
the sandwich H^-1 J^T N J H^-1 of the fit's own weights (so the centre, which is computed
from the corners and adds nothing they do not know, enters with its true correlation), with
the gravity sensor's sigma for the tilt residual; "always" pins the tilt to the sensor's, so
its covariance is that of the constrained fit. A frame whose corners are further from any
view of the panel than their noise allows (errors the sides' own residuals cannot show, such
as a brightness gradient along a not quite saturated edge) has its corner noise scaled by
the fit's chi-square per degree of freedom (`consistency_factor`).

All image points here are undistorted pixel coordinates.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from enum import StrEnum
from functools import lru_cache

import cv2
import numpy as np

from server.geometry import angle_deg, beacon_corners_m, orthonormal_pair, rotation_z
from server.outcomes import Refusal
from server.pose.consistency import FitResiduals, chi_square
from server.vision.subpixel import MIN_LOCKING_PERIOD_PX, EdgeRules
from shared_schemas import Beacon, FailureReason


class GravityMode(StrEnum):
    auto = "auto"
    always = "always"
    never = "never"


@dataclass(frozen=True)
class PoseRules:
    max_ambiguity_ratio: float = 0.2
    max_ambiguous_disagreement_m: float = 0.005
    corner_sigma_floor_px: float = 0.01  # the fits' weights: lens calibration residual across the panel
    # The covariance's noise model (`corner_covariance`): what the sides' measured error leaves out.
    # Each side's crossings sit on OpenCV's 1/32 px sampling grid (~0.009 px rms), ~100 per side:
    side_sigma_floor_px: float = 0.001
    # rms of a level crossing's pixel-locking error (the Fourier term `subpixel.py` fits, 0.058-0.065 px
    # on the tilt bench's frames, PSF 1 px): the corner arcs keep it, and so does a side along the
    # pixel grid, as an offset, when no side crosses the grid (then nothing is fitted)
    pixel_locking_sigma_px: float = 0.06
    # a panel whose corner radius is under EdgeRules.min_corner_radius_px has its sides at the mid
    # level, out by the whole clipped-edge growth (a fraction of a pixel to a few pixels)
    unmeasured_growth_sigma_px: float = 1.0
    # scale the corner noise by the fit's chi-square per degree of freedom when above 1 (`consistency_factor`)
    consistency_scaling: bool = True
    consistency_chi_square: float = 9.21


@dataclass(frozen=True)
class PoseSolution:
    position_m: np.ndarray  # (3,) camera optical centre, map frame
    rotation_wc: np.ndarray  # (3, 3)
    reprojection_error_px: float  # RMS over the five points
    ambiguity_ratio: float
    alternative_distance_m: float  # between the two IPPE minima's camera positions
    gravity_used: bool
    covariance_m2: np.ndarray | None = None  # (3, 3) of position_m, map frame
    consistency_factor: float = 1.0  # corner noise scale from the fit's chi-square (>= 1)
    # the corners' (and the tilt's) residuals with their measured noise, for `consistency.check_fit`;
    # None when the noise model could not be built (a degenerate quad)
    residuals: FitResiduals | None = None


@lru_cache(maxsize=256)
def _beacon_frame(bits: bytes) -> tuple[np.ndarray, np.ndarray]:
    yaw_deg, *center_m = struct.unpack("<4d", bits)
    rotation = rotation_z(yaw_deg)
    center = np.array(center_m)
    rotation.setflags(write=False)
    center.setflags(write=False)
    return rotation, center


def beacon_frame(beacon: Beacon) -> tuple[np.ndarray, np.ndarray]:
    """(R_wb (3, 3), centre (3,) m) of `beacon` in the map, read-only: the same numbers as
    `geometry.beacon_rotation` and `beacon.center_m`, made once per beacon (a pose uses them ~5 times)."""
    # keyed by the floats' exact bits (one pack, not four float.hex): -0.0 and 0.0 are equal keys
    # but not the same numbers
    return _beacon_frame(struct.pack("<4d", beacon.yaw_deg, *beacon.center_m))


def _beacon_to_map(beacon: Beacon, points_b: np.ndarray) -> np.ndarray:
    """`geometry.beacon_to_world`, the same arithmetic, with the beacon's frame made once."""
    rotation_wb, center = beacon_frame(beacon)
    return points_b @ rotation_wb.T + center


def _camera_in_map(beacon: Beacon, rvec: np.ndarray, tvec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position, R_wc) of the camera from a beacon-frame PnP solution."""
    rotation_cb, _ = cv2.Rodrigues(rvec)
    position_b = -rotation_cb.T @ tvec.ravel()
    rotation_wb, center = beacon_frame(beacon)
    position = (position_b[None, :] @ rotation_wb.T + center)[0]  # _beacon_to_map's arithmetic
    return position, rotation_wb @ rotation_cb.T


def _beacon_in_camera(beacon: Beacon, position: np.ndarray, rotation_wc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec) of the beacon frame in the camera, from the camera's pose in the map."""
    rotation_wb, center = beacon_frame(beacon)
    rvec, _ = cv2.Rodrigues(rotation_wc.T @ rotation_wb)
    return rvec, (rotation_wc.T @ (center - position)).reshape(3, 1)


def _rms(projected: np.ndarray, observed: np.ndarray) -> float:
    """RMS distance (px) of the projected points (N, 1, 2) from the observed (N, 2): plain floats, the
    same sums in the same order as numpy's for the five points."""
    values = (projected.reshape(-1) - observed.reshape(-1)).tolist()
    squares = [dx * dx + dy * dy for dx, dy in zip(values[0::2], values[1::2], strict=True)]
    return math.sqrt(sum(squares) / len(squares))


def _tilt_to_level(gravity_camera: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the measured gravity (camera frame) to map -Z."""
    g = np.asarray(gravity_camera, dtype=float) / np.linalg.norm(gravity_camera)
    down = np.array([0.0, 0.0, -1.0])
    gx, gy, gz = g.tolist()
    # np.cross(g, down) written out, term for term (np.cross costs ~20 us a call on 3-vectors)
    axis = np.array([gy * -1.0 - gz * 0.0, gz * 0.0 - gx * -1.0, gx * 0.0 - gy * 0.0])
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
    world = _beacon_to_map(beacon, model)
    # [Px, Py] = [[a, -b], [b, a]] q + C_xy, with a = h cos(yaw), b = h sin(yaw)
    design = np.zeros((2 * len(q), 4))
    design[0::2, 0], design[0::2, 1], design[0::2, 2] = q[:, 0], -q[:, 1], 1.0
    design[1::2, 0], design[1::2, 1], design[1::2, 3] = q[:, 1], q[:, 0], 1.0
    (a, b, cx, cy), *_ = np.linalg.lstsq(design, world[:, :2].ravel(), rcond=None)
    height = float(np.hypot(a, b))
    yaw_deg = float(np.degrees(np.arctan2(b, a)))
    position = np.array([cx, cy, world[0, 2] - height])
    return position, rotation_z(yaw_deg) @ tilt


def _map_residuals(params, object_points, image_points, camera_matrix, across_gravity, weights):
    """Weighted residuals (2 N + 2,) and their Jacobian (2 N + 2, 6) of the MAP fit.

    params = (rvec, tvec) of the beacon frame in the camera; gravity is predicted as
    R_cb (0, 0, -1) (the beacon frame is level) and compared across the measured one.
    image_points (2 N,) flat; across_gravity: its two rows as tuples of floats. This runs 3-7 times
    a fit: the two tilt rows in plain floats, the rest into arrays made once.
    """
    pixel_weight, gravity_weight = weights
    projected, jacobian = cv2.projectPoints(object_points, params[:3], params[3:], camera_matrix, None)
    rotation, rotation_jacobian = cv2.Rodrigues(params[:3])  # d R / d rvec, (3, 9) row-major R
    image_terms = len(image_points)
    residuals = np.empty(image_terms + 2)
    np.multiply(projected.reshape(-1) - image_points, pixel_weight, out=residuals[:image_terms])
    full_jacobian = np.empty((image_terms + 2, 6))
    np.multiply(jacobian[:, :6], pixel_weight, out=full_jacobian[:image_terms])
    down = [-value for value in rotation[:, 2].tolist()]  # the predicted gravity, -R[:, 2]
    d_down = [[-value for value in column] for column in rotation_jacobian[:, 2::3].tolist()]  # [rvec i][component]
    tilt_residuals, tilt_rows = [], []
    for ax, ay, az in across_gravity:
        tilt_residuals.append((ax * down[0] + ay * down[1] + az * down[2]) * gravity_weight)
        tilt_rows.append([(ax * d[0] + ay * d[1] + az * d[2]) * gravity_weight for d in d_down] + [0.0, 0.0, 0.0])
    residuals[image_terms:] = tilt_residuals
    full_jacobian[image_terms:] = tilt_rows
    return residuals, full_jacobian


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class _MapFit:
    """The MAP fit's terms (`_map_residuals`): made once, fitted from one or two starts."""

    object_points: np.ndarray
    image_points: np.ndarray  # (2 N,) x0 y0 x1 y1 ...
    camera_matrix: np.ndarray
    across_gravity: tuple[tuple[float, float, float], ...]  # two unit vectors across the measured gravity
    weights: tuple[float, float]  # 1 / corner sigma (px), 1 / gravity sigma (rad)

    @classmethod
    def of(cls, object_points, image_points, camera_matrix, gravity_camera, corner_sigma_px, gravity_sigma_deg):
        g = np.asarray(gravity_camera, dtype=float)
        across = tuple(tuple(row) for row in orthonormal_pair(g / np.linalg.norm(g)).tolist())
        weights = (1.0 / corner_sigma_px, 1.0 / math.radians(gravity_sigma_deg))
        return cls(object_points, image_points.reshape(-1), camera_matrix, across, weights)

    def residuals(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _map_residuals(
            params, self.object_points, self.image_points, self.camera_matrix, self.across_gravity, self.weights
        )

    def fit(self, start: tuple[np.ndarray, np.ndarray], iterations: int = 6) -> np.ndarray:
        """The parameters (rvec, tvec) (6,) Gauss-Newton reaches from `start` (rvec, tvec)."""
        params = np.concatenate([np.ravel(start[0]), np.ravel(start[1])]).astype(float)
        for _ in range(iterations):
            residuals, jacobian = self.residuals(params)
            normal, gradient = jacobian.T @ jacobian, jacobian.T @ residuals
            ok, step = cv2.solve(normal, gradient, flags=cv2.DECOMP_LU)  # numpy's solve costs twice OpenCV's here
            if not ok:  # singular: numpy's solve raises as before (LinAlgError)
                step = np.linalg.solve(normal, gradient)
            params = params - step.ravel()
            if np.abs(step).max() < 1e-8:
                break
        return params

    def cost(self, params: np.ndarray) -> float:
        """The sum of squared weighted residuals at `params` (chi-square with 2 N + 2 terms)."""
        residuals, _ = self.residuals(params)
        return float(residuals @ residuals)


def _gravity_angle_deg(rvec: np.ndarray, gravity_camera: np.ndarray) -> float:
    """Angle between the gravity a pose predicts in the camera and the measured one."""
    return angle_deg(-cv2.Rodrigues(rvec)[0][:, 2], gravity_camera)


def _level_start(image_points, beacon: Beacon, camera_matrix, gravity_camera) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec) of the closed-form pose with the sensor's tilt."""
    return _beacon_in_camera(beacon, *pose_with_gravity(image_points, beacon, camera_matrix, gravity_camera))


SQPNP_FAILED = "SQPnP found no pose with the beacon in front of the camera"


def _vision_pose(object_points, image_points, camera_matrix) -> tuple[np.ndarray, np.ndarray] | None:
    """(rvec, tvec) of OpenCV's SQPnP on the five points polished by Levenberg-Marquardt, None
    when SQPnP finds no pose with the beacon in front of the camera."""
    ok, rvec, tvec = cv2.solvePnP(object_points, image_points, camera_matrix, None, flags=cv2.SOLVEPNP_SQPNP)
    if not ok or tvec[2, 0] <= 0:
        return None
    return cv2.solvePnPRefineLM(object_points, image_points, camera_matrix, None, rvec, tvec)


def _map_pose(
    object_points,
    image_points,
    start,
    beacon,
    camera_matrix,
    gravity_camera,
    corner_sigma_px: float,
    gravity_sigma_deg: float,
    try_level: bool,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The MAP fit from `start` (the vision pose); also from the sensor's tilt when `try_level` or
    when the two disagree by over 3 sigma (vision may sit in the wrong one of a small square's two
    minima). The lower cost wins; a fit that puts the beacon behind the camera never does (None
    when both do)."""

    terms = _MapFit.of(object_points, image_points, camera_matrix, gravity_camera, corner_sigma_px, gravity_sigma_deg)
    candidates = [terms.fit(start)]
    if try_level or _gravity_angle_deg(candidates[0][:3], gravity_camera) > 3 * gravity_sigma_deg:
        candidates.append(terms.fit(_level_start(image_points, beacon, camera_matrix, gravity_camera)))
    in_front = [params for params in candidates if params[5] > 0]
    if not in_front:
        return None
    # the costs only to choose between two fits (each is one more evaluation)
    best = in_front[0] if len(in_front) == 1 else min(in_front, key=terms.cost)
    return best[:3].reshape(3, 1), best[3:].reshape(3, 1)


def _ippe_square_minima(corners4, image_corners, camera_matrix) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """IPPE_SQUARE's local minima (reprojection error, rvec, tvec), best first; non-finite ones dropped."""
    count, rvecs, tvecs, errors = cv2.solvePnPGeneric(
        corners4, image_corners, camera_matrix, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
    )
    minima = [
        (e, r, t)
        for e, r, t in zip(np.ravel(errors)[:count].tolist(), rvecs, tvecs, strict=False)
        if math.isfinite(e) and all(map(math.isfinite, [*r.ravel().tolist(), *t.ravel().tolist()]))
    ]
    return sorted(minima, key=lambda m: m[0])


def _square_ambiguity(
    corners4, image_corners, beacon: Beacon, camera_matrix, nudge_px: float = 1e-3
) -> tuple[float, float, tuple[np.ndarray, np.ndarray] | None]:
    """(error ratio of IPPE_SQUARE's two minima, distance between their camera positions, m, the
    best minimum's (rvec, tvec) or None).

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
    best = (minima[0][1], minima[0][2]) if minima else None
    if len(minima) < 2:
        return 0.0, 0.0, best
    (first, r0, t0), (last, r1, t1) = minima[0], minima[-1]
    ratio = (first + 1e-9) / (last + 1e-9)
    apart = _camera_in_map(beacon, r0, t0)[0] - _camera_in_map(beacon, r1, t1)[0]
    return float(ratio), math.sqrt(float(apart @ apart)), best  # np.linalg.norm's arithmetic


def _side_geometry(corners: np.ndarray) -> tuple[list[tuple[float, float]], list[float], list[float]]:
    """Unit outward normals of the sides (side k joins corner k to corner k + 1), their lengths,
    and how far each runs across its outward axis (px: the smaller of its x and y extents).

    Plain floats: for four corners Python arithmetic is several times faster than numpy's calls.
    """
    points = corners.tolist()
    mean_x, mean_y = sum(p[0] for p in points) / 4.0, sum(p[1] for p in points) / 4.0
    normals, lengths, across = [], [], []
    for k in range(4):
        (x0, y0), (x1, y1) = points[k], points[(k + 1) % 4]
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        nx, ny = dy / length, -dx / length
        if nx * ((x0 + x1) / 2 - mean_x) + ny * ((y0 + y1) / 2 - mean_y) < 0:
            nx, ny = -nx, -ny
        normals.append((nx, ny))
        lengths.append(length)
        across.append(min(abs(dx), abs(dy)))
    return normals, lengths, across


_EDGES = EdgeRules()  # the sides' stage's defaults, which `side_errors` mirrors


@dataclass(frozen=True)
class SideErrors:
    """What moves the sides the corners are cut from (px), for `corner_covariance`.

    side_sigma: each side's measured position error (noise and slow wave; independent sides);
    locking_sigma: each side's pixel-locking offset, kept when no side crossed the pixel grid;
    growth_sigma: the error of the clipped-edge growth, measured on the corner arcs, that moved
    all four sides; growth_coupling: how much that growth measurement moves per unit common
    outward move of the sides it is measured against (they define the corners of the arcs).
    """

    side_sigma: float
    locking_sigma: float
    growth_sigma: float
    growth_coupling: float
    fit_fraction: float  # share of each side (its middle) the line was fitted to
    # per side (px, end to end of the side): the slope of the pixel-locking error over the part of its
    # period the side's line crosses, which its own turn takes up where no series was fitted (0 then)
    locking_turn_sigma: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
    # motion's uneven term (px, `EdgeFit.uneven_px`): each side moved in by its own growth, read off
    # its own blur by a Gaussian edge's rule, which a motion-blurred edge follows only roughly
    uneven: float = 0.0


def side_errors(
    corners: np.ndarray,
    beacon: Beacon,
    side_sigma_px: float,
    growth_sigma_px: float | None = None,
    rules: PoseRules = PoseRules(),
    geometry: tuple[list[tuple[float, float]], list[float], list[float]] | None = None,
    locking_sigma_px: float | None = None,
    uneven_px: float = 0.0,
) -> SideErrors:
    """The sides' error model of one frame from the sides' measured error and the panel's geometry.

    Mirrors `server.vision.subpixel.refine_edges`: each side is fitted over its straight middle
    less a margin; the corner arcs (radius r = rho side) are sampled over their middle
    `arc_span_deg` with up to `max_profiles_per_corner` crossings each, and the growth is read
    off them in the unit square the four sides make, where a crossing on the circle of radius
    R = x + y + sqrt(2 x y) (x, y from the corner along the sides) gives the growth
    (R - rho) / (1 - 2 rho). A crossing moved by e across the arc (at 45 degrees) moves it by
    (1 + sqrt 2) e / (1 - 2 rho); the sides moved out together by s move it by
    2 (1 + 1 / sqrt 2) s / (1 - 2 rho) (the coupling), and the sides are then moved in by it.
    The arc crossings keep their pixel-locking error (only the sides' is fitted), so each has
    sqrt(noise^2 + locking^2), the noise being the side's error times sqrt(crossings per side);
    the growth is their median (1.2533 sigma / sqrt(n)).
    """
    _, lengths, across = geometry or _side_geometry(corners)
    edges = _EDGES
    rho = beacon.corner_radius_m / min(beacon.extent_m)
    fit_fraction = max(1.0 - 2.0 * rho - 2.0 * edges.corner_margin, 0.1)
    # the pixel-locking term is fitted (and so left out) when a side's line drifts over half its period
    crosses_grid = fit_fraction * max(across) >= MIN_LOCKING_PERIOD_PX
    # the frame's own (`subpixel.locking_sigma_px`, from the blur and growth it measured) where it is the
    # larger: below the rule's, sides along the grid kept more than the model says (the grid bench's
    # ellipses held 74 % of the errors instead of 97 %)
    locking_rms = max(rules.pixel_locking_sigma_px, locking_sigma_px or 0.0)
    locking = 0.0 if crosses_grid else locking_rms
    # a side whose line drifts over part of the period takes the error's slope there as a turn of its
    # own: 2 pi rms (the first harmonic's) per period, over the whole side's drift (at most a period)
    locking_turn = tuple(
        0.0 if crosses_grid else 2.0 * math.pi * locking_rms * min(drift, 1.0 / fit_fraction) for drift in across
    )
    side_sigma = max(side_sigma_px, rules.side_sigma_floor_px)
    radius_px = rho * sum(lengths) / 4.0
    if radius_px < edges.min_corner_radius_px:  # no growth measured: the sides stay at the mid level
        growth = rules.unmeasured_growth_sigma_px if growth_sigma_px is None else growth_sigma_px
        return SideErrors(side_sigma, locking, growth, 0.0, fit_fraction, locking_turn, uneven_px)
    if growth_sigma_px is None:
        per_side = min(max(min(lengths) / 2.0, 12.0), edges.max_profiles_per_side)
        per_arc = min(max(math.radians(edges.arc_span_deg) * radius_px, 6.0), edges.max_profiles_per_corner)
        crossing = math.hypot(side_sigma * math.sqrt(per_side), locking_rms)
        growth_sigma_px = 1.2533 * (1.0 + math.sqrt(2.0)) / (1.0 - 2.0 * rho) * crossing / math.sqrt(4.0 * per_arc)
    coupling = 2.0 * (1.0 + math.sqrt(0.5)) / (1.0 - 2.0 * rho)
    return SideErrors(side_sigma, locking, float(growth_sigma_px), coupling, fit_fraction, locking_turn, uneven_px)


def _corner_design(normals: list[tuple[float, float]], errors: SideErrors) -> np.ndarray:
    """(8, 9): the corners' moves (rows x0 y0 x1 y1 ...) per unit of each independent error,
    scaled by its sigma: 4 side offsets, 4 side turns, the growth's error (last column). The
    corners' covariance is design design^T (see `corner_covariance`)."""
    own = math.hypot(errors.side_sigma, errors.locking_sigma, errors.uneven)
    noise_turn = errors.side_sigma * math.sqrt(12.0) / errors.fit_fraction
    turns = [math.hypot(noise_turn, locking, errors.uneven) for locking in errors.locking_turn_sigma]
    share = errors.growth_coupling / 4.0 * own
    rows = [[0.0] * 9 for _ in range(8)]
    for k in range(4):
        before = (k - 1) % 4
        (ax, ay), (lx, ly) = normals[before], normals[k]  # side k - 1 ends at corner k, side k starts there
        determinant = ax * ly - ay * lx
        # columns of [arriving; leaving]^-1: the corner's move per unit outward move of each side
        by_arriving = (ly / determinant, -lx / determinant)
        by_leaving = (-ay / determinant, ax / determinant)
        for axis in (0, 1):
            row = rows[2 * k + axis]
            out = by_arriving[axis] + by_leaving[axis]  # both sides out by one
            for j in range(4):  # every side's offset moves the growth measured against all four
                row[j] = -out * share
            row[before] += by_arriving[axis] * own
            row[k] += by_leaving[axis] * own
            row[4 + before] = 0.5 * by_arriving[axis] * turns[before]
            row[4 + k] = -0.5 * by_leaving[axis] * turns[k]
            row[8] = out * errors.growth_sigma
    return np.array(rows)


def corner_covariance(corners: np.ndarray, errors: SideErrors) -> tuple[np.ndarray, np.ndarray]:
    """Covariance (8, 8) of the corners (4, 2), x0 y0 x1 y1 ..., from the errors of the sides they
    join: (the sides' own part, the growth's part); the covariance is their sum.

    The corners are not measured one by one: each is where two fitted sides meet. Side k
    (corner k to k + 1) moves by its own offset d_k (sigma side_sigma, plus locking_sigma when
    it kept its pixel-locking offset) and turns so that its ends move by -+ a_k / 2, a_k of
    sigma side_sigma sqrt(12) / fit_fraction (a least-squares slope over the middle of the side,
    extrapolated to its corners). Then all four are moved in by the measured growth, which is
    off by its own error and by the coupling times the mean of the d_k (the turns cancel
    between a side's two corners). Corner k moves so that side k - 1's end and side k's
    start move along their normals as they do. Corners of neighbouring sides correlate; the
    growth is a change of scale, the main error of the range.
    """
    design = _corner_design(_side_geometry(corners)[0], errors)
    return design[:, :8] @ design[:, :8].T, np.outer(design[:, 8], design[:, 8])


def _centre_jacobian(corners: np.ndarray) -> np.ndarray:
    """d centre / d corners (2, 8) of the diagonals' intersection.

    Moving a corner turns its diagonal about the opposite corner, which moves the diagonal at
    the centre by the part of the move across it times the centre's share of the way from the
    opposite corner; the centre then slides along the other diagonal onto the moved one.
    """
    points = corners.tolist()
    jacobian = [[0.0] * 8, [0.0] * 8]
    for first, second, start, end in ((0, 2, 1, 3), (1, 3, 0, 2)):
        ux, uy = points[second][0] - points[first][0], points[second][1] - points[first][1]
        vx, vy = points[end][0] - points[start][0], points[end][1] - points[start][1]
        wx, wy = points[start][0] - points[first][0], points[start][1] - points[first][1]
        t = (wx * vy - wy * vx) / (ux * vy - uy * vx)  # centre = corner first + t u
        scale = 1.0 / (-uy * vx + ux * vy)  # 1 / (across u . v), across u = (-uy, ux)
        slide = ((vx * -uy * scale, vx * ux * scale), (vy * -uy * scale, vy * ux * scale))
        for row in (0, 1):
            for column in (0, 1):
                jacobian[row][2 * first + column] = (1.0 - t) * slide[row][column]
                jacobian[row][2 * second + column] = t * slide[row][column]
    return np.array(jacobian)


def consistency_factor(
    residuals_px: np.ndarray, jacobian: np.ndarray, covariance: np.ndarray, significant_chi_square: float = 0.0
) -> float:
    """chi-square / dof of the corners against the best pose under their noise model, when the
    chi-square exceeds `significant_chi_square` (else 1).

    residuals_px (8,): projected minus measured corners at any pose near the fit; jacobian (8, 6)
    there. The generalised least-squares chi-square (`consistency.chi_square`) does not depend on
    the pose it is taken at (to first order): it measures only how far the corners are from every
    view of the panel, 8 - 6 = 2 degrees of freedom.
    """
    value, dof = chi_square(residuals_px, covariance, jacobian)
    return value / dof if dof > 0 and value > significant_chi_square else 1.0


def _fit_residuals(
    corner_residuals_px: np.ndarray,
    corner_covariance: np.ndarray,
    pixel_jacobian: np.ndarray,
    tilt: tuple[np.ndarray, np.ndarray, float] | None,
) -> FitResiduals:
    """The fit's residuals and their noise (`consistency.FitResiduals`) in the six pose parameters.

    corner_residuals_px (8,), corner_covariance (8, 8), pixel_jacobian (8, 6) in (rvec, tvec);
    tilt: (the tilt's residual against the sensor (2,) rad, its Jacobian (2, 3) in rvec, the
    sensor's sigma in rad), None without gravity. The sensor's tilt is a measurement with its own
    error whether the fit weighed it ("auto") or took it as it is ("always"): the question is
    whether any pose explains the corners and the sensor within their noise.
    """
    if tilt is None:
        return FitResiduals(corner_residuals_px, corner_covariance, pixel_jacobian, 8)
    residual, rows, sigma_rad = tilt
    covariance = np.zeros((10, 10))
    covariance[:8, :8] = corner_covariance
    covariance[8, 8] = covariance[9, 9] = sigma_rad**2
    jacobian = np.zeros((10, 6))
    jacobian[:8], jacobian[8:, :3] = pixel_jacobian, rows
    residuals = np.empty(10)
    residuals[:8], residuals[8:] = corner_residuals_px, residual
    return FitResiduals(residuals, covariance, jacobian, 8)


def _position_covariance(
    beacon: Beacon,
    image_points: np.ndarray,
    fit: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    sigmas: tuple[float, float, float | None, float | None, float],
    gravity: tuple[np.ndarray, float, GravityMode] | None,
    rules: PoseRules,
) -> tuple[np.ndarray | None, float, FitResiduals]:
    """(covariance (3, 3) of the camera's position in the map, m^2, None when a solve fails; the
    sides' noise scale; the corners' and the tilt's residuals under the unscaled noise model).

    fit: (rvec, tvec, projected (5, 1, 2), Jacobian (10, >= 6)) of the final pose; sigmas: the
    sides' measured error, the corner sigma the fits weighed with, the growth's error and the
    crossings' pixel-locking error (px, None: predicted, the rule's), motion's uneven term (px);
    gravity: (measured vector,
    sensor sigma in degrees, mode) when the fit used it.

    With the corners' noise as D D^T (D = `_corner_design`, scaled columns) and the fit's
    normal matrix H, the parameters move by X = H^-1 J^T L D (L: corners to the five points)
    per unit of each error, so their covariance is X X^T; the gravity sensor's error adds
    columns of its own. The position's is P X (P X)^T, P = d position / d parameters.
    Few, small numpy calls: this runs on every fix (~0.1 ms).
    """
    rvec, tvec, projected, jacobian = fit
    side_sigma, weight_sigma, growth_sigma, locking_sigma, uneven = sigmas
    corners = image_points[:4]
    geometry = _side_geometry(corners)
    errors = side_errors(corners, beacon, side_sigma, growth_sigma, rules, geometry, locking_sigma, uneven)
    design = _corner_design(geometry[0], errors)
    pixel_jacobian = jacobian[:, :6]
    residuals = projected.reshape(-1)[:8] - image_points[:4].reshape(-1)
    noise = design @ design.T
    factor = 1.0
    if rules.consistency_scaling:
        factor = consistency_factor(residuals, pixel_jacobian[:8], noise, rules.consistency_chi_square)
        if factor != 1.0:
            design[:, :8] *= math.sqrt(factor)
    # L D, L = [I; d centre / d corners]: the centre is the corners' function, not a measurement
    moves = pixel_jacobian.T @ np.concatenate((design, _centre_jacobian(corners) @ design))  # J^T L D (6, 9)
    normal = pixel_jacobian.T @ pixel_jacobian
    rotation, rotation_jacobian = cv2.Rodrigues(rvec)  # d R[r, c] / d rvec_i at [i, 3 r + c]
    by_rvec = rotation_jacobian.reshape(3, 3, 3)
    if gravity is None:
        fitted = _fit_residuals(residuals, noise, pixel_jacobian[:8], None)
        ok, parameters = cv2.solve(normal, moves, flags=cv2.DECOMP_CHOLESKY)
    else:
        vector, sigma_deg, mode = gravity
        sigma_rad = math.radians(sigma_deg)
        across = orthonormal_pair(vector / math.sqrt(float(vector @ vector)))
        # d (across . -R[:, 2]) / d rvec (2, 3); tvec does not move the predicted gravity
        tilt = -(across @ by_rvec[:, :, 2].T)
        fitted = _fit_residuals(residuals, noise, pixel_jacobian[:8], (across @ -rotation[:, 2], tilt, sigma_rad))
        if mode is GravityMode.always:
            # the tilt taken as measured: min |J d - dz|^2 subject to T d = dg (KKT system)
            system = np.zeros((8, 8))
            system[:6, :6] = normal
            system[6:, :3] = tilt
            system[:3, 6:] = tilt.T
            right = np.zeros((8, 11))
            right[:6, :9] = moves
            right[6, 9] = right[7, 10] = sigma_rad
            ok, solution = cv2.solve(system, right, flags=cv2.DECOMP_LU)
            parameters = solution[:6]
        else:
            # the MAP fit: tilt residual weighted by corner sigma / gravity sigma against unit pixels
            weight2 = (weight_sigma / sigma_rad) ** 2
            normal[:3, :3] += weight2 * (tilt.T @ tilt)
            right = np.zeros((6, 11))
            right[:, :9] = moves
            right[:3, 9:] = weight2 * sigma_rad * tilt.T
            ok, parameters = cv2.solve(normal, right, flags=cv2.DECOMP_CHOLESKY)
    if not ok:
        return None, factor, fitted
    to_beacon = np.empty((3, 6))  # d (-R^T t) / d (rvec, tvec)
    to_beacon[:, :3] = -(tvec.ravel() @ by_rvec).T
    to_beacon[:, 3:] = -rotation.T
    position = beacon_frame(beacon)[0] @ (to_beacon @ parameters)
    return position @ position.T, factor, fitted


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
    growth_sigma_px: float | None = None,
    locking_sigma_px: float | None = None,
    uneven_px: float = 0.0,
) -> PoseSolution | Refusal:
    """Camera pose in the map from corners (4, 2) in model order and the centre (2,).

    corner_sigma_px: the sides' measured position error (`EdgeFit.line_sigma_px`);
    growth_sigma_px: the error of the clipped-edge growth that moved all four sides, when the
    sides' stage measured it (else `side_errors` predicts it from the panel's geometry);
    locking_sigma_px: a crossing's pixel-locking error at the frame's blur (`EdgeFit.locking_px`,
    else `PoseRules.pixel_locking_sigma_px`); uneven_px: how far the sides' own growths lie from the
    common one (`EdgeFit.uneven_px`, motion), an error of each side's own. All set the position's
    covariance and the noise the consistency test weighs the residuals with; the first also the
    fits' weights.
    """
    corners4 = beacon_corners_m(beacon)
    object_points = np.zeros((5, 3))  # the corners, then the centre
    object_points[:4] = corners4
    image_points = np.empty((5, 2))
    image_points[:4], image_points[4] = corners_px, center_px
    ratio, disagreement, best_square = _square_ambiguity(corners4, image_points[:4], beacon, camera_matrix)
    use_gravity = gravity_camera is not None and gravity_mode is not GravityMode.never
    # The MAP fit starts from IPPE_SQUARE's best minimum, in front of the camera, when there is one:
    # it converges to the minimum the vision pose (SQPnP polished by LM, 0.13 ms) starts it at.
    map_start = best_square if use_gravity and gravity_mode is GravityMode.auto else None
    if map_start is None or map_start[1][2, 0] <= 0:
        vision = _vision_pose(object_points, image_points, camera_matrix)
        if vision is None:
            return Refusal(FailureReason.pose_failed, SQPNP_FAILED)
        rvec, tvec = map_start = vision

    corner_sigma = max(corner_sigma_px, rules.corner_sigma_floor_px)
    ambiguous = ratio > rules.max_ambiguity_ratio and disagreement > rules.max_ambiguous_disagreement_m
    if ambiguous and not use_gravity:
        return Refusal(
            FailureReason.pose_ambiguous,
            f"two poses fit almost equally (error ratio {ratio:.2f}) and place the camera "
            f"{disagreement * 1000:.0f} mm apart; a gravity vector would decide",
        )
    if use_gravity and gravity_mode is GravityMode.always:
        rvec, tvec = _level_start(image_points, beacon, camera_matrix, gravity_camera)
    elif use_gravity:
        fused = _map_pose(
            object_points,
            image_points,
            map_start,
            beacon,
            camera_matrix,
            gravity_camera,
            corner_sigma,
            gravity_sigma_deg,
            try_level=ratio > rules.max_ambiguity_ratio / 4,
        )
        if fused is None:  # every fit put the beacon behind the camera: the vision pose stands
            vision = _vision_pose(object_points, image_points, camera_matrix)
            if vision is None:
                return Refusal(FailureReason.pose_failed, SQPNP_FAILED)
            fused = vision
        rvec, tvec = fused
    position, rotation_wc = _camera_in_map(beacon, rvec, tvec)
    projected, jacobian = cv2.projectPoints(object_points, rvec, tvec, camera_matrix, None)
    fitted: FitResiduals | None = None
    try:
        covariance, factor, fitted = _position_covariance(
            beacon,
            image_points,
            (rvec, tvec, projected, jacobian),
            (corner_sigma_px, corner_sigma, growth_sigma_px, locking_sigma_px, uneven_px),
            (np.asarray(gravity_camera, dtype=float), gravity_sigma_deg, gravity_mode) if use_gravity else None,
            rules,
        )
    except (ZeroDivisionError, np.linalg.LinAlgError, cv2.error):  # a degenerate quad: no uncertainty, not no fix
        covariance, factor = None, 1.0
    if covariance is not None and not (
        all(map(math.isfinite, covariance.ravel().tolist()))
        and all(value >= 0 for value in covariance.diagonal().tolist())
    ):
        covariance = None  # extreme intrinsics overflow the arithmetic: a fix without an uncertainty
    return PoseSolution(
        position_m=position,
        rotation_wc=rotation_wc,
        reprojection_error_px=_rms(projected, image_points),
        ambiguity_ratio=ratio,
        alternative_distance_m=disagreement,
        gravity_used=use_gravity,
        covariance_m2=covariance,
        consistency_factor=factor,
        residuals=fitted,
    )
