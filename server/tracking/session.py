"""A device's session: one capture (a pose frame and the ID stripes read beside it) in, one result out.

For each panel of the pose frame, whole or cut by the frame border, the session:
1. locates the camera relative to the panel (`server.rooms.locate_panel` with a template
   beacon at the origin: every map beacon with the same shape, size and yaw gives the same
   pose, shifted; a cut panel's visible outline is fitted by the one-panel pipeline's
   outline path, `server.pose.outline`, as for a single frame, with the contour growth
   its whole panels showed);
2. attaches the stripes of the ID frames to the nearest panel and names it
   (`server.tracking.naming`: VLC evidence gathered across captures, or the track's hand-over);
3. chooses among the named panels and fuses agreeing ones (`server.rooms.choose_and_fuse`),
   then feeds the fix to the track (`server.tracking.track`), keeping the raw fix beside the
   filtered one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from server.geometry import (
    camera_matrix,
    distortion_vector,
    rotation_from_ypr,
    world_to_camera,
    wrap_deg,
    ypr_from_rotation,
)
from server.ingest import LumaFrame
from server.outcomes import Refusal, located, refused
from server.pipeline import PipelineOptions, locate_by_outlines
from server.pose.outline import tilt_from_gravity
from server.rooms import PanelFix, RoomRules, choose_and_fuse, locate_panel
from server.tracking.naming import NamingRules, PanelNamer
from server.tracking.track import Track, TrackRules
from server.vision.beacons import BeaconBlob, find_beacon_blobs
from server.vision.roi import FrameView
from server.vlc.decoder import StripeObservation
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, LocateResult


@dataclass(frozen=True)
class SessionRules:
    id_frame_gate_norm: float = 0.15  # ID-frame blob to pose-frame blob, in frame widths/heights
    growth_memory: int = 10  # whole panels whose contour growth is remembered, for cut ones
    name_gate: float = 0.5  # a cut blob's nearest predicted panel centre / the next nearest, to name it
    naming: NamingRules = NamingRules()
    track: TrackRules = TrackRules()


@dataclass(frozen=True)
class IdSighting:
    """The stripes of one panel in an ID frame, and where the panel was (fraction of the full frame)."""

    centroid_norm: tuple[float, float]
    observation: StripeObservation


@dataclass(frozen=True)
class WaitingIdFrame:
    """An ID frame's stripes waiting for the device's next pose frame (`server.tracking.devices`)."""

    t_s: float | None
    sightings: tuple[IdSighting, ...]

    @property
    def nbytes(self) -> int:
        """The memory its stripes hold (their arrays, plus a little for the objects around them)."""
        return sum(s.observation.nbytes + 256 for s in self.sightings) + 128


@dataclass
class SessionStats:
    captures: int = 0
    fixes: int = 0
    vlc_ids: int = 0
    carried_ids: int = 0
    outliers: int = 0
    conflicts: int = 0  # VLC said one beacon, the track another
    foreign_ids: int = 0  # readings of a code not in the map ("none of the map's" won): not used


# Panels whose yaws differ by this little still share the template: a surveyed map's yaws differ by
# hundredths of a degree (docs/survey.md). Each fix is turned by its own panel's yaw when the panel
# is named (`naming.PanelNamer.name`); the turn's error in the panels' matching (a degree over a
# metre: 17 mm) is far within their gates.
ALIKE_YAW_DEG = 1.0


def _geometry(beacon: Beacon) -> tuple:
    sizes = (*beacon.extent_m, beacon.outline_radius_m)
    return (beacon.shape, *(round(v, 6) for v in sizes))


def template_beacon(beacon_map: BeaconMap) -> Beacon | None:
    """A beacon at the origin standing for every map beacon, when they all look alike: the first
    beacon, its yaw within `ALIKE_YAW_DEG` of every other's."""
    first = beacon_map.beacons[0]
    if len({_geometry(b) for b in beacon_map.beacons}) != 1:
        return None
    if any(abs(wrap_deg(b.yaw_deg - first.yaw_deg)) > ALIKE_YAW_DEG for b in beacon_map.beacons):
        return None
    return first.model_copy(update={"center_m": [0.0, 0.0, 0.0]})


def attach_sightings(
    sightings: Sequence[IdSighting], blobs: Sequence[BeaconBlob], frame: LumaFrame, gate_norm: float
) -> dict[int, list[StripeObservation]]:
    """The stripes of each ID-frame panel, by the index of the nearest pose-frame blob within `gate_norm`."""
    stripes: dict[int, list[StripeObservation]] = {}
    if not blobs:
        return stripes
    centroids = np.array([frame.meta.fraction_of_full_frame(*b.centroid_px) for b in blobs])
    for sighting in sightings:
        gaps = np.hypot(*(centroids - np.asarray(sighting.centroid_norm)).T)
        nearest = int(np.argmin(gaps))
        if gaps[nearest] <= gate_norm:
            stripes.setdefault(nearest, []).append(sighting.observation)
    return stripes


