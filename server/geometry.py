"""Frames, rotations and the beacon model shared by the pipeline and the simulator.

Beacon frame B: origin at the panel centre, x_B and y_B along its edges (the map's X and Y
turned by `yaw_deg` about +Z), z_B = +Z (up, into the ceiling). The camera sees the panel
from below, from the negative z_B side.

Model corner order (that of OpenCV's SOLVEPNP_IPPE_SQUARE, in metres, z_B = 0):
    0: (-s/2, +s/2)   1: (+s/2, +s/2)   2: (+s/2, -s/2)   3: (-s/2, -s/2)
Seen from below by a camera with the map's yaw, corner 0 is at the bottom left of the
image, 1 bottom right, 2 top right, 3 top left.
"""

from __future__ import annotations

import math

import numpy as np

from shared_schemas import Beacon, CameraIntrinsics


def rotation_z(angle_deg: float) -> np.ndarray:
    """3x3 rotation about +Z by `angle_deg` (counter-clockwise seen from above)."""
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_ypr(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """R_wc = Rz(yaw) Ry(pitch) Rx(roll); all zero is a camera looking straight up."""
    p, r = math.radians(pitch_deg), math.radians(roll_deg)
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return rotation_z(yaw_deg) @ ry @ rx


def ypr_from_rotation(rotation_wc: np.ndarray) -> tuple[float, float, float]:
    """Inverse of `rotation_from_ypr` (degrees; pitch in [-90, 90])."""
    r = np.asarray(rotation_wc, dtype=float)
    pitch = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    yaw = math.atan2(r[1, 0], r[0, 0])
    roll = math.atan2(r[2, 1], r[2, 2])
    return math.degrees(yaw), math.degrees(pitch), math.degrees(roll)


def camera_matrix(camera: CameraIntrinsics) -> np.ndarray:
    """The 3x3 intrinsic matrix K of `camera`."""
    return np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])


def distortion_vector(camera: CameraIntrinsics) -> np.ndarray | None:
    """OpenCV distortion coefficients, or None for an ideal pinhole."""
    coefficients = np.asarray(camera.distortion, dtype=float)
    return coefficients if coefficients.size and np.any(coefficients) else None


def model_corners_m(width_m: float, height_m: float | None = None) -> np.ndarray:
    """The 4 corners of a width x height rectangle (a square without `height_m`) in the beacon
    frame, shape (4, 3), in the module's corner order."""
    w, h = width_m / 2.0, (width_m if height_m is None else height_m) / 2.0
    return np.array([[-w, h, 0.0], [w, h, 0.0], [w, -h, 0.0], [-w, -h, 0.0]])


def beacon_corners_m(beacon: Beacon) -> np.ndarray:
    """The corners (4, 3) of the rectangle circumscribing `beacon`'s outline, beacon frame."""
    return model_corners_m(*beacon.extent_m)


def beacon_rotation(beacon: Beacon) -> np.ndarray:
    """R_wb: beacon frame to map frame."""
    return rotation_z(beacon.yaw_deg)


def beacon_to_world(beacon: Beacon, points_b: np.ndarray) -> np.ndarray:
    """Beacon-frame points (N, 3) to map-frame points (N, 3)."""
    return np.asarray(points_b) @ beacon_rotation(beacon).T + np.asarray(beacon.center_m)


def rounded_rectangle_outline_m(
    width_m: float, height_m: float, radius_m: float, points_per_arc: int = 64
) -> np.ndarray:
    """Closed outline of a rounded rectangle in the beacon frame, shape (N, 3), z = 0.

    Counter-clockwise seen from +z_B; the straight sides are the chords between arcs. A circle
    is the rectangle whose radius is half its (equal) sides: four quarter arcs, no sides.
    """
    inner_x, inner_y = width_m / 2.0 - radius_m, height_m / 2.0 - radius_m
    outline: list[np.ndarray] = []
    for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        start = math.pi / 2 * k
        cx, cy = sx * inner_x, sy * inner_y
        if radius_m == 0:
            outline.append(np.array([[cx, cy, 0.0]]))
            continue
        angles = np.linspace(start, start + math.pi / 2, max(points_per_arc, 2))
        outline.append(
            np.stack([cx + radius_m * np.cos(angles), cy + radius_m * np.sin(angles), np.zeros_like(angles)], axis=1)
        )
    return np.concatenate(outline, axis=0)


def beacon_outline_m(beacon: Beacon, points_per_arc: int = 64) -> np.ndarray:
    """The closed outline (N, 3) of `beacon`'s luminous area in its own frame, any shape."""
    width, height = beacon.extent_m
    return rounded_rectangle_outline_m(width, height, beacon.outline_radius_m, points_per_arc)


