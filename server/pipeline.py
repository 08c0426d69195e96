"""The one-panel pipeline: chains the stages and times each one. No vision happens here.

coarse ROI -> blur -> threshold -> beacon contour -> hull / RDP / sides -> sub-pixel sides
-> centre from the diagonals -> corner order -> pose -> consistency (the fitted panel must explain
the corners within the noise the frame measured, else `shape_mismatch`), for one known map beacon:
the paper's corner path, for a square panel wholly in view. A panel cut by the frame border, any panel
that is not square (a rectangle, a circle), and a square whose outline gives no four sides or
whose corners fix the position only to worse than the map's `required_sigma_m`, takes the
outline path instead: beacon contour -> sub-pixel outline points -> outline fit
(`server.pose.outline`), which refuses what it cannot pin down (`pose_uncertain`), -> shape test
(`server.pose.shape`), which refuses a blob that is not the map's panel (`shape_mismatch`). Every refusal
is a `Refusal` with a reason; only unreadable input raises (in `server.ingest`). Which beacon
is in view, and rooms of several panels, are decided above (`server.locator`).

Read top-down: `_locate_beacon` (region, seed blob) hands on to `_locate_by_corners` or
`_locate_by_outline`; each is a short chain of named steps, and each step times its stages under
the names `timing_ms` reports.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from enum import StrEnum
from functools import partial

import cv2
import numpy as np

from server.diagnostics import Diagnostics, PanelSight
from server.geometry import (
    angle_deg,
    beacon_corners_m,
    beacon_to_world,
    camera_matrix,
    dense_beacon_outline_m,
    distortion_vector,
    gravity_in_camera,
    world_to_camera,
    worst_sigma_2d_m,
)
from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal
from server.pose.consistency import ConsistencyRules, check_fit
from server.pose.ordering import OrderedCorners, order_corners
from server.pose.outline import OutlineFit, OutlineFitRules, fit_outline, fit_outlines
from server.pose.outline import warm_kernels as warm_outline_kernels
from server.pose.shape import ShapeRules, shape_refusal, shape_test
from server.pose.solve import GravityMode, PoseRules, PoseSolution, side_errors, solve_pose
from server.vision.binarize import Levels, blur, threshold
from server.vision.contour import Blob, BlobRules, PanelLook, find_beacon_blob
from server.vision.outline import OutlinePoints, OutlineRules, outline_points
from server.vision.polygon import PolygonRules, Quad, intersect_lines, rounded_square_corners, square_corners
from server.vision.readout import undo_readout_turn
from server.vision.roi import FrameView, Roi, RoiRules, brightest_blob_px, find_roi
from server.vision.subpixel import EdgeFit, EdgeRules, refine_edges
from server.vision.subpixel import warm_kernels as warm_edge_kernels
from shared_schemas import Beacon, BeaconIdSource, FailureReason, ToneCurve

# The app asks for a linear tone curve (docs/android.md); the edge model assumes one.
DEVICE_TONE_CURVE = "the device's tone curve was applied (tone_curve 'device'), not the linear one asked for"


# A fit that overrules the gravity sensor by this many of its sigmas has met a frame its model does
# not hold for (the still frames of the robustness bench stay within 3; walking: 15-66)
GRAVITY_OVERRULED_SIGMAS = 10.0


class CornerMethod(StrEnum):
    rounded = "rounded"  # the paper's rounded-corner path (hull, RDP, sides)
    square = "square"  # the paper's square-corner path (RDP at 1 %, four vertices)


@dataclass(frozen=True)
class PipelineOptions:
    corner_method: CornerMethod = CornerMethod.rounded
    subpixel: bool = True
    gravity_mode: GravityMode = GravityMode.auto
    gravity_sigma_deg: float = 0.1
    blur_kernel_px: int = 5
    mask_step_px: int = 2  # the seed mask is made from every n-th pixel of the region (see locate)
    roi: RoiRules = RoiRules()
    blobs: BlobRules = BlobRules()
    polygon: PolygonRules = PolygonRules()
    edges: EdgeRules = EdgeRules()
    pose: PoseRules = PoseRules()
    consistency: ConsistencyRules = ConsistencyRules()
    outline_points: OutlineRules = OutlineRules()
    outline_fit: OutlineFitRules = OutlineFitRules()
    shape: ShapeRules = ShapeRules()
    # the contour growth this device's whole panels showed (`Fix.growth_px`): given, the outline
    # fit of a cut panel need not tell it from distance (`server.tracking.session` keeps it)
    growth_px: float | None = None
    # given (for a picture of what the pipeline saw: server.annotate), every panel measured is
    # recorded in it; None on the normal path, which then keeps nothing beyond its result
    diagnostics: Diagnostics | None = None


@dataclass
class _Timer:
    timing_ms: dict[str, float] = field(default_factory=dict)

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        start = time.perf_counter()
        try:
            yield
        finally:
            self.timing_ms[name] = (time.perf_counter() - start) * 1000.0

    def refusal(self, refusal: Refusal, warnings: Sequence[str] = ()) -> Refusal:
        """`refusal` with the stage times so far and what was noticed on the way."""
        return replace(refusal, warnings=tuple(warnings), timing_ms=self.total())

    def total(self) -> dict[str, float]:
        return {**self.timing_ms, "total": sum(self.timing_ms.values())}


def _undistorted(points: np.ndarray, matrix: np.ndarray, distortion: np.ndarray | None) -> np.ndarray:
    if distortion is None or len(points) == 0:  # (OpenCV returns None for no points)
        return points
    return cv2.undistortPoints(points.reshape(-1, 1, 2), matrix, distortion, P=matrix).reshape(-1, 2)


@dataclass
class _Seen:
    """What the stages of one `locate_beacon` call found, by reference (no copies, no cost): made
    into a `PanelSight` only when the options ask for diagnostics."""

    roi: Roi | None = None
    step: int = 1  # of the mask the blob's contour is in
    blob: Blob | None = None
    quad: Quad | None = None  # window pixels
    edges: EdgeFit | None = None
    outline: OutlinePoints | None = None


@dataclass(frozen=True)
class _Job:
    """One `locate_beacon` call: what every step reads, and where the steps' times and sightings go."""

    frame: LumaFrame
    beacon: Beacon
    options: PipelineOptions
    id_source: BeaconIdSource
    timer: _Timer
    seen: _Seen
    matrix: np.ndarray
    distortion: np.ndarray | None
    look: PanelLook

    @classmethod
    def of(
        cls, frame: LumaFrame, beacon: Beacon, options: PipelineOptions, id_source: BeaconIdSource, seen: _Seen
    ) -> _Job:
        matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
        return cls(frame, beacon, options, id_source, _Timer(), seen, matrix, distortion, PanelLook.of(beacon))


