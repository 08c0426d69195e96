"""A device's session: one capture (a pose frame and the ID stripes read beside it) in, one result out.

For each complete panel of the pose frame the session:
1. locates the camera relative to the panel (`server.rooms.locate_panel` with a template
   beacon at the origin: every map beacon with the same side, corner radius and yaw gives
   the same pose, shifted);
2. attaches the stripes of the ID frames to the nearest panel and names it
   (`server.tracking.naming`: VLC evidence gathered across captures, or the track's hand-over);
3. chooses among the named panels and fuses agreeing ones (`server.rooms.choose_and_fuse`),
   then feeds the fix to the track (`server.tracking.track`), keeping the raw fix beside the
   filtered one;
4. with no complete panel, fits the visible edges of cut-off panels (`server.pose.cut_off`),
   using the contour growth measured on earlier complete panels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from server.geometry import ypr_from_rotation
from server.ingest import LumaFrame
from server.outcomes import Refusal, located, refused
from server.pipeline import PipelineOptions
from server.pose.cut_off import CutOffRules, fit_cut_off_panel, fit_expected_panels
from server.pose.partial import edge_points, measure_growth
from server.rooms import PanelFix, RoomRules, choose_and_fuse, locate_panel
from server.tracking.naming import NamingRules, PanelNamer
from server.tracking.track import Track, TrackRules
from server.vision.beacons import BeaconBlob, find_beacon_blobs
from server.vlc.decoder import StripeObservation
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, LocateResult


@dataclass(frozen=True)
class SessionRules:
    id_frame_gate_norm: float = 0.15  # ID-frame blob to pose-frame blob, in frame widths/heights
    growth_memory: int = 10  # complete panels whose contour growth is remembered
    naming: NamingRules = NamingRules()
    track: TrackRules = TrackRules()
    cut_off: CutOffRules = CutOffRules()


@dataclass(frozen=True)
class IdSighting:
    """The stripes of one panel in an ID frame, and where the panel was (fraction of the full frame)."""

    centroid_norm: tuple[float, float]
    observation: StripeObservation


@dataclass
class SessionStats:
    captures: int = 0
    fixes: int = 0
    vlc_ids: int = 0
    carried_ids: int = 0
    outliers: int = 0
    conflicts: int = 0  # VLC said one beacon, the track another
    foreign_ids: int = 0  # confident codes of beacons not in the map


def _geometry(beacon: Beacon) -> tuple:
    sizes = (*beacon.extent_m, beacon.outline_radius_m, beacon.yaw_deg % 360.0)
    return (beacon.shape, *(round(v, 6) for v in sizes))


def template_beacon(beacon_map: BeaconMap) -> Beacon | None:
    """A beacon at the origin standing for every map beacon, when they all look alike."""
    if len({_geometry(b) for b in beacon_map.beacons}) != 1:
        return None
    return beacon_map.beacons[0].model_copy(update={"center_m": [0.0, 0.0, 0.0]})


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
    last_rotation_wc: np.ndarray | None = None

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
        candidates = find_beacon_blobs(pose_frame.pixels, room.candidates)
        blobs = list(candidates.blobs)
        template = template_beacon(self.beacon_map)
        stripes = attach_sightings(sightings, blobs, pose_frame, self.rules.id_frame_gate_norm)
        fixes: list[PanelFix] = []
        refusals: list[Refusal] = []
        for index, blob in enumerate(blobs):
            if blob.cut_off or template is None:
                continue
            others = [b for b in blobs if b is not blob]
            relative = locate_panel(
                pose_frame, blob, others, template, BeaconIdSource.vlc, options, candidates.levels.background, room
            )
            if isinstance(relative, Refusal):
                refusals.append(relative)
                continue
            named = self.namer.name(blob, relative, stripes.get(index, []), t_s, self.track, claimed)
            if named is not None:
                fixes.append(named)
        best = choose_and_fuse(fixes, room)
        level = candidates.levels.threshold
        if best is not None:
            self._measure_growth(pose_frame, best, level)
            return self._tracked(best, len(blobs), t_s)
        partial = self._expected_panels(pose_frame, blobs, level, t_s)
        if not isinstance(partial, PanelFix) and template is not None:
            alone = self._cut_off_panels(pose_frame, blobs, stripes, level, t_s, claimed, template, room)
            partial = alone if alone is not None else partial
        if isinstance(partial, PanelFix):
            return self._tracked(partial, len(blobs), t_s)
        if partial is not None:
            refusals.insert(0, partial)
        return refused(self._why_no_fix(blobs, refusals), beacons_in_view=len(blobs), track=self.track.coasting(t_s))

    def _expected_panels(
        self, frame: LumaFrame, blobs: list[BeaconBlob], level: float, t_s: float
    ) -> PanelFix | Refusal | None:
        """A fix from the visible parts of panels named by the track; None when not even tried."""
        predicted = self.track.predicted_m(t_s)
        if not blobs or predicted is None or not self.growths_px or self.last_rotation_wc is None:
            return None
        yaw = ypr_from_rotation(self.last_rotation_wc)[0]
        found = fit_expected_panels(
            frame,
            blobs,
            list(self.beacon_map.beacons),
            predicted,
            yaw,
            float(np.median(self.growths_px)),
            level,
            self.rules.cut_off,
        )
        if isinstance(found, Refusal):
            return found
        blob, beacon, fix = found
        return PanelFix(blob, beacon, fix, None)

    def _cut_off_panels(
        self,
        frame: LumaFrame,
        blobs: list[BeaconBlob],
        stripes,
        level: float,
        t_s: float,
        claimed: set[int],
        template: Beacon,
        room: RoomRules,
    ) -> PanelFix | None:
        """Each cut-off panel located alone relative to the template, then named like a complete panel."""
        yaw = ypr_from_rotation(self.last_rotation_wc)[0] if self.last_rotation_wc is not None else template.yaw_deg
        growth = float(np.median(self.growths_px)) if self.growths_px else None
        fixes = []
        for index, blob in enumerate(blobs):
            if not blob.cut_off:
                continue
            relative = fit_cut_off_panel(frame, blob, template, yaw, growth, level, self.rules.cut_off)
            if relative is None:
                continue
            named = self.namer.name(blob, relative, stripes.get(index, []), t_s, self.track, claimed)
            if named is not None:
                fixes.append(named)
        return choose_and_fuse(fixes, room)

    def _measure_growth(self, frame: LumaFrame, best: PanelFix, level: float) -> None:
        """The clipped panel's contour growth, from a complete panel whose pose is now known."""
        points = edge_points(frame.pixels, best.blob.bounding_box, level, self.rules.cut_off.partial)
        growth = measure_growth(best.beacon, points, best.fix.position_m, best.fix.rotation_wc, frame.camera)
        if growth is not None:
            self.growths_px = (self.growths_px + [growth])[-self.rules.growth_memory :]
        self.last_rotation_wc = np.asarray(best.fix.rotation_wc)

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
        state = self.track.add(t_s, np.asarray(best.fix.position_m), best.fix.id_source is BeaconIdSource.track)
        return located(best.fix, vlc=best.vlc, beacons_in_view=in_view, track=state)
