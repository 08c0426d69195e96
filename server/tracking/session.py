"""A device's session: its panels in view, their ID evidence, and its motion-filtered track.

One capture = one pose frame and the ID frames taken beside it (docs/vlc.md). For each
complete panel of the pose frame the session:
1. locates the camera relative to the panel (a template beacon at the origin: every map
   beacon with the same side, corner radius and yaw gives the same pose, shifted);
2. follows the panel from capture to capture by that relative position (it changes only by
   the walked distance, while neighbouring panels are a beacon spacing apart), so ID frames
   of the same panel keep adding evidence to one `IdEvidence` (candidates: the map's IDs);
3. names the panel: a confident VLC decision wins; without one, the map beacon whose
   position best matches the track's prediction carries the ID over (`BeaconIdSource.track`),
   when it is unambiguous;
4. chooses among the named panels and fuses agreeing ones (`server.rooms`), then feeds the
   fix to the constant-velocity filter, keeping the raw fix beside the filtered one.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from server.ingest import LumaFrame
from server.pipeline import PipelineOptions
from server.rooms import PanelFix, RoomRules, choose_and_fuse, locate_panel, vlc_reading
from server.tracking.filter import FilterRules, FilterState, predict, start, update
from server.vision.beacons import find_beacon_blobs
from server.vlc.decoder import IdEvidence
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, LocateResult, TrackState


@dataclass(frozen=True)
class SessionRules:
    id_frame_gate_norm: float = 0.15  # ID-frame blob to pose-frame blob, in frame widths/heights
    panel_gate_m: float = 0.45  # relative-position jump allowed between captures of one panel
    carry_gate_m: float = 0.30  # track prediction to the carried beacon's hypothesis
    carry_ratio: float = 2.5  # the next hypothesis must be this much farther
    panel_timeout_s: float = 3.0
    evidence_frames: int = 16
    room: RoomRules = RoomRules()
    motion: FilterRules = FilterRules()


@dataclass
class PanelTrack:
    """One physical panel followed across captures."""

    relative_m: np.ndarray  # camera position minus panel centre at the last sighting
    t_s: float
    evidence: IdEvidence
    beacon_id: int | None = None  # confidently decoded ID, kept once known


@dataclass
class SessionStats:
    captures: int = 0
    fixes: int = 0
    vlc_ids: int = 0
    carried_ids: int = 0
    outliers: int = 0
    conflicts: int = 0  # VLC said one beacon, the track another


def _geometry(beacon: Beacon) -> tuple[float, float, float]:
    return (round(beacon.side_m, 6), round(beacon.corner_radius_m, 6), round(beacon.yaw_deg % 360.0, 6))


@dataclass
class DeviceSession:
    beacon_map: BeaconMap
    options: PipelineOptions = PipelineOptions()
    rules: SessionRules = SessionRules()
    panels: list[PanelTrack] = field(default_factory=list)
    track: FilterState | None = None
    stats: SessionStats = field(default_factory=SessionStats)
    last_seen_s: float = field(default_factory=time.monotonic)

    def _template(self) -> Beacon | None:
        """A beacon at the origin standing for every map beacon, when they all look alike."""
        shapes = {_geometry(b) for b in self.beacon_map.beacons}
        if len(shapes) != 1:
            return None
        first = self.beacon_map.beacons[0]
        return first.model_copy(update={"center_m": [0.0, 0.0, 0.0]})

    def _panel_for(self, relative_m: np.ndarray, t_s: float, claimed: set[int]) -> PanelTrack:
        shift = np.zeros(3)
        if self.track is not None:
            shift = self.track.velocity_mps * max(0.0, t_s - self.track.t_s)
        best, best_distance = None, self.rules.panel_gate_m
        for index, panel in enumerate(self.panels):
            if index in claimed:
                continue
            # the camera moved by `shift`; relative to a fixed panel so did the relative position
            distance = float(np.linalg.norm(relative_m - (panel.relative_m + shift)))
            if distance < best_distance:
                best, best_distance = index, distance
        if best is None:
            evidence = IdEvidence(candidates=tuple(sorted(b.id for b in self.beacon_map.beacons)),
                                  rules=self.rules.room.stripes, max_frames=self.rules.evidence_frames)
            self.panels.append(PanelTrack(relative_m, t_s, evidence))
            best = len(self.panels) - 1
        claimed.add(best)
        panel = self.panels[best]
        panel.relative_m, panel.t_s = relative_m, t_s
        return panel

    def _carried(self, relative_m: np.ndarray, t_s: float) -> Beacon | None:
        if self.track is None:
            return None
        predicted = predict(self.track, t_s, self.rules.motion).position_m
        distances = sorted((float(np.linalg.norm(relative_m + b.center_m - predicted)), b.id)
                           for b in self.beacon_map.beacons)
        if distances[0][0] > self.rules.carry_gate_m:
            return None
        if len(distances) > 1 and distances[1][0] < self.rules.carry_ratio * distances[0][0]:
            return None
        return self.beacon_map.beacon(distances[0][1])

    def locate(self, pose_frame: LumaFrame, id_frames: list[LumaFrame] = ()) -> LocateResult:
        """The fix of one capture, with its VLC reading and the filtered track."""
        self.last_seen_s = time.monotonic()
        self.stats.captures += 1
        t_s = (pose_frame.meta.timestamp_ns or 0) * 1e-9
        self.panels = [p for p in self.panels if t_s - p.t_s <= self.rules.panel_timeout_s]
        candidates = find_beacon_blobs(pose_frame.pixels, self.rules.room.candidates)
        blobs = list(candidates.blobs)
        template = self._template()
        height, width = pose_frame.pixels.shape
        # stripes of each ID frame, attached to the nearest pose-frame blob
        stripes: dict[int, list] = {}
        for frame in id_frames:
            for panel in read_id_frame(frame, self.rules.room.candidates, self.rules.room.stripes).panels:
                if panel.observation is None or not blobs:
                    continue
                gaps = [np.hypot(panel.centroid_norm[0] - b.centroid_px[0] / width,
                                 panel.centroid_norm[1] - b.centroid_px[1] / height) for b in blobs]
                nearest = int(np.argmin(gaps))
                if gaps[nearest] <= self.rules.id_frame_gate_norm:
                    stripes.setdefault(nearest, []).append(panel.observation)
        fixes: list[PanelFix] = []
        claimed: set[int] = set()
        refusals: list[LocateResult] = []
        for index, blob in enumerate(blobs):
            if blob.cut_off or template is None:
                continue
            others = [b for b in blobs if b is not blob]
            relative = locate_panel(pose_frame, blob, others, template, self.options, candidates.levels.background,
                                    self.rules.room)
            if not relative.ok:
                refusals.append(relative)
                continue
            relative_m = np.array(relative.position_m)
            panel = self._panel_for(relative_m, t_s, claimed)
            for observation in stripes.get(index, []):
                panel.evidence.add(observation)
            reading = vlc_reading(panel.evidence) if panel.evidence.observations else None
            if reading is not None and reading.confident:
                if panel.beacon_id is not None and panel.beacon_id != reading.beacon_id:
                    self.stats.conflicts += 1
                panel.beacon_id = reading.beacon_id
            carried = self._carried(relative_m, t_s)
            if panel.beacon_id is not None:
                beacon, source = self.beacon_map.beacon(panel.beacon_id), BeaconIdSource.vlc
                if carried is not None and carried.id != beacon.id:
                    self.stats.conflicts += 1
            elif carried is not None:
                beacon, source = carried, BeaconIdSource.track
            else:
                continue
            result = relative.model_copy(update={
                "position_m": (relative_m + beacon.center_m).tolist(), "beacon_id": beacon.id,
                "beacon_id_source": source})
            fixes.append(PanelFix(blob, beacon, source, result, reading))
        best = choose_and_fuse(fixes, self.rules.room)
        if best is None:
            return self._no_fix(blobs, refusals, t_s)
        return self._track(best, len(blobs), t_s)

    def _no_fix(self, blobs, refusals, t_s) -> LocateResult:
        if refusals:
            first = refusals[0]
            reason, message = first.reason, first.message
        elif blobs and all(b.cut_off for b in blobs):
            reason, message = FailureReason.beacon_cut_off, "every panel in view touches the frame border"
        elif blobs:
            reason, message = FailureReason.unknown_beacon, "no panel in view has a beacon ID yet (VLC or track)"
        else:
            reason, message = FailureReason.no_beacon, "no beacon-shaped blob in view"
        track = None
        if self.track is not None and t_s >= self.track.t_s:
            predicted = predict(self.track, t_s, self.rules.motion)
            track = TrackState(filtered_position_m=predicted.position_m.tolist(),
                               velocity_mps=predicted.velocity_mps.tolist(), outlier=False)
        return LocateResult(ok=False, reason=reason, message=message, beacons_in_view=len(blobs), track=track)

    def _track(self, best: PanelFix, in_view: int, t_s: float) -> LocateResult:
        self.stats.fixes += 1
        if best.source is BeaconIdSource.vlc:
            self.stats.vlc_ids += 1
        else:
            self.stats.carried_ids += 1
        fix = np.array(best.result.position_m)
        outlier = False
        if self.track is None or t_s < self.track.t_s:
            self.track = start(t_s, fix, self.rules.motion)
        else:
            step = update(self.track, t_s, fix, self.rules.motion)
            self.track, outlier = step.state, not step.accepted
            self.stats.outliers += int(outlier)
        state = TrackState(filtered_position_m=self.track.position_m.tolist(),
                           velocity_mps=self.track.velocity_mps.tolist(), outlier=outlier,
                           beacon_id_carried=best.source is BeaconIdSource.track)
        return best.result.model_copy(update={"vlc": best.vlc, "beacons_in_view": in_view, "track": state})


@dataclass
class SessionStore:
    """Sessions by device id; idle ones are dropped."""

    idle_s: float = 600.0
    sessions: dict[str, DeviceSession] = field(default_factory=dict)

    def get(self, device_id: str, beacon_map: BeaconMap, options: PipelineOptions = PipelineOptions()) -> DeviceSession:
        now = time.monotonic()
        self.sessions = {k: s for k, s in self.sessions.items() if now - s.last_seen_s <= self.idle_s}
        session = self.sessions.get(device_id)
        if session is None or session.beacon_map != beacon_map:
            session = DeviceSession(beacon_map, options)
            self.sessions[device_id] = session
        return session
