"""Stage 1 of a survey: every named panel of one frame and its image points.

A panel is named by its own stripes on an ID frame (`server.rooms.read_room`, which also
measures it on the frame with its stripes flattened), else by a `PanelLabel`, a pixel inside its
image, on the beacon-shaped blobs of `server.vlc.capture.frame_blobs`. Each named panel
is measured by the one-panel pipeline on its own crop (`server.rooms.locate_panel`):

- a square wholly in view takes the corner path; its points are the sub-pixel corners where the
  sides cross at the mid level (the pipeline's own estimate of the clipped-edge growth put back:
  the fit measures each panel's growth over all its frames instead, `server.survey.adjust`) and the
  intersection of the corrected corners' diagonals. The sides are measured to about 0.02 px,
  independently of the pose, and the corners of a 0.17 m panel 1.4 m away span about 230 px at
  half the Mi 8's resolution: the panel's size, which is what sets the map's scale, is then known
  to about 0.01 %, and its place across the view to hundredths of a millimetre.
- a panel cut by the frame border (or one the corner path hands over) takes the outline path;
  its corners are not seen, so its points are the outline fit's pose projected back (the
  pipeline's reported corners), weighed far lower (`SurveyRules.outline_sigma_px`).

The points are returned in ideal (undistorted) pixels, in the model's corner order for the
sketch's yaw; which of a square's four labellings is right is settled later against the fitted
yaw (`server.survey.chain`). The relative pose of the camera in the panel's own frame (from the
same fix) seeds the fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.camera import ProfileTable
from server.geometry import beacon_rotation, camera_matrix, distortion_vector, grown_quads
from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal
from server.rooms import locate_panel, read_room
from server.survey.rules import SurveyInputError, SurveyRules
from server.vision.beacons import BeaconBlob
from server.vlc.capture import frame_blobs
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FrameKind, ProfileRef, device_profiles
from shared_schemas.survey import PanelLabel, SkippedFrame


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class Sighting:
    """One named panel on one frame."""

    beacon: Beacon  # the sketch's
    # (5, 2) the frame's ideal pixels: the four corners in model order for the sketch's yaw, the centre;
    # a whole panel's corners at the mid level (`grown`), an outline fit's on the panel's outline
    points_px: np.ndarray
    sigmas_px: np.ndarray  # (5,) of each point
    cut: bool  # from the outline path (cut by the border, or handed over)
    grown: bool  # the corners lie outside the panel's outline by the panel's clipped-edge growth (`adjust`)
    position_b: np.ndarray  # (3,) the camera's optical centre in the panel's frame
    rotation_bc: np.ndarray  # (3, 3) camera to panel frame
    area_px: float
    growth_px: float | None  # the clipped-edge growth the pipeline took off the sides (px), if it measured one


@dataclass(frozen=True, eq=False)
class FrameSightings:
    name: str
    matrix: np.ndarray  # (3, 3) the camera matrix of the frame's own pixels (ideal: distortion undone)
    gravity_camera: np.ndarray | None  # (3,) unit, down
    gravity_sigma_deg: float
    compass_bearing_deg: float | None
    sightings: tuple[Sighting, ...]
    notes: tuple[str, ...]  # panels in view that were not used, and why
    # frames that share it share the clipped-edge growth of a panel (px: it scales with the resolution and
    # the overexposure): the full frame's size, exposure, ISO and tone curve
    growth_group: tuple = ()


def check_labels(labels: list[PanelLabel], sketch: BeaconMap, name: str, field: str = "labels") -> None:
    """Labels must name sketch panels, each once per frame; `field` names the labels in the request."""
    ids = {b.id for b in sketch.beacons}
    seen: set[int] = set()
    for k, label in enumerate(labels):
        if label.beacon_id not in ids:
            raise SurveyInputError(
                f"frame '{name}': label {k} names beacon {label.beacon_id}, which is not in sketch '{sketch.name}' "
                f"(its beacons: {sorted(ids)})",
                field=f"{field}.{k}.beacon_id",
            )
        if label.beacon_id in seen:
            raise SurveyInputError(f"frame '{name}': beacon {label.beacon_id} is labelled twice", f"{field}.{k}")
        seen.add(label.beacon_id)


def _gravity_sigma_deg(frame: LumaFrame, profiles: ProfileTable, rules: SurveyRules) -> float:
    """The frame's profile's gravity sigma; `profiles` is the table the frame was decoded with (a stored,
    calibrated profile is in it, not among the bundled ones), else the rules' sigma."""
    camera = frame.meta.camera
    profile = profiles.get(camera.profile) if isinstance(camera, ProfileRef) else None
    return rules.gravity_sigma_deg if profile is None else profile.gravity_sigma_deg


def _labelled(frame: LumaFrame, blobs: tuple[BeaconBlob, ...], labels: list[PanelLabel], sketch: BeaconMap):
    """(blob, beacon) of each label's panel, and notes on labels that hit no panel or a taken one."""
    column, row = frame.meta.full_offset
    named: dict[int, tuple[BeaconBlob, Beacon]] = {}
    notes: list[str] = []
    for label in labels:
        x, y = label.x_px - column, label.y_px - row
        hit = [
            b
            for b in blobs
            if cv2.pointPolygonTest(b.contour_px.astype(np.float32).reshape(-1, 1, 2), (float(x), float(y)), True)
            >= -2.0
        ]
        beacon = sketch.beacon(label.beacon_id)
        assert beacon is not None  # check_labels
        if not hit:
            notes.append(
                f"the label of beacon {label.beacon_id} at ({label.x_px:.0f}, {label.y_px:.0f}) px is on no panel"
            )
            continue
        blob = min(hit, key=lambda b: float(np.hypot(b.centroid_px[0] - x, b.centroid_px[1] - y)))
        taken = [k for k, (other, _) in named.items() if other is blob]
        if taken:
            notes.append(f"the labels of beacons {taken[0]} and {label.beacon_id} are on the same panel: both left out")
            del named[taken[0]]
            continue
        named[label.beacon_id] = (blob, beacon)
    return list(named.values()), notes