@dataclass(frozen=True)
class _SeedBlob:
    """The beacon's blob in the region's seed mask (every `step`-th pixel of `window`, the region's
    pixels), and its bounding box in frame pixels (x, y, width, height)."""

    blob: Blob
    step: int
    window: np.ndarray
    box: tuple[int, int, int, int]


@dataclass(frozen=True)
class _Corners:
    """The panel's corners in ideal (undistorted) frame pixels at the frame's one instant, in the
    map's order, and the centre from the diagonals."""

    ordered: OrderedCorners
    center_px: np.ndarray


@dataclass(frozen=True)
class _CornerWeights:
    """How far the pose is to trust the corners, and the gravity sensor beside them."""

    corner_sigma_px: float
    growth_sigma_px: float | None
    locking_sigma_px: float | None
    uneven_px: float
    gravity_mode: GravityMode
    warnings: tuple[str, ...]


def locate_beacon(
    frame: LumaFrame,
    beacon: Beacon,
    options: PipelineOptions = PipelineOptions(),
    id_source: BeaconIdSource = BeaconIdSource.single_beacon_map,
) -> Fix | Refusal:
    """The pose of the camera that took `frame`, which shows map beacon `beacon`, or why there is none."""
    seen = _Seen()
    outcome = _locate_beacon(_Job.of(frame, beacon, options, id_source, seen))
    if options.diagnostics is not None:
        options.diagnostics.add(_sight(frame, beacon.id, seen, outcome, options))
    return outcome


def _sight(
    frame: LumaFrame, beacon_id: int, seen: _Seen, outcome: Fix | Refusal, options: PipelineOptions
) -> PanelSight:
    """What `seen` holds, in the full frame's (distorted) pixels; refused at the ROI stage, its largest blob."""
    roi = seen.roi
    origin = np.zeros(2) if roi is None else np.array([roi.x0, roi.y0], dtype=float)
    if roi is None:  # refused on the coarse view: the blob it judged
        contour = brightest_blob_px(frame.pixels, options.roi, FrameView.of(frame.meta))
    else:
        contour = None if seen.blob is None else seen.blob.contour * seen.step + origin
    sight = PanelSight(
        beacon_id=beacon_id,
        outcome=outcome,
        roi_px=None if roi is None else (roi.x0, roi.y0, roi.x1, roi.y1),
        threshold_dn=None if roi is None else roi.levels.threshold,
        contour_px=contour,
        cut=seen.blob is not None and seen.blob.cut,
        polygon_px=None if seen.quad is None else seen.quad.corners + origin,
        sides_px=None if seen.edges is None else _sides_px(seen.edges, frame),
        outline_px=None if seen.outline is None else seen.outline.points_px,
    )
    return sight.moved(frame.meta.full_offset)


