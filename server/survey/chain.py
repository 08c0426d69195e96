"""Stage 2 of a survey: which panels the frames tie to the anchor, and a start for the fit.

Frames and panels form a graph (a frame that sees panels A and B joins them). From the anchor,
whose sketch centre and yaw are taken as true, each frame that sees a placed panel is posed
from that panel's single-panel fix (the camera in the panel's frame), and each panel it sees
that is not placed yet is placed from its own fix on the same frame: B relative to A, through
the camera. A panel the graph does not reach is refused, naming it and the frames that would
reach it.

A square looks the same after a quarter turn (a rectangle after a half turn), so the camera's
pose in a panel's frame is known only up to that turn. Of those turns the one is taken that puts
the frame's other panels nearest where they are placed already, else nearest their sketch
positions: the sketch must place each panel nearer its true place than to where a quarter turn
about a neighbour would put it (within about a third of the panels' spacing). A placed panel's
yaw is the one of its equivalent yaws nearest the sketch's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from server.geometry import rotation_z, wrap_deg, ypr_from_rotation
from server.survey.rules import SurveyRefused
from server.survey.sightings import FrameSightings, Sighting
from shared_schemas import Beacon, BeaconMap


@dataclass(frozen=True)
class PanelPose:
    center_m: np.ndarray  # (3,)
    yaw_deg: float


@dataclass(frozen=True)
class CameraPose:
    position_m: np.ndarray  # (3,) optical centre
    rotation_wc: np.ndarray  # (3, 3)


@dataclass(frozen=True)
class Start:
    panels: dict[int, PanelPose]
    cameras: tuple[CameraPose, ...]  # one per frame, in the frames' order


def symmetry_deg(beacon: Beacon) -> float:
    """The turn that leaves the panel's outline unchanged: 90 for a square, 180 for a rectangle."""
    width, height = beacon.extent_m
    return 90.0 if math.isclose(width, height) else 180.0


def nearest_equivalent_deg(yaw_deg: float, reference_deg: float, step_deg: float) -> float:
    """`yaw_deg` plus the multiple of `step_deg` that brings it nearest `reference_deg`, in (-180, 180]."""
    turns = round((reference_deg - yaw_deg) / step_deg)
    return wrap_deg(yaw_deg + turns * step_deg)


def _centre_in_camera(sighting: Sighting) -> np.ndarray:
    """The panel's centre in the camera frame, from the camera's pose in the panel's frame."""
    return -sighting.rotation_bc.T @ sighting.position_b


def _pose_frame(frame: FrameSightings, placed: dict[int, PanelPose], sketch: BeaconMap) -> CameraPose:
    """The frame's camera from its best-measured placed panel, turned by the panel's symmetry so that
    its other panels fall nearest where they are placed (or sketched)."""
    known = [s for s in frame.sightings if s.beacon.id in placed]
    base = max(known, key=lambda s: (not s.cut, s.area_px))
    panel = placed[base.beacon.id]
    rotation_wb = rotation_z(panel.yaw_deg)
    step = symmetry_deg(base.beacon)
    best: tuple[float, CameraPose] | None = None
    for k in range(round(360.0 / step)):
        turn = rotation_z(k * step)
        camera = CameraPose(
            panel.center_m + rotation_wb @ turn @ base.position_b, rotation_wb @ turn @ base.rotation_bc
        )
        score = 0.0
        for other in frame.sightings:
            if other is base:
                continue
            where = camera.position_m + camera.rotation_wc @ _centre_in_camera(other)
            target = placed[other.beacon.id].center_m if other.beacon.id in placed else other.beacon.center_m
            score += float(np.sum((where - np.asarray(target)) ** 2))
        if best is None or score < best[0]:
            best = (score, camera)
    assert best is not None
    return best[1]


def _place(sighting: Sighting, camera: CameraPose) -> PanelPose:
    center = camera.position_m + camera.rotation_wc @ _centre_in_camera(sighting)
    yaw = ypr_from_rotation(camera.rotation_wc @ sighting.rotation_bc.T)[0]
    return PanelPose(center, nearest_equivalent_deg(yaw, sighting.beacon.yaw_deg, symmetry_deg(sighting.beacon)))


def _unconnected_message(
    beacon: Beacon, anchor: int, frames: list[FrameSightings], placed: dict[int, PanelPose], sketch: BeaconMap
) -> str:
    seeing = [f for f in frames if any(s.beacon.id == beacon.id for s in f.sightings)]
    connected = sorted(placed)
    nearest = min(
        (b for b in sketch.beacons if b.id in placed),
        key=lambda b: float(np.linalg.norm(np.subtract(b.center_m, beacon.center_m))),
    )
    if seeing:
        names = ", ".join(f"'{f.name}'" for f in seeing[:5]) + (" ..." if len(seeing) > 5 else "")
        with_ids = sorted({s.beacon.id for f in seeing for s in f.sightings} - {beacon.id})
        what = f"frames {names} see it only with beacons {with_ids}, which are not connected to the anchor either"
    else:
        what = "no frame used sees it (with another named panel)"
    return (
        f"beacon {beacon.id} is not connected to anchor {anchor}: {what}; add frames that see beacon {beacon.id} "
        f"together with one of the connected beacons {connected} (nearest in the sketch: {nearest.id})"
    )


def chain_start(frames: list[FrameSightings], sketch: BeaconMap, anchor: int) -> Start:
    """Every panel placed and every frame posed by chaining from the anchor; refuses a panel it cannot reach."""
    anchor_beacon = sketch.beacon(anchor)
    assert anchor_beacon is not None  # checked by the caller
    placed = {anchor: PanelPose(np.asarray(anchor_beacon.center_m, float), anchor_beacon.yaw_deg)}
    cameras: list[CameraPose | None] = [None] * len(frames)
    progress = True
    while progress:
        progress = False
        for k, frame in enumerate(frames):
            if cameras[k] is not None or not any(s.beacon.id in placed for s in frame.sightings):
                continue
            camera = _pose_frame(frame, placed, sketch)
            cameras[k] = camera
            for sighting in frame.sightings:
                if sighting.beacon.id not in placed:
                    placed[sighting.beacon.id] = _place(sighting, camera)
            progress = True
    for beacon in sketch.beacons:
        if beacon.id not in placed:
            raise SurveyRefused(_unconnected_message(beacon, anchor, frames, placed, sketch), beacon.id)
    # every frame sees a placed panel now: all panels are placed, and each frame has one
    return Start(placed, tuple(c for c in cameras if c is not None))