def dense_beacon_outline_m(beacon: Beacon, span_px: float, max_step_px: float = 1.0) -> np.ndarray:
    """`beacon_outline_m` with points about `max_step_px` apart when the panel's longer size
    spans `span_px` pixels (the projection's scale): straight sides cut into steps, arcs too."""
    width, height = beacon.extent_m
    size = max(width, height)
    radius = beacon.outline_radius_m
    per_arc = max(8, int(math.ceil(math.pi / 2 * radius / size * span_px / max_step_px)) + 1)
    closed = beacon_outline_m(beacon, per_arc)
    closed = np.vstack([closed, closed[:1]])
    steps = np.linalg.norm(np.diff(closed, axis=0), axis=1) / size * span_px / max_step_px
    # each side and each arc's chord cut as np.linspace(a, b, n, endpoint=False) cuts it, the
    # same arithmetic in one array (a circle has thousands of chords: a linspace call each cost
    # more than the rest of its shape test)
    counts = np.maximum(1, np.ceil(steps).astype(int))
    chord = np.repeat(np.arange(len(counts)), counts)
    index = (np.arange(len(chord)) - np.repeat(np.cumsum(counts) - counts, counts)).astype(float)[:, None]
    delta = np.subtract(closed[1:], closed[:-1])
    step = delta / counts[:, None]
    # (linspace's own care for a zero step, gh-5437: the fraction first, then the chord)
    flat = np.any(step == 0, axis=1)[chord, None]
    return np.where(flat, index / counts[chord, None] * delta[chord], index * step[chord]) + closed[:-1][chord]


def world_to_camera(points_w: np.ndarray, position_m: np.ndarray, rotation_wc: np.ndarray) -> np.ndarray:
    """Map-frame points (N, 3) into the camera frame: X_c = R_wc^T (X_w - C)."""
    return (np.asarray(points_w) - np.asarray(position_m)) @ np.asarray(rotation_wc)


def worst_sigma_2d_m(covariance_m2: np.ndarray) -> float:
    """The horizontal position's 1-sigma along its worst direction, from a (3, 3) covariance."""
    return float(math.sqrt(max(np.linalg.eigvalsh(np.asarray(covariance_m2)[:2, :2]).max(), 0.0)))


def gravity_in_camera(rotation_wc: np.ndarray) -> np.ndarray:
    """Down (the map's -Z) in the camera frame of a camera-to-map rotation: what a gravity sensor reads."""
    return np.asarray(rotation_wc, dtype=float).T @ np.array([0.0, 0.0, -1.0])


def angle_deg(u: np.ndarray, v: np.ndarray) -> float:
    """The angle (degrees) between two non-zero vectors of any lengths."""
    # plain floats: numpy's calls cost several times the arithmetic for a 3-vector (twice a fix)
    first, second = np.asarray(u, dtype=float).ravel().tolist(), np.asarray(v, dtype=float).ravel().tolist()
    dot = sum(a * b for a, b in zip(first, second, strict=True))
    cosine = dot / (math.sqrt(sum(a * a for a in first)) * math.sqrt(sum(b * b for b in second)))
    return math.degrees(math.acos(min(max(cosine, -1.0), 1.0)))


def orthonormal_pair(vector: np.ndarray) -> np.ndarray:
    """Two unit vectors (2, 3) orthogonal to `vector` and to each other."""
    x, y, z = np.asarray(vector, dtype=float).tolist()
    # the cross product with the axis least aligned with `vector`, written out in plain floats (np.cross
    # and numpy's scalars are slow); the norm is np.linalg.norm's sqrt of the dot product
    if abs(x) <= min(abs(y), abs(z)):
        a, b, c = 0.0, z, -y
    elif abs(y) <= abs(z):
        a, b, c = -z, 0.0, x
    else:
        a, b, c = y, -x, 0.0
    norm = math.sqrt(a * a + b * b + c * c)
    fx, fy, fz = a / norm, b / norm, c / norm
    return np.array([[fx, fy, fz], [y * fz - z * fy, z * fx - x * fz, x * fy - y * fx]])


def wrap_deg(angle_deg: float) -> float:
    """`angle_deg` in (-180, 180]."""
    return float(-((-angle_deg + 180.0) % 360.0 - 180.0))


def grown_quads(corners_px: np.ndarray, growth_px: np.ndarray | float) -> np.ndarray:
    """Quadrilaterals (..., 4, 2) with every side moved outward along its normal by `growth_px`
    (broadcast over the leading axes; negative moves inward): corner k is where the moved sides
    k - 1 -> k and k -> k + 1 meet. This is how the sub-pixel stage's clipped-edge growth moves the
    sides of a panel's image (`server.vision.subpixel.refine_edges`)."""
    corners = np.asarray(corners_px, dtype=float)
    along = np.roll(corners, -1, axis=-2) - corners  # side k: corner k -> k + 1
    normal = np.stack([along[..., 1], -along[..., 0]], axis=-1) / np.linalg.norm(along, axis=-1, keepdims=True)
    outward = np.sign(np.sum(normal * (corners - corners.mean(axis=-2, keepdims=True)), axis=-1, keepdims=True))
    normal = normal * np.where(outward == 0, 1.0, outward)
    offset = np.sum(normal * corners, axis=-1) + np.asarray(growth_px, dtype=float)[..., None]  # n . x = c
    n1, c1 = np.roll(normal, 1, axis=-2), np.roll(offset, 1, axis=-1)  # side k - 1
    det = n1[..., 0] * normal[..., 1] - n1[..., 1] * normal[..., 0]
    x = (c1 * normal[..., 1] - offset * n1[..., 1]) / det
    y = (n1[..., 0] * offset - normal[..., 0] * c1) / det
    return np.stack([x, y], axis=-1)