def _sides_px(edges: EdgeFit, frame: LumaFrame) -> np.ndarray:
    """Each fitted side (4, 25, 2) drawn from corner to corner, through the lens again (the fit is undistorted)."""
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    corners, along = edges.corners, np.linspace(0.0, 1.0, 25)[:, None]
    return np.stack(
        [_distorted(corners[k] + along * (corners[(k + 1) % 4] - corners[k]), matrix, distortion) for k in range(4)]
    )


def _locate_beacon(job: _Job) -> Fix | Refusal:
    """The region, the blob in it, then the corner path for a square wholly in view, else the outline path."""
    roi = _find_region(job)
    if isinstance(roi, Refusal):
        return job.timer.refusal(roi)
    job.seen.roi = roi
    seed = _seed_blob(job, roi)
    if isinstance(seed, Refusal):
        return job.timer.refusal(seed)
    job.seen.blob, job.seen.step = seed.blob, seed.step
    if seed.blob.cut or not _corner_path_fits(job.beacon):
        return _locate_by_outline(job, seed.box, roi.levels, cut=seed.blob.cut)
    return _locate_by_corners(job, roi, seed)


def _corner_path_fits(beacon: Beacon) -> bool:
    """The paper's corner path is for squares; rectangles and circles take the outline path."""
    width, height = beacon.extent_m
    return beacon.has_corners and width == height


def _find_region(job: _Job) -> Roi | Refusal:
    """The region of the frame the panel lies in, and its levels, from the coarse view."""
    with job.timer.stage("roi"):
        return find_roi(job.frame.pixels, job.options.roi, job.options.blobs, job.look, FrameView.of(job.frame.meta))


def _seed_blob(job: _Job, roi: Roi) -> _SeedBlob | Refusal:
    """The beacon's blob in the region's seed mask (blurred, thresholded at the region's levels)."""
    options = job.options
    window = job.frame.pixels[roi.y0 : roi.y1, roi.x0 : roi.x1]
    step = options.mask_step_px if options.subpixel else 1
    with job.timer.stage("blur"):
        # The mask only seeds the sub-pixel stage, which samples the window along the sides
        # (O(perimeter)): corners a pixel or two off are as good a start, for a quarter of the blur
        # and contour work. Without that stage (the paper's path) the corners come from the mask:
        # every pixel.
        blurred = blur(window[::step, ::step], options.blur_kernel_px)
    with job.timer.stage("threshold"):
        mask = threshold(blurred, roi.levels)
    with job.timer.stage("contour"):
        blob = find_beacon_blob(mask, options.blobs, job.look)
    if isinstance(blob, Refusal):
        return blob
    x, y, w, h = blob.bounding_box
    return _SeedBlob(blob, step, window, (roi.x0 + x * step, roi.y0 + y * step, w * step, h * step))


# --- the corner path: a square panel wholly in view -------------------------------------------


def _locate_by_corners(job: _Job, roi: Roi, seed: _SeedBlob) -> Fix | Refusal:
    """The paper's corner path: polygon, sub-pixel sides, corners, pose, the check against the
    evidence; the outline path where the corners cannot pin the panel down."""
    quad = _polygon(job, seed)
    if isinstance(quad, Refusal):
        if not _may_fall_back(job):
            return job.timer.refusal(quad)
        # RDP found no four straight sides (a small panel, its rounded corners a large share of
        # its outline, or a soft edge): the outline fit needs no sides, only the outline.
        return _locate_by_outline(job, seed.box, roi.levels, cut=False)
    job.seen.quad = quad
    edges = _subpixel_edges(job, roi, seed.window, quad)
    if job.options.subpixel and edges is None:
        # The polygon's corners were too far off for the sides' search windows (a large panel
        # whose small corner arcs RDP takes for sharp corners): its visible outline measures it.
        return _locate_by_outline(job, seed.box, roi.levels, cut=False)
    job.seen.edges = edges
    warnings = edges.warnings if edges is not None else ()
    corners = _corners(job, roi, quad, edges)
    if isinstance(corners, Refusal):
        return job.timer.refusal(corners, warnings)
    weights = _corner_weights(job, corners.ordered, edges)
    pose, overruled = _corner_pose(job, corners, weights)
    warnings = (*warnings, *weights.warnings, *overruled)
    if isinstance(pose, Refusal):
        return job.timer.refusal(pose, warnings)
    reported = _reported_px(job, corners)
    refusal = _check_corner_pose(job, pose, edges, reported)
    if refusal is not None:
        return job.timer.refusal(refusal, warnings)
    fix = _corner_fix(job, corners.ordered, edges, pose, reported, warnings)
    return _unless_loose(job, fix, edges, seed.box, roi.levels)


