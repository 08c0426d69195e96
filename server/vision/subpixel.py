"""Stage 7 (beyond the paper): sub-pixel sides from the grey levels, with the clipped-edge bias removed.

The polygon stage gives corners good to a pixel or so. Here each side is measured again
from the image itself, in the way of AprilTag's edge refinement:

1. Along the straight part of each side (away from the rounded corners) grey-level profiles
   are sampled across the edge (bilinear, 0.25 px steps), and each profile's crossing of the
   frame's mid level is found to a fraction of a pixel. Profiles across the middle of each
   rounded corner are sampled in the same pass.
2. The crossings are undistorted (when the camera has distortion) and the four sides are
   fitted as lines together (total least squares, outliers trimmed), with the crossings'
   pixel-locking error as a shared periodic term of their sub-pixel phase
   (`_remove_pixel_locking`; only on sides that cross the pixel grid: along a pixel row
   or column the term is a constant, no different from the side's offset).
3. The mid-level contour of a *clipped* panel is not its outline (contract, "Physics"): the
   PSF spreads the saturated light outward, so the contour is the outline grown by some
   distance D (a fraction of a pixel to a few pixels, depending on overexposure and PSF,
   neither of which the frame tells). Growing a rounded square by D moves its sides out
   by D and turns its corner radius r into r + D, so the corners measure D where the sides
   cannot: in the plane of the panel (the four lines rectified to a unit square) the
   corner crossings lie on circles of radius R = rho (1 - 2 d) + d, with rho = r / side
   from the map and d = D in side units. The lines are then moved in by D. This needs the
   map's corner radius to be right (0.1 mm of radius is ~0.5 px of D at 1 m, see
   docs/accuracy.md) and a corner radius of a few pixels, but no model of the PSF or of
   the overexposure, except for one small term: blur rounds a curved edge's level set
   inward by s^2 / (2 R) (s the blur, R the radius; less light reaches a point outside a
   convex edge than outside a straight one), which the corner geometry would amplify about
   three-fold. s is estimated from the gap between the mid- and quarter-level crossings of
   the sides, assuming a Gaussian edge profile only for this term.
4. Neighbouring lines intersect at the corners of the circumscribed square.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.special import ndtr

from server.vision.binarize import Levels

UNIT_SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
NEXT, PREVIOUS = np.array([1, 2, 3, 0]), np.array([3, 0, 1, 2])  # corner or side k + 1, k - 1
# each corner's own axes in the unit square (4, 2, 2): columns along side k and back along side k - 1
CORNER_AXES = np.stack([UNIT_SQUARE[NEXT] - UNIT_SQUARE, UNIT_SQUARE[PREVIOUS] - UNIT_SQUARE], axis=2)
# A side takes part in the pixel-locking fit only if its line crosses this much of its outward
# axis (a tenth of L's period, several times the crossings' 0.01-0.04 px noise): below it
# the crossings' phases are set by their noise, not by the geometry.
MIN_PHASE_SPAN_PX = 0.1
# ... and L is fitted at all only when one side's line crosses half a period of it: over less
# each side's own turn and shift take up what the series would, and the fit moves the sides by
# what it makes of their noise (0.3 px at 2 m, quarter resolution, four sides 0.15 px across the
# grid: corners the noise model put at 0.06 px, found by the consistency test, `pose/consistency.py`;
# 0.8 px across it, the fit takes a two-harmonic L out to 0.01 px, tests/server/vision/test_subpixel.py).
MIN_LOCKING_PERIOD_PX = 0.5
LOCKING_HARMONICS = 2  # terms of the pixel-locking series
# A gap between two level crossings along a pixel row or column is off by their pixel-locking
# errors (~0.06 px rms each, `PoseRules.pixel_locking_sigma_px`), which do not average out there.
LOCKING_GAP_PX = 0.085
# the blurs (px) `blur_sigma_px` reads the level gap against
BLUR_TABLE_PX = np.linspace(0.1, 8.0, 160)
BLUR_TABLE_PX.flags.writeable = False


@dataclass(frozen=True)
class EdgeRules:
    half_window_px: float = 6.0
    step_px: float = 0.25
    max_profiles_per_side: int = 120
    max_profiles_per_corner: int = 40
    corner_margin: float = 0.03  # of the side, kept clear beyond the corner arcs
    arc_span_deg: float = 60.0  # middle part of each 90 degree corner arc that is measured
    min_corner_radius_px: float = 5.0  # below this the corners cannot measure the growth
    # sides whose blur (mid- to quarter-level gap) differs by more than this many standard errors
    # of their medians, and by more than this share of it, are blurred unevenly (motion): not by
    # noise. A still panel tilted 9 deg at 2 m, full resolution, showed a 12 % pair difference;
    # walking at 1.2 m/s gives 3-52 % (quarter resolution, 24 frames): the share is a compromise
    uneven_blur_sigmas: float = 4.0
    uneven_blur_fraction: float = 0.15
    # the crossings and the line fits by the compiled kernels (`server.vision.subpixel_kernel`);
    # False: by the NumPy functions here, the reference they equal
    compiled: bool = True


@dataclass(frozen=True)
class EdgeFit:
    """Refined sides and corners in undistorted full-frame pixel coordinates.

    `lines` (4, 3): a x + b y + c = 0 with (a, b) the unit outward normal; side k joins
    corner k to corner k + 1. `edge_shift_px`: how far the true edges lie outward of the
    mid-level crossings (negative: inward, as for an overexposed panel).
    """

    corners: np.ndarray
    lines: np.ndarray
    edge_shift_px: float
    line_rms_px: float
    line_sigma_px: float  # 1-sigma error of a side's position, for the pose's weights
    points_per_side: tuple[int, ...]
    arc_points: int
    warnings: tuple[str, ...] = ()
    # the part of the growth that the blur's rounding of the corners took off (px, >= 0): the
    # one term that assumes a linear response (the blur is read off two levels of the edge)
    curvature_px: float = 0.0
    # how far the sides' own growths lie from the common one when their blur differs (px, >= 0;
    # 0 when it does not): motion during the exposure blurs the sides across it more
    uneven_px: float = 0.0
    # rms of a crossing's pixel-locking error at this frame's blur and growth (`locking_sigma_px`;
    # px), None when the corners measured neither
    locking_px: float | None = None


@functools.cache
def _kernels():
    """`server.vision.subpixel_kernel`, imported at the first refinement: numba takes ~0.7 s to
    import, which a process that never refines edges (the client's CLI, a survey) need not pay."""
    from server.vision import subpixel_kernel

    return subpixel_kernel


def warm_kernels() -> None:
    """Load the compiled kernels (compile them, on a cold cache: seconds) with the stage's own
    argument types, so that the first frame does not wait for them (`server.api.main` at start-up)."""
    kernels = _kernels()
    offsets = profile_offsets(EdgeRules().half_window_px, EdgeRules().step_px)
    profiles = np.linspace(255.0, 0.0, len(offsets), dtype=np.float32)[None, :]
    kernels.level_crossings(profiles, offsets, 128.0, _nearest_first(offsets), np.empty(1, np.float32))
    rng = np.random.default_rng(0)
    corners = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
    along = np.linspace(0.1, 0.9, 12)[None, :, None]
    points = corners[:, None, :] + along * (corners[NEXT] - corners)[:, None, :] + rng.normal(0.0, 0.05, (4, 12, 2))
    outward = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    kernels.fit_lines(
        points, np.ones((4, 12)), outward, points, LOCKING_HARMONICS, MIN_PHASE_SPAN_PX, MIN_LOCKING_PERIOD_PX
    )
    _profile_layout(corners, 0.8, offsets, (48, 48), EdgeRules())
    arcs = np.full((4, 8, 2), 0.1)
    kernels.arc_growth(_plane(arcs, square_homography(corners)), corners, 0.1, UNIT_SQUARE, CORNER_AXES)


def _norms(vectors: np.ndarray) -> np.ndarray:
    """Euclidean lengths along the last axis: `np.linalg.norm(vectors, axis=-1)`'s own arithmetic
    (the root of the summed squares), without its Python layers."""
    return np.sqrt((vectors * vectors).sum(axis=-1))


def _linspace(start: float, stop: float, num: int) -> np.ndarray:
    """`np.linspace(start, stop, num)` for num >= 2 and start != stop, by its own arithmetic (the
    same values) without its Python layers."""
    values = np.arange(num, dtype=float) * ((stop - start) / (num - 1)) + start
    values[-1] = stop
    return values


def _median(values: np.ndarray) -> float:
    """`np.median(values)` of a 1-D array without NaNs (the mean of the two middle values of an
    even count, in the array's precision), by one partition, without numpy's Python layers."""
    half = len(values) // 2
    part = np.partition(values, [half - 1, half] if len(values) % 2 == 0 else half)
    return float((part[(len(values) - 1) // 2] + part[half]) / 2)


def _nanmedians(values: np.ndarray) -> np.ndarray:
    """Median of each row of `values` (k, n) float, its NaNs left out (NaN for a row of NaNs).

    The value `np.nanmedian(values, axis=1)` gives (the mean of the two middle values of an even
    count), from one sort: numpy's own takes its masked-array path for rows this short, ~50 calls.
    """
    ordered = np.sort(values, axis=1)  # NaNs sort last
    counts = values.shape[1] - np.isnan(values).sum(axis=1)
    rows = np.arange(len(values))
    return (ordered[rows, (counts - 1) // 2] + ordered[rows, counts // 2]) / 2  # a row of NaNs: both NaN


def _outward_normals(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit directions, outward normals and lengths of the four sides of a convex quad."""
    starts, ends = corners, corners[NEXT]
    directions = ends - starts
    lengths = _norms(directions)
    directions = directions / lengths[:, None]
    normals = directions[:, ::-1] * [1.0, -1.0]
    outward = np.sign((normals * ((starts + ends) / 2 - corners.mean(axis=0))).sum(axis=1))
    return directions, normals * outward[:, None], lengths


def profile_offsets(half_window_px: float, step_px: float, dtype=np.float32) -> np.ndarray:
    """Sample positions (m,) along a profile, px from its base point: -half_window_px to
    +half_window_px inclusive, `step_px` apart (`dtype` float32 or float64)."""
    return np.arange(-half_window_px, half_window_px + 1e-9, step_px, dtype=dtype)


def _sample_maps(bases: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`sample_profiles`' sample coordinates (n, m) x and y, float32."""
    map_x = (bases[:, :1] + offsets[None, :] * normals[:, :1]).astype(np.float32, copy=False)
    map_y = (bases[:, 1:2] + offsets[None, :] * normals[:, 1:2]).astype(np.float32, copy=False)
    return map_x, map_y


def sample_profiles(image: np.ndarray, bases: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Grey-level profiles (n, m) float32 across edges, bilinear.

    image (height, width), uint8 or float32: sample j of profile i is the image at
    bases[i] + offsets[j] * normals[i]. bases (n, 2) x, y in the image's pixels (pixel
    centres at whole numbers); normals (n, 2) unit vectors; offsets (m,) px (`profile_offsets`).
    The sample coordinates are computed in the precision of `bases`, `normals` and `offsets`,
    then given to OpenCV as float32 (it places them on a 1/32 px grid). A uint8 image is
    read straight, each sample rounded to a whole DN (moves a crossing by < 0.005 px, and
    costs less than a float copy of the image); outside the image the border pixels repeat.
    """
    map_x, map_y = _sample_maps(bases, normals, offsets)
    profiles = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return profiles.astype(np.float32, copy=False)


def _nearest_first(offsets: np.ndarray) -> np.ndarray:
    """The profile's samples but its last in the order a crossing is looked for: the first in the
    order of nearness to offset 0 (of two as near, the first, as an argmin over the distances takes it)."""
    return np.argsort(np.abs(offsets[:-1]), kind="stable")


def _crossings(profiles: np.ndarray, offsets: np.ndarray, level: float, rules: EdgeRules) -> np.ndarray:
    """`level_crossings`, by the compiled kernel unless `rules` ask for the reference."""
    if not rules.compiled:
        return level_crossings(profiles, offsets, level)
    return _kernels().level_crossings(
        profiles, offsets, level, _nearest_first(offsets), np.empty(len(profiles), np.float32)
    )


def level_crossings(profiles: np.ndarray, offsets: np.ndarray, level: float) -> np.ndarray:
    """Where each profile falls through `level`: (n,) px along its normal, NaN where it does not.

    profiles (n, m) grey levels (DN) sampled at offsets (m,) px, evenly spaced and increasing
    (from inside a bright blob outward, as `sample_profiles` with outward normals gives them).
    Of each profile's bright-to-dark crossings (a sample >= level followed by one < level),
    the one nearest offset 0 is taken and placed between its two samples by linear
    interpolation, so the result is a sub-pixel offset from the profile's base point.
    """
    at_or_above = profiles >= level  # profiles are finite (sampled from an image)
    falls = at_or_above[:, :-1] > at_or_above[:, 1:]  # sample j at or above the level, j + 1 below it
    nearest_first = _nearest_first(offsets)
    j = nearest_first[np.argmax(falls[:, nearest_first], axis=1)]
    rows = np.arange(len(profiles))
    v0, v1 = profiles[rows, j], profiles[rows, j + 1]
    fraction = (v0 - level) / np.maximum(v0 - v1, 1e-9)
    result = offsets[j] + fraction * (offsets[1] - offsets[0])
    return np.where(falls[rows, j], result, np.nan)


def _side_profiles(corners, directions, normals, lengths, straight_fraction, rules):
    """Base points (4, n, 2) on the straight part of each side, and their outward normals."""
    n_along = int(min(max(float(lengths.min()) / 2, 12), rules.max_profiles_per_side))
    start = (1.0 - straight_fraction) / 2 + rules.corner_margin
    along = _linspace(start, 1.0 - start, n_along)
    bases = corners[:, None, :] + along[None, :, None] * (lengths[:, None, None] * directions[:, None, :])
    return bases.reshape(-1, 2), np.repeat(normals, n_along, axis=0), n_along


def _arc_profiles(corners, directions, radius_px, rules):
    """Base points and outward normals across the middle of each rounded corner (rough geometry).

    Corner k joins side k - 1 (arriving) to side k (leaving); with u along side k and v back
    along side k - 1, the arc of radius R is centre - R (cos t v + sin t u) for t in 0..90 deg.
    """
    arc_length = np.pi / 2 * radius_px * rules.arc_span_deg / 90.0
    n_arc = int(min(max(arc_length, 6), rules.max_profiles_per_corner))
    half_span = math.radians(rules.arc_span_deg) / 2
    t = np.pi / 4 + _linspace(-half_span, half_span, n_arc)
    u = directions
    v = -directions[PREVIOUS]
    outward = -(np.cos(t)[None, :, None] * v[:, None, :] + np.sin(t)[None, :, None] * u[:, None, :])
    outward /= _norms(outward)[..., None]
    centres = corners + radius_px * (u + v)
    bases = centres[:, None, :] + radius_px * outward
    return bases.reshape(-1, 2), outward.reshape(-1, 2), n_arc


def _profile_layout(
    corners: np.ndarray, straight_fraction: float, offsets: np.ndarray, shape: tuple[int, ...], rules: EdgeRules
) -> tuple:
    """Where the stage samples the ROI of `shape` (height, width): the sides' unit directions, outward
    normals and lengths (4, 2), (4, 2), (4,), the corner radius (px), each profile's base point and
    outward normal (n, 2) (the sides' profiles, then the corners' when the radius is measurable),
    their counts per side and per corner (0: no corners), the sample maps (n, m) float32 that
    `sample_profiles` makes of them, and which profiles lie wholly inside the ROI (n,)."""
    if rules.compiled:
        return _kernels().profile_layout(
            corners, straight_fraction, offsets, shape[1], shape[0], rules.corner_margin,
            rules.max_profiles_per_side, rules.max_profiles_per_corner, rules.arc_span_deg,
            rules.min_corner_radius_px,
        )  # fmt: skip
    directions, normals, lengths = _outward_normals(corners)
    radius_px = (1.0 - straight_fraction) / 2 * float(lengths.mean())
    bases, across, n_along = _side_profiles(corners, directions, normals, lengths, straight_fraction, rules)
    n_arc = 0
    if radius_px >= rules.min_corner_radius_px:
        arc_bases, arc_normals, n_arc = _arc_profiles(corners, directions, radius_px, rules)
        bases, across = np.concatenate([bases, arc_bases]), np.concatenate([across, arc_normals])
    bases32, across32 = bases.astype(np.float32), across.astype(np.float32)
    map_x, map_y = _sample_maps(bases32, across32, offsets)
    height, width = shape
    ends = bases32 + offsets[[0, -1], None, None] * across32  # (2, n, 2): each profile's first, last sample
    inside = ((ends >= 0) & (ends <= np.array([width - 1, height - 1], dtype=np.float32))).all(axis=(0, 2))
    return directions, normals, lengths, radius_px, bases, across, n_along, n_arc, map_x, map_y, inside


def _fit_lines(
    points: np.ndarray, weights: np.ndarray, outward: np.ndarray, phase_points: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Total-least-squares lines of the four sides at once, one trimmed refit, pixel locking removed.

    points (4, n, 2), weights (4, n) 1 for a valid crossing else 0, outward (4, 2);
    phase_points (4, n, 2): the same crossings in the sensor's own pixels (before
    undistortion), for the pixel-locking term (see `_remove_pixel_locking`).
    Returns lines (4, 3) a x + b y + c = 0 with (a, b) the unit normal along `outward`,
    the RMS distance of the kept points per side, and the sides' position error. Points
    further than 3.5 robust sigmas (MAD) from the first fit are dropped: a noise crossing
    must not tilt a side.
    """
    coords = np.ascontiguousarray(np.moveaxis(points, 2, 0))  # (2, 4, n): x, y, each row summed pairwise
    sides = np.arange(4)
    for _ in range(2):
        centres = (weights * coords).sum(axis=2) / weights.sum(axis=1)  # (2, 4)
        deltas = coords - centres[..., None]
        sxx, syy, sxy = (weights * deltas[[0, 1, 0]] * deltas[[0, 1, 1]]).sum(axis=2)
        along = 0.5 * np.arctan2(2 * sxy, sxx - syy)  # the scatter's major axis
        normal = np.array([-np.sin(along), np.cos(along)])  # (2, 4)
        normal *= np.sign((normal * outward.T).sum(axis=0))
        residuals = deltas[0] * normal[0, :, None] + deltas[1] * normal[1, :, None]
        kept, distances = weights > 0, np.abs(residuals)
        ordered = np.sort(np.where(kept, distances, np.inf), axis=1)
        spread = ordered[sides, kept.sum(axis=1) // 2] * 1.4826  # MAD of each side
        weights = weights * (distances <= 3.5 * np.maximum(spread, 1e-3)[:, None])
    lines = np.array([*normal, -(normal[0] * centres[0] + normal[1] * centres[1])]).T.copy()
    if phase_points is not None:
        lines, residuals = _remove_pixel_locking(lines, points, weights, phase_points, centres.T)
    rms = np.sqrt((weights * residuals**2).sum(axis=1) / weights.sum(axis=1))
    return lines, rms, _line_offset_sigma(residuals, weights, rms)


def _remove_pixel_locking(
    lines,
    points,
    weights,
    phase_points,
    centres,
    harmonics: int = LOCKING_HARMONICS,
    min_phase_span_px: float = MIN_PHASE_SPAN_PX,
    min_period_span_px: float = MIN_LOCKING_PERIOD_PX,
):
    """Refit the four lines together with the crossings' pixel-locking error.

    A level crossing interpolated between the pixels of a steep, clipped edge is off by a
    periodic function L of the edge's sub-pixel phase (up to ~0.1 px either way at a PSF of
    1 px). Along a side that runs across the pixel grid the phase turns many times and L
    averages out; along one nearly aligned with the grid it drifts slowly and bends or
    tilts the line. L is the same on all four sides when the phase is counted along each
    side's outward axis (the edge profile is the same), so one Fourier series (`harmonics`
    terms) is fitted with small turns and shifts of the four lines, linearly, and left out.
    Returns the new lines and the residuals without L.

    Only sides whose crossings span at least `min_phase_span_px` of their outward axis
    (the fitted line's drift across the pixel grid from its first kept crossing to its
    last) fit L: on a side running along a pixel row or column every crossing has the same
    phase, L is a constant there and cannot be told from the side's own offset (the
    within-side spread of the phase is then the crossings' own noise, so fitting L on it
    would fit the noise and move the side). L from the other sides is still taken out of
    such a side (a trapezoid seen under a tilt). When no side's line crosses `min_period_span_px`
    of the period (a face-to-face view, or a panel square to the pixel grid) nothing is
    refitted and each side keeps its L in its offset and, over the part of the period it crosses,
    in its turn (`solve.side_errors` counts both).
    """
    sides = np.arange(4)
    normal = lines[:, :2]
    tangent = normal[:, ::-1] * [-1.0, 1.0]
    axis = np.argmax(np.abs(normal), axis=1)  # 0: the side's outward axis is x
    sign = np.sign(normal[sides, axis])
    phase = np.mod(sign[:, None] * phase_points[sides, :, axis], 1.0)
    offset = points - centres[:, None, :]
    residuals = offset[..., 0] * normal[:, :1] + offset[..., 1] * normal[:, 1:]
    along = offset[..., 0] * tangent[:, :1] + offset[..., 1] * tangent[:, 1:]
    kept = weights > 0
    extent = np.where(kept, along, -np.inf).max(axis=1) - np.where(kept, along, np.inf).min(axis=1)
    spans = np.abs(tangent[sides, axis]) * extent  # px the line crosses on its outward axis
    if spans.max() < min_period_span_px:
        return lines, residuals
    # columns: a small turn of each side (4), a shift of each side (4), the series (2 per harmonic)
    design = np.zeros(points.shape[:2] + (8 + 2 * harmonics,))
    design[sides, :, sides] = along
    design[sides, :, 4 + sides] = 1.0
    angles = (2 * np.pi * phase)[..., None] * np.arange(1, harmonics + 1)  # (4, n, harmonics)
    cosines, sines = np.cos(angles), np.sin(angles)
    sampled = (spans >= min_phase_span_px)[:, None, None]
    design[..., 8::2] = -cosines * sampled
    design[..., 9::2] = -sines * sampled
    # Normal equations by one matrix product (a 12 x 4n by 4n x 12 GEMM, far below OpenBLAS's
    # threading threshold), not lstsq: LAPACK's least squares wakes OpenBLAS's threads, which
    # then spin on a 2-core machine and stall every stage after them by milliseconds. OpenCV's
    # LU solves them in a tenth of numpy's time (its layers, not the 12 x 12 arithmetic).
    weighted = (design * weights[..., None]).reshape(-1, design.shape[2])
    normal_matrix = weighted.T @ design.reshape(-1, design.shape[2])
    rhs = -(weighted.T @ residuals.reshape(-1))
    solved, solution = cv2.solve(normal_matrix, rhs, flags=cv2.DECOMP_LU)
    solution = solution[:, 0] if solved else np.linalg.solve(normal_matrix, rhs)  # numpy's say when singular
    # L, fitted on the sides that sample its phase, is taken out of all four (the edge profile
    # is the same): each side's turn and shift are fitted again to its crossings less L. Their
    # 2 x 2 normal equations are the diagonal blocks of the ones above.
    locking = cosines @ solution[8::2] + sines @ solution[9::2]
    target = locking - residuals
    moment_0, moment_1 = normal_matrix[sides + 4, sides + 4], normal_matrix[sides, sides + 4]
    moment_2 = normal_matrix[sides, sides]
    rhs_turn, rhs_shift = (weights * along * target).sum(axis=1), (weights * target).sum(axis=1)
    determinant = moment_2 * moment_0 - moment_1**2
    if not np.all(determinant != 0):  # as np.linalg.solve said of a singular side: a numerical failure
        raise np.linalg.LinAlgError("a side's turn and shift are not determined by its crossings")
    turn = (moment_0 * rhs_turn - moment_1 * rhs_shift) / determinant
    shift = (moment_2 * rhs_shift - moment_1 * rhs_turn) / determinant
    new_normal = normal + turn[:, None] * tangent
    scale = _norms(new_normal)
    c = lines[:, 2] + shift - turn * (tangent * centres).sum(axis=1)
    new_lines = np.array([*new_normal.T, c]).T / scale[:, None]
    new_residuals = points[..., 0] * new_lines[:, :1] + points[..., 1] * new_lines[:, 1:2] + new_lines[:, 2:3] - locking
    return new_lines, new_residuals


def _line_offset_sigma(residuals: np.ndarray, weights: np.ndarray, rms: np.ndarray, chunks: int = 8) -> float:
    """1-sigma error (px) of a fitted side's position, noise and slow waviness together.

    Noise averages out along a side (rms / sqrt(n)), but a slow wave does not: on a side
    nearly aligned with the pixel grid the crossings' pixel-locking error drifts with the
    edge's sub-pixel phase and bends the fitted line. The wave is what remains in the
    means of `chunks` consecutive stretches once their own noise is taken out.
    """
    count = weights.sum(axis=1)
    size = residuals.shape[1] // chunks * chunks
    chunk_weights = weights[:, :size].reshape(4, chunks, -1).sum(axis=2)
    chunk_sums = (weights * residuals)[:, :size].reshape(4, chunks, -1).sum(axis=2)
    means = chunk_sums / np.maximum(chunk_weights, 1.0)
    wave = (chunk_weights * means**2).sum(axis=1) / np.maximum(chunk_weights.sum(axis=1), 1.0)
    wave = np.maximum(wave - chunks * rms**2 / count, 0.0)
    return math.sqrt((rms**2 / count + wave).mean())


def _intersections(lines: np.ndarray) -> np.ndarray:
    """Corner k = side k - 1 meets side k, (4, 2)."""
    (a0, b0, c0), (a1, b1, c1) = lines[PREVIOUS].T, lines.T
    w = a0 * b1 - b0 * a1
    return np.array([(b0 * c1 - c0 * b1) / w, (c0 * a1 - a0 * c1) / w]).T.copy()


def blur_sigma_px(growth_px: float, level_gap_px: float) -> float | None:
    """Blur (px, PSF and pixel together) of a Gaussian edge profile from two level crossings.

    With the edge at 0 the profile above background is a Phi(-x / s); the mid-level crossing
    lies `growth_px` outside the edge and the quarter-level one (half the mid level above
    background) `level_gap_px` further out: Phi(-(D + gap) / s) = Phi(-D / s) / 2. The ratio
    grows with s, so s is read off a table.
    """
    if not (np.isfinite(level_gap_px) and level_gap_px > 0):
        return None
    sigmas = BLUR_TABLE_PX
    growth = max(growth_px, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):  # both tails underflow for the narrowest blurs
        ratio = ndtr(-(growth + level_gap_px) / sigmas) / ndtr(-growth / sigmas)
    ratio[np.isnan(ratio)] = 0.0  # 0 / 0 where both tails underflow: the ratio's limit there is 0
    return float(np.interp(0.5, ratio, sigmas))


def locking_sigma_px(blur_px: float, growth_px: float, phases: int = 32) -> float:
    """rms (px) over the edge's sub-pixel phase of a mid-level crossing's pixel-locking error, for
    a Gaussian edge of blur `blur_px` (PSF and pixel together) whose mid level lies `growth_px`
    outside it: what a side along the pixel grid keeps as an offset of its own.

    The crossing is read off the profile interpolated linearly between pixel centres (bilinear
    sampling), where the edge's profile is curved; how much it errs depends on where the edge
    falls between two pixel centres (the phase). The profile is that of the clipped panel:
    a Phi(-x / s) against a saturation of 1, with a = 1 / (2 Phi(-D / s)) putting the mid level
    at D (the growth the corners measured). Its mean over the phase is a common growth, which the
    corners measure with the rest; its spread is returned (0.06 px at s = 1 px, a = 4; 0.1 px at
    s = 0.8 px, a = 6: sharper edges and brighter panels lock harder).
    """
    if not (math.isfinite(blur_px) and math.isfinite(growth_px)):
        return 0.0
    s = min(max(blur_px, 0.1), 8.0)  # `blur_sigma_px`'s table
    growth = min(max(growth_px, 0.0), 4.0 * s)  # beyond, the mid level lies in a tail of no light
    gain = 1.0 / (2.0 * max(float(ndtr(-growth / s)), 1e-6))
    phase = (np.arange(phases) + 0.5) / phases
    reach = int(np.ceil(6 * s + growth)) + 2
    centres = np.arange(-reach, reach + 1)
    values = np.minimum(gain * ndtr((phase[:, None] - centres[None, :]) / s), 1.0)  # edge at x = phase
    below = np.argmax(values < 0.5, axis=1) - 1  # the last pixel centre at or above the mid level
    rows = np.arange(phases)
    upper, lower = values[rows, below], values[rows, below + 1]
    errors = centres[below] + (upper - 0.5) / (upper - lower) - phase
    errors = errors - errors.sum() / phases
    return math.sqrt((errors * errors).sum() / phases)  # np.std's arithmetic


# Where a bare panel's blurred edge has fallen to the background: this band beyond its mid-level
# crossing (px; a PSF of 1-1.5 px leaves ~0.5 % of the contrast there), and how far above the
# background (share of the contrast) the light there must be to be a pedestal of its own.
SURROUND_BAND_PX = (3.0, 5.0)
SURROUND_RISE = 0.02


def pedestal_levels(profiles: np.ndarray, offsets: np.ndarray, crossings: np.ndarray, levels: Levels) -> Levels:
    """The levels an edge is to be read at: `levels`, or with the light just outside the panel as
    the background when it stands out of the frame's. Light there (a lit bezel, a glossy
    ceiling's sheen, the lens's halo) lies under the blurred edge as a pedestal, so the edge is a
    step from it: its mid level, not the frame's, is where the edge crosses at the outline grown by
    one distance, as the corners measure it.

    profiles (n, m) across the edge at `offsets`, outward, with their mid-level `crossings` (n,).
    """
    beyond = offsets[None, :] - crossings[:, None]
    band = (beyond >= SURROUND_BAND_PX[0]) & (beyond <= SURROUND_BAND_PX[1])
    if not band.any():
        return levels
    surround = _median(profiles[band])
    rise = surround - levels.background
    # light at half the contrast or more beside the panel is no pedestal under its edge but glare
    # over it: the edge would be read above its own plateau
    if rise <= SURROUND_RISE * levels.contrast or rise >= 0.5 * levels.contrast:
        return levels
    return Levels(background=surround, plateau=levels.plateau)


def uneven_blur(side_gaps_px: np.ndarray, locking_px: np.ndarray, sigmas: float, fraction: float) -> np.ndarray | None:
    """Each side's gap between its mid- and quarter-level crossings (4,) as motion blurs them, or None.

    Motion during the exposure smears the two sides across it alike and the two along it alike:
    the opposite sides' gaps agree and the two pairs differ. Seen only when the pairs' means differ
    by more than `sigmas` standard errors (the spread of each side's own gaps, and `locking_px`
    (4,), each side's pixel-locking offset), by more than `fraction` of the mean gap, and by more
    than twice the difference within either pair (a tilted panel's near and far sides differ, not
    its pairs). The gaps returned are the pairs' means.

    side_gaps_px (4, n): the gaps of each side's profiles (NaN where a crossing is missing).
    """
    counts = np.isfinite(side_gaps_px).sum(axis=1)
    if counts.min() < 6:
        return None
    medians = _nanmedians(side_gaps_px)
    spread = 1.4826 * _nanmedians(np.abs(side_gaps_px - medians[:, None]))  # robust sigma
    standard_errors = np.hypot(1.2533 * np.maximum(spread, 1e-3) / np.sqrt(counts), locking_px)
    pairs = (medians[[0, 1]] + medians[[2, 3]]) / 2
    between = abs(float(pairs[0] - pairs[1]))
    within = float(np.abs(medians[[0, 1]] - medians[[2, 3]]).max())
    noise = 0.5 * math.sqrt((standard_errors**2).sum())  # of the difference of two pairs' means
    if between <= max(sigmas * noise, fraction * float(medians.mean()), 2 * within):
        return None
    return pairs[[0, 1, 0, 1]]


def side_growths(growth_px: float, level_gap_px: float, side_gaps_px: np.ndarray) -> np.ndarray:
    """Each side's own growth (4,) when their blurs differ: the corners' `growth_px` belongs to the
    common blur (read off `level_gap_px`), and at one overexposure a Gaussian edge's growth is
    proportional to its blur, so each side's is `growth_px` times its blur over the common one."""
    common = blur_sigma_px(growth_px, level_gap_px)
    if not common:
        return np.full(4, growth_px)
    own = np.array([blur_sigma_px(growth_px, gap) or common for gap in side_gaps_px])
    return growth_px * own / common


def square_homography(corners_px: np.ndarray) -> np.ndarray:
    """The homography (3, 3) that takes the square of the sides, corners_px (4, 2) in cyclic order,
    to the unit square (`contour_growth`'s plane; OpenCV's, from the corners as float32)."""
    return cv2.getPerspectiveTransform(corners_px.astype(np.float32), UNIT_SQUARE.astype(np.float32))


def _plane(arc_points_px: np.ndarray, homography: np.ndarray) -> np.ndarray:
    """The arc points (4, m, 2) in the unit square of the sides (`contour_growth`'s plane)."""
    points = arc_points_px.reshape(-1, 1, 2).astype(np.float64)
    return cv2.perspectiveTransform(points, homography).reshape(arc_points_px.shape)


def _growth(
    corners_px: np.ndarray, arc_points_px: np.ndarray, radius_fraction: float, homography: np.ndarray, rules: EdgeRules
) -> float | None:
    """`contour_growth`, by the compiled kernel unless `rules` ask for the reference."""
    if not rules.compiled:
        return contour_growth(corners_px, arc_points_px, radius_fraction, homography)
    plane = _plane(arc_points_px, homography)
    growth = _kernels().arc_growth(plane, corners_px, radius_fraction, UNIT_SQUARE, CORNER_AXES)
    return None if math.isnan(growth) else growth


def contour_growth(
    corners_px: np.ndarray, arc_points_px: np.ndarray, radius_fraction: float, homography: np.ndarray | None = None
) -> float | None:
    """How far (px, >= 0 outward) the measured contour lies outside the panel's outline.

    corners_px (4, 2): corners of the square the measured sides make, cyclic order;
    arc_points_px (4, m, 2): measured contour points on each rounded corner (NaN where a
    profile had none); radius_fraction: corner radius / side of the panel. In the unit
    square of the sides, a point (x, y) of a corner with both axes pointing inward lies on
    the circle of radius R tangent to both axes (centre (R, R)) when R = x + y + sqrt(2 x y)
    (the root on the corner side of the centre). None when fewer than 8 points are usable.
    `homography`: `square_homography(corners_px)`, when the caller has it already.
    """
    if homography is None:
        homography = square_homography(corners_px)
    plane = _plane(arc_points_px, homography)
    local = (plane - UNIT_SQUARE[:, None, :]) @ CORNER_AXES  # (4, m, 2): exact, the axes' entries are 0, +-1
    x, y = local[..., 0], local[..., 1]
    usable = (x > 0) & (y > 0)  # NaN compares False
    if np.count_nonzero(usable) < 8:
        return None
    x, y = x[usable], y[usable]
    radii = x + y + np.sqrt(2 * x * y)
    growth_units = (_median(radii) - radius_fraction) / (1.0 - 2.0 * radius_fraction)
    side_px = float(_norms(corners_px[NEXT] - corners_px).mean())
    return growth_units * side_px


def refine_edges(
    roi: np.ndarray,
    roi_origin: tuple[int, int],
    corners: np.ndarray,
    levels: Levels,
    straight_fraction: float,
    camera_matrix: np.ndarray,
    distortion: np.ndarray | None,
    rules: EdgeRules = EdgeRules(),
) -> EdgeFit | None:
    """Sub-pixel sides and corners of the beacon.

    roi: the raw (unblurred) grey levels around the beacon; roi_origin: its (x, y) in the
    frame; corners (4, 2): starting corners in ROI pixels, cyclic order; straight_fraction:
    the share of each side that is straight (1 - 2 r / side). Returns None when a side has
    too few edge points to fit.
    """
    radius_fraction = (1.0 - straight_fraction) / 2
    offsets = profile_offsets(rules.half_window_px, rules.step_px)
    directions, normals, lengths, radius_px, bases, across, n_along, n_arc, map_x, map_y, inside = _profile_layout(
        corners, straight_fraction, offsets, roi.shape, rules
    )
    use_arcs = n_arc > 0
    # straight from the 8-bit pixels (see `sample_profiles`)
    profiles = cv2.remap(roi, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float32)
    crossings = _crossings(profiles, offsets, levels.threshold, rules)
    warnings: list[str] = []
    side_levels = pedestal_levels(profiles[: 4 * n_along], offsets, crossings[: 4 * n_along], levels)
    if side_levels != levels:
        levels = side_levels
        crossings = _crossings(profiles, offsets, levels.threshold, rules)
    valid = np.isfinite(crossings) & inside
    quarter_level = (levels.threshold + levels.background) / 2
    level_gap = _crossings(profiles[: 4 * n_along], offsets, quarter_level, rules) - crossings[: 4 * n_along]
    every_third = level_gap[::3]  # the common gap from a third of the profiles, as it always was
    level_gap_px = float(_nanmedians(every_third[None, :])[0])
    # A side along the pixel grid keeps its crossings' pixel-locking error as an offset of its gap
    # (two crossings, ~0.06 px each); across the grid by a pixel or more it averages out.
    phase_span_px = straight_fraction * lengths * np.abs(directions).min(axis=1)
    locking_px = LOCKING_GAP_PX * np.minimum(np.maximum(1.0 - phase_span_px, 0.0), 1.0)
    side_gaps_px = uneven_blur(
        level_gap.reshape(4, n_along), locking_px, rules.uneven_blur_sigmas, rules.uneven_blur_fraction
    )

    points = bases + crossings[:, None] * across + np.asarray(roi_origin, dtype=float)
    sensor_points = points[: 4 * n_along].reshape(4, n_along, 2)
    if distortion is not None:
        points = cv2.undistortPoints(points.reshape(-1, 1, 2), camera_matrix, distortion, P=camera_matrix).reshape(
            -1, 2
        )
    side_valid = valid[: 4 * n_along].reshape(4, n_along)
    counts = side_valid.sum(axis=1)
    if counts.min() < max(6, n_along // 3):
        return None
    side_points = np.where(side_valid[..., None], points[: 4 * n_along].reshape(4, n_along, 2), 0.0)
    fit_arguments = (
        side_points,
        side_valid.astype(float),
        normals,
        np.where(side_valid[..., None], sensor_points, 0.0),
    )
    solved = False
    if rules.compiled:
        lines_array, rms, line_sigma, solved = _kernels().fit_lines(
            *fit_arguments, LOCKING_HARMONICS, MIN_PHASE_SPAN_PX, MIN_LOCKING_PERIOD_PX
        )
    if not solved:  # singular equations: the reference says what then
        lines_array, rms, line_sigma = _fit_lines(*fit_arguments)

    shift, curvature_px, uneven_px, locking = 0.0, 0.0, 0.0, None
    side_shifts = np.zeros(4)
    if use_arcs:
        first = 4 * n_along
        arc_points = np.where(valid[first:, None], points[first:], np.nan).reshape(4, n_arc, 2)
        square = _intersections(lines_array)
        homography = square_homography(square)
        growth = _growth(square, arc_points, radius_fraction, homography, rules)
        blur_px = blur_sigma_px(growth, level_gap_px) if growth is not None else None
        if growth is not None and blur_px is not None:
            # put the corner points back where a straight edge's level would be (see above)
            inward_px = blur_px**2 / (2.0 * (radius_px + max(growth, 0.0)))
            arc_points = arc_points + inward_px * across[first:].reshape(4, n_arc, 2)
            before, growth = growth, _growth(square, arc_points, radius_fraction, homography, rules)
            curvature_px = abs(before - growth) if growth is not None else 0.0
        if growth is None:
            warnings.append("too few corner points: sides taken at the mid level")
        else:
            shift = -growth
            if blur_px is not None:
                locking = locking_sigma_px(blur_px, growth)
            side_shifts[:] = shift
            if side_gaps_px is not None and blur_px is not None:
                side_shifts = -side_growths(growth, level_gap_px, side_gaps_px)
                uneven_px = float(np.max(np.abs(side_shifts - shift)))
                blurs = [blur_sigma_px(growth, gap) or float("nan") for gap in side_gaps_px]
                warnings.append(
                    f"the sides are blurred unevenly ({min(blurs):.2f}-{max(blurs):.2f} px; the camera moved "
                    f"during the exposure?): each side moved in by its own growth, {uneven_px:.2f} px apart"
                )
    else:
        warnings.append("corner radius too small in the image to measure the clipped-edge growth")
    lines_array[:, 2] -= side_shifts  # move each line outward by its shift along its normal
    return EdgeFit(
        corners=_intersections(lines_array),
        lines=lines_array,
        edge_shift_px=shift,
        line_rms_px=math.sqrt((rms * rms).mean()),
        line_sigma_px=line_sigma,
        points_per_side=tuple(counts.tolist()),
        arc_points=int(np.count_nonzero(valid[4 * n_along :])),
        warnings=tuple(warnings),
        curvature_px=curvature_px,
        uneven_px=uneven_px,
        locking_px=locking,
    )
