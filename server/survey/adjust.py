"""Stage 3 of a survey: the bundle adjustment of every panel and every camera together.

Unknowns: each panel's centre (x, y, z) and yaw, except the anchor's (its sketch centre and yaw
fix the map's frame); each frame's camera pose (rotation vector of `rotation_wc`, optical
centre). Panels hang level on the ceiling: their tilt is not an unknown (a panel's own tilt of a
few tenths of a degree would move its corners by well under a tenth of a millimetre). And the
clipped-edge growth of the whole panels' mid-level corners (`server.survey.sightings`): D0 + D2 r^2
with r the panel's distance from the principal point in focal lengths (the lens vignettes, so the
overexposure and the growth fall towards the corners); D0 for each panel (real panels differ in
luminance by 10-20 %, and the growth with it), both per group of frames of one size and exposure
(`FrameSightings.growth_group`: the growth in px scales with both). The panels' sizes set the map's
scale, and a panel's frames at different distances tell its growth from it.

Residuals (`scipy.optimize.least_squares`, a sparse Jacobian through `jac_sparsity`: a panel's
points depend on its four numbers and its frame's six only):

- each sighting's five points (four corners and the centre, ideal pixels) against the panel's
  model projected by the frame's camera (a whole panel's corners grown by the growth), over the
  sighting's sigma;
- each frame's gravity reading against the camera's down, over the sensor's sigma (the two
  components across the reading), which levels the map: without it a common tilt of all cameras
  and panels would fit the images nearly as well.

Uncertainty: the covariance of the unknowns is (J^T J)^-1 scaled by the residuals' variance
(their sum of squares over the degrees of freedom), so sigmas that were guessed too small or too
large are corrected by the fit itself; only the panels' part is formed, by the Schur complement
over the cameras (`without_cameras_covariance`). A square's corners are labelled (which of its four is
model corner 0) against the start's yaw before the fit, and kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import block_diag, csr_matrix, lil_matrix
from scipy.spatial.transform import Rotation

from server.geometry import beacon_corners_m, grown_quads, orthonormal_pair, wrap_deg
from server.pose.outline import HELD_GROWTH_PX
from server.survey.chain import CameraPose, PanelPose, Start, symmetry_deg
from server.survey.rules import SurveyRules
from server.survey.sightings import FrameSightings, Sighting
from shared_schemas import Beacon

DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class PanelEstimate:
    pose: PanelPose
    center_sigma_m: np.ndarray  # (3,)
    yaw_sigma_deg: float
    frames: int


@dataclass(frozen=True)
class Adjusted:
    panels: dict[int, PanelEstimate]
    cameras: tuple[CameraPose, ...]
    rms_px: float
    sighting_rms_px: tuple[tuple[float, ...], ...]  # per frame, per sighting: its points' RMS (px)
    sighting_chi: tuple[tuple[float, ...], ...]  # the same over the points' sigmas


def _model_points(beacon: Beacon, shift: int) -> np.ndarray:
    """(5, 3) the panel's corners relabelled by `shift` (image corner k is model corner k + shift) and centre."""
    corners = np.roll(beacon_corners_m(beacon), -shift, axis=0)
    return np.vstack([corners, np.zeros(3)])