def _beyond_paper(options: PipelineOptions) -> bool:
    """Whether this is our path; the paper's own (no sub-pixel stage, or square corners) stays as the paper has it."""
    return options.subpixel and options.corner_method is CornerMethod.rounded


def _may_fall_back(job: _Job) -> bool:
    """Whether the outline path may stand in for the corners: beyond the paper, and not under the
    device's tone curve, which only the corner path's uncertainty knows of."""
    return _beyond_paper(job.options) and job.frame.meta.tone_curve is not ToneCurve.device


def _polygon(job: _Job, seed: _SeedBlob) -> Quad | Refusal:
    """The blob's four corners (window pixels), or why its outline gives no four sides."""
    with job.timer.stage("polygon"):
        quad = (
            rounded_square_corners(seed.blob.contour, job.options.polygon)
            if job.options.corner_method is CornerMethod.rounded
            else square_corners(seed.blob.contour)
        )
    if isinstance(quad, Refusal):
        return quad
    return Quad(corners=quad.corners * seed.step)  # pixel i of the mask is pixel step * i of the window


def _subpixel_edges(job: _Job, roi: Roi, window: np.ndarray, quad: Quad) -> EdgeFit | None:
    """The sides refined to sub-pixel (undistorted frame pixels); None without that stage, or where the
    polygon's corners were too far off for the sides' search windows."""
    with job.timer.stage("subpixel"):
        if not job.options.subpixel:
            return None
        beacon = job.beacon
        straight = 1.0 - 2.0 * beacon.corner_radius_m / min(beacon.extent_m)
        return refine_edges(
            window, (roi.x0, roi.y0), quad.corners, roi.levels, straight, job.matrix, job.distortion, job.options.edges
        )


def _corners(job: _Job, roi: Roi, quad: Quad, edges: EdgeFit | None) -> _Corners | Refusal:
    """The sides' corners (else the polygon's, undistorted) at the frame's one instant, in the map's
    order, and the centre from the diagonals."""
    if edges is not None:
        corners = edges.corners
    else:
        corners = _undistorted(quad.corners + np.array([roi.x0, roi.y0], dtype=float), job.matrix, job.distortion)
    corners = undo_readout_turn(corners, job.matrix, job.frame.meta)
    with job.timer.stage("center"):
        center = intersect_lines(corners[0], corners[2], corners[1], corners[3])
    if center is None:
        return Refusal(FailureReason.not_four_sides, "the diagonals do not intersect")
    return _Corners(order_corners(corners, job.beacon.yaw_deg, job.frame.meta.heading_deg), center)


def _corner_weights(job: _Job, ordered: OrderedCorners, edges: EdgeFit | None) -> _CornerWeights:
    """The corners' errors for the pose, from what the sides measured (the paper's paths: a pixel)."""
    options = job.options
    if edges is None:
        return _CornerWeights(1.0, None, None, 0.0, options.gravity_mode, ())
    # What the edge model cannot know, added to the growth's error as a 1-sigma of its own size:
    # - the device's own tone curve: the mid level lies far down the edge's tail in light, where the
    #   corners' level set is no longer the outline grown by one distance; the growth's error is of
    #   the size of the blur's rounding of the corners (sRGB at 2 m, quarter resolution: 0.25-0.35
    #   px against a 0.6-0.9 px term);
    # - sides blurred unevenly (motion): each side's growth is scaled from the common one by its
    #   blur, a Gaussian edge's rule, which a motion-blurred edge follows only roughly.
    device_curve = job.frame.meta.tone_curve is ToneCurve.device
    unknown = (edges.curvature_px if device_curve else 0.0, edges.uneven_px)
    growth_sigma = None
    if any(unknown):
        predicted = side_errors(
            ordered.corners, job.beacon, edges.line_sigma_px, rules=options.pose, locking_sigma_px=edges.locking_px
        ).growth_sigma
        growth_sigma = math.hypot(predicted, *unknown)
    # Motion skews and smears the square (rolling shutter, blur), which the corners read as tilt;
    # the gravity sensor does not see it: in auto mode it then sets the tilt.
    moved = edges.uneven_px > 0 and options.gravity_mode is GravityMode.auto
    return _CornerWeights(
        corner_sigma_px=edges.line_sigma_px,
        growth_sigma_px=growth_sigma,
        locking_sigma_px=edges.locking_px,
        uneven_px=edges.uneven_px,
        gravity_mode=GravityMode.always if moved else options.gravity_mode,
        warnings=(f"{DEVICE_TONE_CURVE}: the clipped-edge growth is uncertain by {unknown[0]:.2f} px more",)
        if device_curve
        else (),
    )


