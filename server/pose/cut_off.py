"""Fixes from panels cut by the frame border, for a device's session (`server.tracking.session`).

Two starts for `server.pose.partial.fit_partial`, which fits the visible outline:
- `fit_expected_panels`: the blobs where an established track expects map beacons, named by
  the nearest predicted panel centre, fitted together from the predicted position;
- `fit_cut_off_panel`: one cut-off blob alone, relative to a template beacon at the origin,
  from the distance its size suggests (how a walk that starts between panels starts); the
  session names it afterwards like a complete panel.
Both take pitch and roll from gravity and yaw from the session's last complete fix.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.geometry import camera_matrix, distortion_vector, rotation_from_ypr
from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal
from server.pose.partial import PartialRules, edge_points, fit_partial, tilt_from_gravity
from server.vision.beacons import BeaconBlob
from shared_schemas import Beacon, BeaconIdSource, CameraIntrinsics, FailureReason


@dataclass(frozen=True)
class CutOffRules:
    partial: PartialRules = PartialRules()
    name_gate: float = 0.5  # nearest predicted panel centre / next nearest, at a blob's centroid


def _attitude(gravity_camera, yaw_deg: float) -> np.ndarray:
    pitch, roll = tilt_from_gravity(np.asarray(gravity_camera))
    return rotation_from_ypr(yaw_deg, pitch, roll)


def _ray(camera: CameraIntrinsics, rotation_wc: np.ndarray, pixel: tuple[float, float]) -> np.ndarray:
    """The viewing ray through `pixel` (pinhole, no distortion: only a start), in the map frame."""
    return rotation_wc @ np.array([(pixel[0] - camera.cx) / camera.fx, (pixel[1] - camera.cy) / camera.fy, 1.0])


def fit_expected_panels(
    frame: LumaFrame,
    blobs: list[BeaconBlob],
    beacons: list[Beacon],
    predicted_m: np.ndarray,
    yaw_deg: float,
    growth_px: float,
    level: float,
    rules: CutOffRules = CutOffRules(),
) -> tuple[BeaconBlob, Beacon, Fix] | Refusal:
    """A fix from the visible parts of the map panels the track predicts in view at `predicted_m`,
    with the first blob it named and that blob's beacon."""
    gravity = frame.meta.gravity_camera
    if gravity is None:
        return Refusal(FailureReason.beacon_cut_off, "cut-off panels need the gravity vector")
    rotation = _attitude(gravity, yaw_deg)
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    centres = np.array([b.center_m for b in beacons], float)
    projected, _ = cv2.projectPoints((centres - predicted_m) @ rotation, np.zeros(3), np.zeros(3), matrix, distortion)
    projected = projected.reshape(-1, 2)
    panels, named = [], []
    for blob in blobs:
        gaps = np.linalg.norm(projected - blob.centroid_px, axis=1)
        order = np.argsort(gaps)
        # the nearest predicted panel names the blob when it is clearly nearer than the next one
        if len(order) > 1 and gaps[order[0]] > rules.name_gate * gaps[order[1]]:
            continue
        beacon = beacons[int(order[0])]
        panels.append((beacon, edge_points(frame.pixels, blob.bounding_box, level, rules.partial)))
        named.append((blob, beacon))
    if not panels:
        return Refusal(FailureReason.beacon_cut_off, "no panel in view where the track expects one")
    # start where the largest named blob's centroid ray meets its panel at the predicted height
    blob, beacon = max(named, key=lambda item: item[0].area_px)
    ray = _ray(frame.camera, rotation, blob.centroid_px)
    start_m = np.asarray(beacon.center_m) - ray * (beacon.center_m[2] - predicted_m[2]) / ray[2]
    fit = fit_partial(panels, frame.camera, gravity, start_m, yaw_deg, growth_px, rules.partial)
    if isinstance(fit, Refusal):
        return fit
    blob, beacon = named[0]
    centre, _ = cv2.projectPoints(
        (np.array([beacon.center_m]) - fit.position_m) @ fit.rotation_wc, np.zeros(3), np.zeros(3), matrix, distortion
    )
    return (
        blob,
        beacon,
        Fix(
            position_m=fit.position_m,
            rotation_wc=fit.rotation_wc,
            beacon_id=beacon.id,
            id_source=BeaconIdSource.track,
            reprojection_error_px=fit.rms_px,
            gravity_used=True,
            center_px=centre.reshape(2),
            warnings=(
                f"pose from the visible edges of cut-off panels {[b.id for _, b in named]} "
                f"({fit.points} points, sigma {fit.sigma_m * 1000:.1f} mm)",
            ),
        ),
    )


def fit_cut_off_panel(
    frame: LumaFrame,
    blob: BeaconBlob,
    template: Beacon,
    yaw_deg: float,
    growth_px: float | None,
    level: float,
    rules: CutOffRules = CutOffRules(),
) -> Fix | None:
    """The camera relative to the template beacon from one cut-off blob (its growth fitted when
    `growth_px` is None); None without gravity or when the fit fails."""
    gravity = frame.meta.gravity_camera
    if gravity is None:
        return None
    rotation = _attitude(gravity, yaw_deg)
    points = edge_points(frame.pixels, blob.bounding_box, level, rules.partial)
    distance_m = frame.camera.fx * template.size_m / max(blob.bounding_box[2], blob.bounding_box[3], 1)
    ray = _ray(frame.camera, rotation, blob.centroid_px)
    start_m = -ray * distance_m / ray[2]
    fit = fit_partial([(template, points)], frame.camera, gravity, start_m, yaw_deg, growth_px, rules.partial)
    if isinstance(fit, Refusal):
        return None
    return Fix(
        position_m=fit.position_m,
        rotation_wc=fit.rotation_wc,
        beacon_id=None,
        id_source=None,
        reprojection_error_px=fit.rms_px,
        gravity_used=True,
        center_px=np.asarray(blob.centroid_px, float),
        warnings=(
            f"pose from the visible edges of a cut-off panel ({fit.points} points, "
            f"sigma {fit.sigma_m * 1000:.1f} mm, growth {fit.growth_px:.2f} px)",
        ),
    )