def _sighting(frame: LumaFrame, fix: Fix, beacon: Beacon, blob: BeaconBlob, rules: SurveyRules) -> Sighting | str:
    if fix.corners_px is None or fix.center_px is None:
        return f"beacon {beacon.id} gave no corners (a circle cannot be surveyed)"
    matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
    points = np.vstack([fix.corners_px, fix.center_px]).astype(float)
    if distortion is not None:
        points = cv2.undistortPoints(points.reshape(-1, 1, 2), matrix, distortion, P=matrix).reshape(-1, 2)
    rotation_wb = beacon_rotation(beacon)
    position_b = rotation_wb.T @ (np.asarray(fix.position_m) - np.asarray(beacon.center_m))
    if fix.from_outline:
        sigmas = np.full(5, rules.outline_sigma_px)
    else:
        sigmas = np.array([*[rules.corner_sigma_px] * 4, rules.centre_sigma_px])
        if fix.growth_px is not None:  # the sides back where the pipeline measured them
            points[:4] = grown_quads(points[:4], fix.growth_px)
        # sides blurred unevenly were each moved in by their own growth, and one common growth put back
        # leaves the corners (and the diagonals' crossing) off by up to `uneven_px`: weighed by it
        sigmas = np.hypot(sigmas, fix.uneven_px)
    return Sighting(
        beacon=beacon,
        points_px=points,
        sigmas_px=sigmas,
        cut=fix.from_outline,
        grown=not fix.from_outline,
        position_b=position_b,
        rotation_bc=rotation_wb.T @ np.asarray(fix.rotation_wc),
        area_px=blob.area_px,
        growth_px=fix.growth_px,
    )


def frame_sightings(
    frame: LumaFrame,
    name: str,
    labels: list[PanelLabel],
    sketch: BeaconMap,
    rules: SurveyRules = SurveyRules(),
    profiles: ProfileTable | None = None,
) -> FrameSightings | SkippedFrame:
    """The named, measured panels of `frame` (at least two), or why the frame is skipped; `profiles`: the
    table the frame was decoded with (default: the bundled profiles)."""
    check_labels(labels, sketch, name)
    notes: list[str] = []
    measured: list[tuple[BeaconBlob, Beacon, Fix | Refusal]] = []
    found = frame_blobs(frame, rules.room.candidates.for_beacons(sketch.beacons), rules.room.stripes)
    blobs = found.blobs
    if frame.meta.frame_kind is FrameKind.id:
        # the same blobs as the survey's own: a labelled panel's blob is then left out of its `others`
        room = read_room(frame, sketch, rules.pipeline, rules.room, found)
        if room.problem is not None:  # no panel named: the labels name any of the found blobs
            notes.append(f"its stripes cannot name panels ({room.problem})")
        notes += [p.note for p in room.panels if p.note is not None]
        measured += [(p.blob, p.beacon, p.fix) for p in room.panels if p.beacon is not None and p.fix is not None]
        striped = {b.id for _, b, _ in measured}
        # a label names only a panel its stripes did not; such a panel is measured on its striped pixels
        # (not flattened without its code), which the pipeline often refuses: label pose frames instead
        labels = [label for label in labels if label.beacon_id not in striped]
        if room.problem is None:
            blobs = tuple(p.blob for p in room.panels if p.beacon is None)
    if labels:
        named, label_notes = _labelled(frame, blobs, labels, sketch)
        notes += label_notes
        for blob, beacon in named:
            others = [b for b in found.blobs if b is not blob]
            # (the fix's ID source is not reported: a survey says how it named each frame's panels)
            source = BeaconIdSource.single_beacon_map
            fix = locate_panel(frame, blob, others, beacon, source, rules.pipeline, found.levels, rules.room)
            measured.append((blob, beacon, fix))
    sightings: list[Sighting] = []
    for blob, beacon, fix in measured:
        if isinstance(fix, Refusal):
            notes.append(f"beacon {beacon.id} was not measured: {fix.message}")
            continue
        sighting = _sighting(frame, fix, beacon, blob, rules)
        if isinstance(sighting, str):
            notes.append(sighting)
        else:
            sightings.append(sighting)
    if len(sightings) < 2:
        ids = [s.beacon.id for s in sightings]
        what = "no named panel" if not ids else f"only beacon {ids[0]} named and measured"
        why = f"{what} of {len(found.blobs)} in view; a survey frame must see two or more"
        return SkippedFrame(name=name, why="; ".join([why, *notes]))
    meta = frame.meta
    gravity = None if meta.gravity_camera is None else np.asarray(meta.gravity_camera, float)
    return FrameSightings(
        name=name,
        matrix=camera_matrix(frame.camera),
        gravity_camera=None if gravity is None else gravity / np.linalg.norm(gravity),
        gravity_sigma_deg=_gravity_sigma_deg(frame, device_profiles() if profiles is None else profiles, rules),
        compass_bearing_deg=meta.compass_bearing_deg,
        sightings=tuple(sightings),
        notes=tuple(notes),
        growth_group=(*meta.full_size, meta.exposure_s, meta.iso, meta.tone_curve),
    )