def _corner_pose(
    job: _Job, corners: _Corners, weights: _CornerWeights
) -> tuple[PoseSolution | Refusal, tuple[str, ...]]:
    """The pose from the corners, and the warning when they overruled the gravity sensor by far."""
    meta, options = job.frame.meta, job.options
    gravity = None if meta.gravity_camera is None else np.asarray(meta.gravity_camera)
    # both solves called from here, so that a numerical failure names this stage (server.locator)
    solve = partial(
        solve_pose,
        corners.ordered.corners,
        corners.center_px,
        job.beacon,
        job.matrix,
        gravity,
        options.gravity_sigma_deg,
        corner_sigma_px=weights.corner_sigma_px,
        rules=options.pose,
        growth_sigma_px=weights.growth_sigma_px,
        locking_sigma_px=weights.locking_sigma_px,
        uneven_px=weights.uneven_px,
    )
    warnings: tuple[str, ...] = ()
    with job.timer.stage("pose"):
        pose = solve(gravity_mode=weights.gravity_mode)
        off_deg = _tilt_off_gravity_deg(pose.rotation_wc, gravity) if not isinstance(pose, Refusal) else 0.0
        if weights.gravity_mode is GravityMode.auto and off_deg > GRAVITY_OVERRULED_SIGMAS * options.gravity_sigma_deg:
            # The corners overrule the gravity sensor by far: the square's shape is not the still
            # panel's (smeared or skewed by a moving camera where the sides' blur did not tell)
            warnings = (
                f"the panel's shape tilts the camera {off_deg:.1f} deg from the gravity sensor's reading: "
                f"the sensor's tilt taken (did the camera move?)",
            )
            pose = solve(gravity_mode=GravityMode.always)
    return pose, warnings


def _reported_px(job: _Job, corners: _Corners) -> np.ndarray:
    """The corners (4, in the map's order) and the centre (last) in the frame's (distorted) pixels, for the fix."""
    return _distorted(np.vstack([corners.ordered.corners, corners.center_px]), job.matrix, job.distortion)


def _check_corner_pose(job: _Job, pose: PoseSolution, edges: EdgeFit | None, reported_px: np.ndarray) -> Refusal | None:
    """Why the corner path's pose is no fix (numbers not finite, or it does not explain its own corners), or None."""
    arrays = (pose.position_m, pose.rotation_wc, reported_px)
    numbers = [value for array in arrays for value in np.ravel(array).tolist()]
    if not all(map(math.isfinite, (*numbers, pose.reprojection_error_px, pose.ambiguity_ratio))):
        # extreme but valid intrinsics or distortion can overflow without raising: such a fix
        # must not reach a device's track (it would stay NaN) nor the result
        return Refusal(FailureReason.numerical_failure, "the pose or the reported corners are not finite numbers")
    if edges is None or pose.residuals is None:
        return None
    # the fix must answer to its own evidence: the corners against the map beacon's shape, within
    # the noise the sides measured (the paper's paths measure none: their corners are the mask's)
    with job.timer.stage("consistency"):
        judged = check_fit(pose.residuals, job.beacon, job.options.consistency)
    return judged if isinstance(judged, Refusal) else None


def _corner_fix(
    job: _Job,
    ordered: OrderedCorners,
    edges: EdgeFit | None,
    pose: PoseSolution,
    reported_px: np.ndarray,
    warnings: tuple[str, ...],
) -> Fix:
    """The corner path's `Fix`, with the stage times so far."""
    return Fix(
        position_m=pose.position_m,
        rotation_wc=pose.rotation_wc,
        beacon_id=job.beacon.id,
        id_source=job.id_source,
        reprojection_error_px=pose.reprojection_error_px,
        gravity_used=pose.gravity_used,
        center_px=reported_px[4],
        corners_px=reported_px[:4],
        orientation_rule=ordered.rule,
        ambiguity_ratio=pose.ambiguity_ratio,
        covariance_m2=pose.covariance_m2,
        growth_px=-edges.edge_shift_px if edges is not None and edges.edge_shift_px else None,
        uneven_px=edges.uneven_px if edges is not None else 0.0,
        warnings=warnings,
        timing_ms=job.timer.total(),
    )