@dataclass
class DeviceSession:
    beacon_map: BeaconMap
    rules: SessionRules = SessionRules()
    namer: PanelNamer = field(init=False)
    track: Track = field(init=False)
    captures: int = 0
    growths_px: list[float] = field(default_factory=list)
    last_rotation_wc: np.ndarray | None = None  # of the last fix: the yaw that cut panels start from

    def __post_init__(self) -> None:
        self.namer = PanelNamer(self.beacon_map, self.rules.naming)
        self.track = Track(self.rules.track)

    @property
    def stats(self) -> SessionStats:
        naming = self.namer.stats
        return SessionStats(
            captures=self.captures,
            fixes=self.track.fixes,
            vlc_ids=naming.vlc_ids,
            carried_ids=naming.carried_ids,
            outliers=self.track.outliers,
            conflicts=naming.conflicts,
            foreign_ids=naming.foreign_ids,
        )

    def locate(
        self,
        pose_frame: LumaFrame,
        sightings: Sequence[IdSighting] = (),
        options: PipelineOptions = PipelineOptions(),
        room: RoomRules = RoomRules(),
    ) -> LocateResult:
        """The fix of one capture, with its VLC reading and the filtered track."""
        self.captures += 1
        t_s = (pose_frame.meta.timestamp_ns or 0) * 1e-9
        claimed = self.namer.new_capture(t_s)
        candidates = find_beacon_blobs(pose_frame.pixels, room.candidates, FrameView.of(pose_frame.meta))
        blobs = list(candidates.blobs)
        template = template_beacon(self.beacon_map)
        stripes = attach_sightings(sightings, blobs, pose_frame, self.rules.id_frame_gate_norm)
        fixes: list[PanelFix] = []
        refusals: list[Refusal] = []
        for index, blob in enumerate(blobs):
            if template is None:
                continue
            others = [b for b in blobs if b is not blob]
            growth = float(np.median(self.growths_px)) if self.growths_px else None
            panel_options = replace(options, growth_px=growth) if blob.cut_off else options
            relative = locate_panel(
                pose_frame,
                blob,
                others,
                template,
                BeaconIdSource.vlc,
                panel_options,
                candidates.levels,
                room,
            )
            if isinstance(relative, Refusal):
                refusals.append(relative)
                continue
            if not blob.cut_off and relative.growth_px is not None:
                self.growths_px = (self.growths_px + [relative.growth_px])[-self.rules.growth_memory :]
            named = self.namer.name(blob, relative, stripes.get(index, []), t_s, self.track, claimed)
            if named is not None:
                fixes.append(named)
        best = choose_and_fuse(fixes, room)
        if best is None and any(b.cut_off for b in blobs):
            together = self._cut_panels_together(pose_frame, [b for b in blobs if b.cut_off], candidates, options, t_s)
            if isinstance(together, Refusal):
                refusals.insert(0, together)
            else:
                best = together
        notes = tuple(dict.fromkeys(self.namer.notes))  # stripes that read as no map beacon: said, never used
        if best is not None:
            self.last_rotation_wc = np.asarray(best.fix.rotation_wc)
            return self._tracked(replace(best, fix=best.fix.warned(*notes)), len(blobs), t_s)
        why = self._why_no_fix(blobs, refusals)
        why = replace(why, warnings=why.warnings + notes)
        return refused(why, beacons_in_view=len(blobs), track=self.track.coasting(t_s))

    def _cut_panels_together(
        self, frame: LumaFrame, cut: list[BeaconBlob], candidates, options: PipelineOptions, t_s: float
    ) -> PanelFix | Refusal | None:
        """One fix from the visible parts of all the cut panels the track expects, fitted together
        from the predicted pose (each alone may not pin the position down); None when untried."""
        predicted = self.track.predicted_m(t_s)
        gravity = frame.meta.gravity_camera
        if predicted is None or self.last_rotation_wc is None or gravity is None:
            return None
        yaw = ypr_from_rotation(self.last_rotation_wc)[0]
        attitude = rotation_from_ypr(yaw, *tilt_from_gravity(np.asarray(gravity)))
        beacons = list(self.beacon_map.beacons)
        centres = world_to_camera(np.array([b.center_m for b in beacons], float), predicted, attitude)
        matrix, distortion = camera_matrix(frame.camera), distortion_vector(frame.camera)
        projected, _ = cv2.projectPoints(centres, np.zeros(3), np.zeros(3), matrix, distortion)
        projected = projected.reshape(-1, 2)
        named: list[tuple[BeaconBlob, Beacon]] = []
        for blob in cut:
            gaps = np.linalg.norm(projected - np.asarray(blob.centroid_px), axis=1)
            order = np.argsort(gaps)
            # the nearest predicted panel names the blob when it is clearly nearer than the next one
            beacon = beacons[int(order[0])]
            clear = len(order) < 2 or gaps[order[0]] < self.rules.name_gate * gaps[order[1]]
            if clear and all(beacon.id != other.id for _, other in named):  # one blob per beacon: the largest
                named.append((blob, beacon))
        if not named:
            return Refusal(FailureReason.beacon_cut_off, "no cut panel where the track expects one")
        growth = float(np.median(self.growths_px)) if self.growths_px else None
        fix = locate_by_outlines(
            frame,
            [(beacon, blob.bounding_box) for blob, beacon in named],
            candidates.levels,
            replace(options, growth_px=growth),
            predicted,
            yaw,
        )
        if isinstance(fix, Refusal):
            return fix
        blob, beacon = next((b, p) for b, p in named if p.id == fix.beacon_id)
        return PanelFix(blob, beacon, fix, None)

    def _why_no_fix(self, blobs: list[BeaconBlob], refusals: list[Refusal]) -> Refusal:
        if refusals:
            return refusals[0]
        if blobs and all(b.cut_off for b in blobs):
            return Refusal(FailureReason.beacon_cut_off, "every panel in view touches the frame border")
        if blobs:
            return Refusal(FailureReason.unknown_beacon, "no panel in view has a beacon ID yet (VLC or track)")
        return Refusal(FailureReason.no_beacon, "no beacon-shaped blob in view")

    def _tracked(self, best: PanelFix, in_view: int, t_s: float) -> LocateResult:
        self.namer.count(best.fix.id_source)
        state = self.track.add(
            t_s, np.asarray(best.fix.position_m), best.fix.id_source is BeaconIdSource.track, best.fix.covariance_m2
        )
        return located(best.fix, vlc=best.vlc, beacons_in_view=in_view, track=state)