class _Problem:
    """The fixed inputs of the fit, flattened over all sightings (N) and frames (F)."""

    def __init__(self, frames: list[FrameSightings], start: Start, anchor: int) -> None:
        self.anchor = anchor
        self.free = sorted(k for k in start.panels if k != anchor)
        self.column = {beacon_id: 4 * j for j, beacon_id in enumerate(self.free)}
        self.frame_base = 4 * len(self.free)
        self.frames = frames
        self.start = start
        sightings = [(f, s) for f, frame in enumerate(frames) for s in frame.sightings]
        self.frame_of = np.array([f for f, _ in sightings])
        self.panel_ids = [s.beacon.id for _, s in sightings]
        self.sigma = np.array([s.sigmas_px for _, s in sightings])  # (N, 5)
        self.grown = np.array([s.grown for _, s in sightings], bool)
        self.observed = np.array([s.points_px for _, s in sightings])  # (N, 5, 2)
        # each panel's own growth (D0) per group of frames that share size and exposure; the fall with r^2
        # (D2) per group: growth = D0 + D2 r^2
        groups = list(dict.fromkeys(frame.growth_group for frame in frames))
        keys = list(dict.fromkeys((s.beacon.id, frames[f].growth_group) for f, s in sightings if s.grown))
        self.growth_keys = keys
        self.groups = len(groups)
        key_index = {key: j for j, key in enumerate(keys)}
        self.growth_of = np.array(
            [key_index.get((s.beacon.id, frames[f].growth_group), -1) for f, s in sightings], int
        )  # (N,) D0's index, -1 for an outline fit's points
        self.fall_of = np.array([groups.index(frames[f].growth_group) for f, _ in sightings], int)  # (N,)
        measured: dict[tuple, list[float]] = {}
        for (_, s), j in zip(sightings, self.growth_of, strict=True):
            if j >= 0 and s.growth_px is not None:
                measured.setdefault(keys[j], []).append(s.growth_px)
        every = [g for values in measured.values() for g in values]
        fallback = float(np.median(every)) if every else HELD_GROWTH_PX
        self.growth_start_px = [float(np.median(measured[key])) if key in measured else fallback for key in keys]
        self.growth_base = self.frame_base + 6 * len(frames)
        self.fall_base = self.growth_base + len(keys)
        # the growth falls towards the image's corners, where the lens vignettes (less overexposure):
        # r is the panel's distance from the principal point in focal lengths
        centres = self.observed[:, 4]
        principal = np.array([[f.matrix[0, 2], f.matrix[1, 2]] for f in frames])[self.frame_of]
        focal = np.array([f.matrix[0, 0] for f in frames])[self.frame_of]
        self.radius2 = np.sum(((centres - principal) / focal[:, None]) ** 2, axis=1)
        self.model = np.array([_labelled(start, f, frames[f], s) for f, s in sightings])  # (N, 5, 3)
        self.matrix = np.array([frame.matrix for frame in frames])  # (F, 3, 3)
        with_gravity = [f for f, frame in enumerate(frames) if frame.gravity_camera is not None]
        self.gravity_frames = np.array(with_gravity, int)
        self.gravity_axes = np.array([orthonormal_pair(frames[f].gravity_camera) for f in with_gravity])  # type: ignore[arg-type]
        self.gravity_sigma = np.radians([frames[f].gravity_sigma_deg for f in with_gravity])

    def x0(self) -> np.ndarray:
        panels = [[*self.start.panels[k].center_m, math.radians(self.start.panels[k].yaw_deg)] for k in self.free]
        cameras = [[*Rotation.from_matrix(c.rotation_wc).as_rotvec(), *c.position_m] for c in self.start.cameras]
        return np.concatenate([np.ravel(panels), np.ravel(cameras), self.growth_start_px, np.zeros(self.groups)])

    def unpack(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(panel centres (P, 3), yaws (P,) rad by `self.free` order, rotations_wc (F, 3, 3), positions (F, 3));
        the growths (D0 per `growth_keys`, then D2 per group) are the last unknowns."""
        panels = x[: self.frame_base].reshape(-1, 4)
        cameras = x[self.frame_base : self.growth_base].reshape(-1, 6)
        return panels[:, :3], panels[:, 3], Rotation.from_rotvec(cameras[:, :3]).as_matrix(), cameras[:, 3:]

    def sighting_panels(self, centres: np.ndarray, yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) centres and (N,) yaws of every sighting's panel (the anchor's fixed)."""
        anchor = self.start.panels[self.anchor]
        all_centres = {k: centres[j] for j, k in enumerate(self.free)} | {self.anchor: anchor.center_m}
        all_yaws = {k: yaws[j] for j, k in enumerate(self.free)} | {self.anchor: math.radians(anchor.yaw_deg)}
        return np.array([all_centres[k] for k in self.panel_ids]), np.array([all_yaws[k] for k in self.panel_ids])

    def point_errors(self, x: np.ndarray) -> np.ndarray:
        """(N, 5, 2) projected minus observed, px."""
        centres, yaws, rotations, positions = self.unpack(x)
        c, y = self.sighting_panels(centres, yaws)
        f = self.frame_of
        projected = _project(self.model, c, y, rotations[f], positions[f], self.matrix[f])
        growth = x[self.growth_base + self.growth_of[self.grown]]
        growth = growth + x[self.fall_base + self.fall_of[self.grown]] * self.radius2[self.grown]
        projected[self.grown, :4] = grown_quads(projected[self.grown, :4], growth)
        return projected - self.observed

    def residuals(self, x: np.ndarray) -> np.ndarray:
        points = (self.point_errors(x) / self.sigma[:, :, None]).ravel()
        _, _, rotations, _ = self.unpack(x)
        if not len(self.gravity_frames):
            return points
        down = np.einsum("fji,j->fi", rotations[self.gravity_frames], DOWN)  # R_wc^T [0, 0, -1]
        across = np.einsum("fkj,fj->fk", self.gravity_axes, down) / self.gravity_sigma[:, None]
        return np.concatenate([points, across.ravel()])

    def sparsity(self) -> lil_matrix:
        n_points = 10 * len(self.frame_of)
        rows = n_points + 2 * len(self.gravity_frames)
        pattern = lil_matrix((rows, self.fall_base + self.groups), dtype=int)
        for k, (panel, frame) in enumerate(zip(self.panel_ids, self.frame_of, strict=True)):
            block = slice(10 * k, 10 * k + 10)
            if panel != self.anchor:
                pattern[block, self.column[panel] : self.column[panel] + 4] = 1
            start = self.frame_base + 6 * frame
            pattern[block, start : start + 6] = 1
            if self.grown[k]:  # the corners, not the centre
                pattern[10 * k : 10 * k + 8, self.growth_base + self.growth_of[k]] = 1
                pattern[10 * k : 10 * k + 8, self.fall_base + self.fall_of[k]] = 1
        for k, frame in enumerate(self.gravity_frames):
            start = self.frame_base + 6 * frame
            pattern[n_points + 2 * k : n_points + 2 * k + 2, start : start + 3] = 1
        return pattern


def _labelled(start: Start, index: int, frame: FrameSightings, sighting: Sighting) -> np.ndarray:
    """The model points in the labelling of the sighting's corners that the start projects nearest them."""
    camera, panel = start.cameras[index], start.panels[sighting.beacon.id]
    turns = round(360.0 / symmetry_deg(sighting.beacon))
    step = 4 // turns
    best = None
    for shift in range(0, 4, step):
        model = _model_points(sighting.beacon, shift)
        projected = _project(
            model[None],
            panel.center_m[None],
            np.radians([panel.yaw_deg]),
            camera.rotation_wc[None],
            camera.position_m[None],
            frame.matrix[None],
        )[0]
        error = float(np.sum((projected - sighting.points_px) ** 2))
        if best is None or error < best[0]:
            best = (error, model)
    assert best is not None
    return best[1]


def _project(
    model: np.ndarray,
    centres: np.ndarray,
    yaws: np.ndarray,
    rotations_wc: np.ndarray,
    positions: np.ndarray,
    matrices: np.ndarray,
) -> np.ndarray:
    """(N, 5, 2) ideal pixels of model points (N, 5, 3) of panels at `centres`, `yaws` (rad) seen by cameras."""
    cos, sin = np.cos(yaws), np.sin(yaws)
    x = model[..., 0] * cos[:, None] - model[..., 1] * sin[:, None]
    y = model[..., 0] * sin[:, None] + model[..., 1] * cos[:, None]
    world = np.stack([x, y, model[..., 2]], axis=-1) + centres[:, None, :]
    camera = np.einsum("nji,nkj->nki", rotations_wc, world - positions[:, None, :])  # R_wc^T (X - p)
    pixels = np.einsum("nij,nkj->nki", matrices, camera)
    depth = pixels[..., 2]
    # a point behind the camera (a far-off start only) gets a large residual instead of a flip
    depth = np.where(depth > 1e-6, depth, 1e-6)
    return pixels[..., :2] / depth[..., None]


def without_cameras_covariance(jacobian, cameras_at: int, cameras: int) -> np.ndarray:
    """(J^T J)^-1 of every unknown but the cameras' (in their order: the panels', then the growth's), by the
    Schur complement over the cameras' 6 x 6 blocks.

    A camera's six unknowns meet no other camera's in J^T J (each residual belongs to one frame), so its
    camera part is block diagonal: inverting it costs F small inverses, and the dense inverse is only of
    the panels' size, where the whole (J^T J)^-1 of hundreds of frames took seconds and gigabytes.
    `jacobian`: (residuals, unknowns), sparse or dense; the cameras' unknowns are columns
    [cameras_at, cameras_at + 6 cameras)."""
    jac = csr_matrix(jacobian)
    information = (jac.T @ jac).tocsr()
    camera_columns = np.arange(cameras_at, cameras_at + 6 * cameras)
    rest = np.setdiff1d(np.arange(information.shape[0]), camera_columns)
    cameras_part = information[camera_columns][:, camera_columns]
    blocks = [np.linalg.pinv(cameras_part[6 * f : 6 * f + 6, 6 * f : 6 * f + 6].toarray()) for f in range(cameras)]
    cross = information[rest][:, camera_columns]
    reduced = information[rest][:, rest].toarray() - (cross @ block_diag(blocks, format="csr") @ cross.T).toarray()
    return np.linalg.pinv(reduced)


def adjust(frames: list[FrameSightings], start: Start, anchor: int, rules: SurveyRules = SurveyRules()) -> Adjusted:
    """The joint fit from `start`; every panel's pose and 1-sigma, every camera, the RMS."""
    problem = _Problem(frames, start, anchor)
    fit = least_squares(
        problem.residuals,
        problem.x0(),
        jac_sparsity=problem.sparsity(),
        x_scale="jac",
        method="trf",
        max_nfev=rules.max_evaluations,
    )
    centres, yaws, rotations, positions = problem.unpack(fit.x)
    dof = max(1, len(fit.fun) - len(fit.x))
    variance = float(np.sum(fit.fun**2)) / dof
    covariance = without_cameras_covariance(fit.jac, problem.frame_base, len(frames)) * variance
    sigmas = np.sqrt(np.clip(np.diag(covariance), 0.0, None))  # the panels' first, by `problem.free` order
    errors = problem.point_errors(fit.x)
    per_point = np.sum(errors**2, axis=-1)  # (N, 5)
    counts = dict.fromkeys(start.panels, 0)
    for k in problem.panel_ids:
        counts[k] += 1
    panels = {
        anchor: PanelEstimate(start.panels[anchor], np.zeros(3), 0.0, counts[anchor]),
    }
    for j, k in enumerate(problem.free):
        yaw = math.degrees(yaws[j])
        panels[k] = PanelEstimate(
            PanelPose(centres[j], wrap_deg(yaw)),
            sigmas[4 * j : 4 * j + 3],
            math.degrees(sigmas[4 * j + 3]),
            counts[k],
        )
    rms_each = np.sqrt(per_point.mean(axis=1))
    chi_each = np.sqrt((per_point / problem.sigma**2).mean(axis=1))
    split = np.cumsum([len(f.sightings) for f in frames])[:-1]
    return Adjusted(
        panels=panels,
        cameras=tuple(CameraPose(p, r) for p, r in zip(positions, rotations, strict=True)),
        rms_px=float(np.sqrt(per_point.mean())),
        sighting_rms_px=tuple(tuple(map(float, part)) for part in np.split(rms_each, split)),
        sighting_chi=tuple(tuple(map(float, part)) for part in np.split(chi_each, split)),
    )