def _unless_loose(
    job: _Job, fix: Fix, edges: EdgeFit | None, box: tuple[int, int, int, int], levels: Levels
) -> Fix | Refusal:
    """`fix`, unless its corners fix the position worse than the map's `required_sigma_m`: then
    the outline fit decides, or, where it may not stand in, a refusal."""
    options = job.options
    if not _beyond_paper(options) or fix.covariance_m2 is None:
        return fix
    corner_sigma_mm = worst_sigma_2d_m(fix.covariance_m2) * 1000
    if corner_sigma_mm <= options.outline_fit.max_sigma_m * 1000:
        return fix
    if not _may_fall_back(job) or (edges is not None and edges.uneven_px):  # one growth would not do either
        return job.timer.refusal(
            Refusal(
                FailureReason.pose_uncertain,
                f"the panel's corners fix the position only to {corner_sigma_mm:.0f} mm (1 sigma); the map's "
                f"required_sigma_m is {options.outline_fit.max_sigma_m * 1000:.3g} mm",
            ),
            fix.warnings,
        )
    # The corners fix the position only loosely (a small panel whose few-pixel corner arcs
    # measure the clipped-edge growth badly): the outline fit, which fits the growth with the
    # pose from every outline point, decides; what it cannot pin down is refused.
    by_outline = _locate_by_outline(job, box, levels, cut=False)
    note = f"the corners fixed the position only to {corner_sigma_mm:.0f} mm (1 sigma): outline fit"
    if not isinstance(by_outline, Fix):
        return replace(by_outline, warnings=(*by_outline.warnings, note))
    doubt = _outline_doubt(by_outline, fix, job.frame, options)
    if doubt is not None:
        return job.timer.refusal(Refusal(FailureReason.pose_uncertain, doubt), [*fix.warnings, note])
    return by_outline.warned(note)


def _outline_doubt(by_outline: Fix, by_corners: Fix, frame: LumaFrame, options: PipelineOptions) -> str | None:
    """Why the outline fit standing in for loose corners is not to be trusted, or None.

    The two must agree within their uncertainties, and the outline must not overrule the gravity
    sensor by far: where they do not, the frame breaks a model both share (the panel moved or
    smeared across the frame)."""
    apart_m = np.subtract(by_outline.position_m, by_corners.position_m)[:2]
    if by_outline.covariance_m2 is not None and by_corners.covariance_m2 is not None:
        joint = np.asarray(by_corners.covariance_m2)[:2, :2] + np.asarray(by_outline.covariance_m2)[:2, :2]
        if float(apart_m @ np.linalg.solve(joint, apart_m)) > options.pose.consistency_chi_square:
            return (
                f"the corners and the outline of the panel place the camera {np.hypot(*apart_m) * 1000:.0f} mm "
                f"apart, more than their uncertainties allow"
            )
    off_deg = _tilt_off_gravity_deg(by_outline.rotation_wc, _gravity(frame, options))
    if off_deg > GRAVITY_OVERRULED_SIGMAS * options.gravity_sigma_deg:
        return (
            f"the outline of the panel tilts the camera {off_deg:.1f} deg from the gravity sensor's "
            f"reading (its error is {options.gravity_sigma_deg:g} deg)"
        )
    return None


def _tilt_off_gravity_deg(rotation_wc: np.ndarray, gravity_camera: np.ndarray | None) -> float:
    """The angle (deg) between a pose's down and the gravity sensor's, 0 without a sensor."""
    return 0.0 if gravity_camera is None else angle_deg(gravity_in_camera(rotation_wc), gravity_camera)


# --- the outline path: a panel cut by the frame border, of another shape, or a loose square ----


def _locate_by_outline(job: _Job, box: tuple[int, int, int, int], levels: Levels, cut: bool) -> Fix | Refusal:
    """The pose from the visible outline of the blob in `box` (frame pixels): its outline points,
    the outline fit, the shape test."""
    found, points = _outline_of(job, box, levels)
    job.seen.outline = found
    gravity = _gravity(job.frame, job.options)
    fit = _fit_panel_outline(job, points, found.level_gap_px, gravity, cut)
    if isinstance(fit, Refusal):
        return job.timer.refusal(fit)
    with job.timer.stage("shape"):
        mismatch = _shape_mismatch(job.frame, [job.beacon], fit, found.points_px, found.edge_noise_px, job.options)
    if mismatch is not None:
        return job.timer.refusal(mismatch)
    what = "a panel cut by the frame border" if cut else "the panel"
    note = f"pose from the visible outline of {what} ({fit.points} points, growth {fit.growth_px:.2f} px)"
    return _outline_fix(job.frame, job.beacon, fit, job.id_source, gravity is not None, note, job.timer)


def _outline_of(job: _Job, box: tuple[int, int, int, int], levels: Levels) -> tuple[OutlinePoints, np.ndarray]:
    """The blob's outline points in `box`, and the same undistorted, at the frame's one instant."""
    with job.timer.stage("outline"):
        found = outline_points(job.frame.pixels, box, levels, job.options.outline_points)
        ideal = _undistorted(found.points_px, job.matrix, job.distortion)
        return found, undo_readout_turn(ideal, job.matrix, job.frame.meta)


def _fit_panel_outline(
    job: _Job, points: np.ndarray, level_gap_px: float, gravity: np.ndarray | None, cut: bool
) -> OutlineFit | Refusal:
    """The outline fit of one panel; a cut one takes the growth this device's whole panels showed."""
    options = job.options
    with job.timer.stage("pose"):
        return fit_outline(
            points,
            level_gap_px,
            job.beacon,
            job.matrix,
            gravity,
            options.gravity_sigma_deg,
            job.frame.meta.heading_deg,
            growth_px=options.growth_px if cut else None,
            rules=options.outline_fit,
        )


def locate_by_outlines(
    frame: LumaFrame,
    panels: list[tuple[Beacon, tuple[int, int, int, int]]],
    levels: Levels,
    options: PipelineOptions,
    start_position_m: np.ndarray,
    start_yaw_deg: float,
) -> Fix | Refusal:
    """The pose from the visible outlines of several map panels together (boxes in frame
    pixels), from a start: a device's cut panels, named by its track. The fix names the first."""
    timer = _Timer()
    if not panels:
        return timer.refusal(Refusal(FailureReason.beacon_cut_off, "no cut panels to fit"))
    found, points = _outlines_of(frame, panels, levels, options, timer)
    if not points:
        return timer.refusal(Refusal(FailureReason.beacon_cut_off, "no outline points of the cut panels in view"))
    gravity = _gravity(frame, options)
    level_gap_px = _finite_median([f.level_gap_px for f in found])
    with timer.stage("pose"):
        fit = fit_outlines(
            points,
            level_gap_px,
            camera_matrix(frame.camera),
            gravity,
            options.gravity_sigma_deg,
            start_position_m,
            start_yaw_deg,
            options.growth_px,
            options.outline_fit,
        )
    if isinstance(fit, Refusal):
        return timer.refusal(fit)
    with timer.stage("shape"):
        every = np.vstack([f.points_px for f in found])
        noise = _finite_median([f.edge_noise_px for f in found])
        mismatch = _shape_mismatch(frame, [b for b, _ in points], fit, every, noise, options)
    if mismatch is not None:
        return timer.refusal(mismatch)
    note = f"pose from the visible outlines of cut panels {[b.id for b, _ in points]} together ({fit.points} points)"
    return _outline_fix(frame, points[0][0], fit, BeaconIdSource.track, gravity is not None, note, timer)


def _outlines_of(
    frame: LumaFrame,
    panels: list[tuple[Beacon, tuple[int, int, int, int]]],
    levels: Levels,
    options: PipelineOptions,
    timer: _Timer,
) -> tuple[list[OutlinePoints], list[tuple[Beacon, np.ndarray]]]:
    """Each panel's outline points in its box, and those of the panels that show any, undistorted,
    at the frame's one instant (one for all panels)."""
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    with timer.stage("outline"):
        found = [outline_points(frame.pixels, box, levels, options.outline_points) for _, box in panels]
        ideal = [_undistorted(f.points_px, matrix, distortion) for f in found]
        turned = undo_readout_turn(np.vstack(ideal), matrix, frame.meta)
        split = np.split(turned, np.cumsum([len(p) for p in ideal])[:-1])
        return found, [(beacon, p) for (beacon, _), p in zip(panels, split, strict=True) if len(p)]


def _finite_median(values: list[float]) -> float:
    """The median of the finite `values`, NaN without any."""
    finite = [value for value in values if np.isfinite(value)]
    return float(np.median(finite)) if finite else float("nan")


def _shape_mismatch(
    frame: LumaFrame,
    beacons: list[Beacon],
    fit: OutlineFit,
    points_px: np.ndarray,
    edge_noise_px: float,
    options: PipelineOptions,
) -> Refusal | None:
    """The shape test of an outline fit (`server.pose.shape`): None when the blob is the panel's shape."""
    in_view = _outline_in_view_px(frame, beacons, fit, options.outline_points.border_px)
    test = shape_test(fit.residuals_px, fit.parameters, edge_noise_px, in_view, points_px, fit.growth_px, options.shape)
    return shape_refusal(test, beacons[0], options.shape)


def _outline_in_view_px(frame: LumaFrame, beacons: list[Beacon], fit: OutlineFit, border_px: float) -> np.ndarray:
    """The fitted panels' outlines (M, 2), about a pixel apart, where they lie in the frame (frame
    pixels, more than `border_px` inside its border): where the outline points should be."""
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    height, width = frame.pixels.shape
    seen = []
    for beacon in beacons:
        distance_m = float(np.linalg.norm(np.subtract(beacon.center_m, fit.position_m)))
        span_px = min(float(matrix[0, 0]) * beacon.size_m / max(distance_m, 1e-3), 8000.0)
        outline = beacon_to_world(beacon, dense_beacon_outline_m(beacon, span_px))
        in_camera = world_to_camera(outline, fit.position_m, fit.rotation_wc)
        in_camera = in_camera[in_camera[:, 2] > 1e-6]
        # the lens's distortion only where the ideal projection is near the frame (its polynomial
        # folds far outside it)
        ideal = in_camera[:, :2] / in_camera[:, 2:] * np.diag(matrix)[:2] + matrix[:2, 2]
        near = np.all((ideal > -0.1 * np.array([width, height])) & (ideal < 1.1 * np.array([width, height])), axis=1)
        if not near.any():
            continue
        projected, _ = cv2.projectPoints(in_camera[near], np.zeros(3), np.zeros(3), matrix, distortion)
        seen.append(projected.reshape(-1, 2))
    if not seen:
        return np.zeros((0, 2))
    px = np.vstack(seen)
    inside = np.all((px > border_px) & (px < np.array([width, height]) - 1 - border_px), axis=1)
    return px[inside]


def _gravity(frame: LumaFrame, options: PipelineOptions) -> np.ndarray | None:
    """The frame's gravity vector for the outline fit, unless there is none or it is not to be used."""
    if frame.meta.gravity_camera is None or options.gravity_mode is GravityMode.never:
        return None
    return np.asarray(frame.meta.gravity_camera, dtype=float)


def _outline_fix(
    frame: LumaFrame,
    beacon: Beacon,
    fit: OutlineFit,
    id_source: BeaconIdSource,
    gravity_used: bool,
    note: str,
    timer: _Timer,
) -> Fix:
    """The `Fix` of an outline fit, with `beacon`'s corners and centre projected into the frame."""
    projected = _corners_and_centre_px(frame, beacon, fit)
    return Fix(
        position_m=fit.position_m,
        rotation_wc=fit.rotation_wc,
        beacon_id=beacon.id,
        id_source=id_source,
        reprojection_error_px=fit.rms_px,
        gravity_used=gravity_used,
        center_px=projected[-1],
        corners_px=projected[:4] if beacon.has_corners else None,
        orientation_rule=fit.orientation_rule,
        covariance_m2=fit.covariance_m2,
        growth_px=fit.growth_px,
        from_outline=True,
        warnings=(note, f"{DEVICE_TONE_CURVE}: the outline fit's uncertainty does not include it")
        if frame.meta.tone_curve is ToneCurve.device
        else (note,),
        timing_ms=timer.total(),
    )


def _corners_and_centre_px(frame: LumaFrame, beacon: Beacon, fit: OutlineFit) -> np.ndarray:
    """`beacon`'s corners (none without) and centre (last) as the fitted pose puts them in the frame (distorted)."""
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    corners_m = beacon_to_world(beacon, beacon_corners_m(beacon)) if beacon.has_corners else np.zeros((0, 3))
    model = np.vstack([corners_m, np.asarray(beacon.center_m, float)[None, :]])
    in_camera = world_to_camera(model, fit.position_m, fit.rotation_wc)
    projected, _ = cv2.projectPoints(in_camera, np.zeros(3), np.zeros(3), matrix, distortion)
    return projected.reshape(-1, 2)


def _distorted(points: np.ndarray, matrix: np.ndarray, distortion: np.ndarray | None) -> np.ndarray:
    """Ideal pixel coordinates back to the frame's (distorted) pixels, for reporting."""
    if distortion is None:
        return points
    normalized = np.column_stack([points, np.ones(len(points))]) @ np.linalg.inv(matrix).T
    projected, _ = cv2.projectPoints(normalized, np.zeros(3), np.zeros(3), matrix, distortion)
    return projected.reshape(-1, 2)


def warm_kernels() -> None:
    """Load the pipeline's compiled kernels (numba; on a cold cache it compiles them: ~15 s CPU, then cached in
    `__pycache__`): the service at its start (`server.api.main`), setup once (`scripts/setup.sh`), so that no
    request and no first `lumipose locate` waits for them."""
    warm_edge_kernels()  # every frame's corners need these
    warm_outline_kernels()
