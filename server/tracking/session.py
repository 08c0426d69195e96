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
   fix to the constant-velocity filter, keeping the raw fix beside the filtered one;
5. with no complete panel, fits the visible edges of the cut-off panels the track expects
   (`server.pose.partial`), using the contour growth measured on earlier complete panels.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from server.geometry import camera_matrix, distortion_vector, rotation_from_ypr, ypr_from_rotation
from server.ingest import LumaFrame
from server.pipeline import PipelineOptions
from server.pose.partial import PartialRules, edge_points, fit_partial, measure_growth, tilt_from_gravity
from server.rooms import PanelFix, RoomRules, choose_and_fuse, locate_panel, vlc_reading
from server.tracking.filter import FilterRules, FilterState, predict, start, update
from server.vision.beacons import find_beacon_blobs
from server.vlc.decoder import IdEvidence
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, LocateResult, TrackState, VlcReading


@dataclass(frozen=True)
class SessionRules:
    id_frame_gate_norm: float = 0.15  # ID-frame blob to pose-frame blob, in frame widths/heights
    panel_gate_m: float = 0.6  # relative-position jump allowed between captures (0.5 s at 0.8 m/s, turning)
    carry_gate_m: float = 0.30  # track prediction to the carried beacon's hypothesis
    carry_ratio: float = 2.5  # the next hypothesis must be this much farther
    panel_timeout_s: float = 1.2  # a panel unseen for longer is forgotten (with an established track)
    unpredicted_timeout_s: float = 0.6  # without one: only from one capture to the next
    evidence_frames: int = 16
    partial_gate: float = 0.5  # nearest predicted panel centre / next nearest, at a blob's centroid
    established_fixes: int = 2  # accepted fixes in a row (a speed) before the track may carry or veto an ID
    room: RoomRules = RoomRules()
    motion: FilterRules = FilterRules()
    partial: PartialRules = PartialRules()


@dataclass
class PanelTrack:
    """One physical panel followed across captures."""

    relative_m: np.ndarray  # camera position minus panel centre at the last sighting
    t_s: float
    evidence: IdEvidence
    beacon_id: int | None = None  # confidently decoded ID, kept once known
    reading: VlcReading | None = None  # the decision that named it


@dataclass
class SessionStats:
    captures: int = 0
    fixes: int = 0
    vlc_ids: int = 0
    carried_ids: int = 0
    outliers: int = 0
    conflicts: int = 0  # VLC said one beacon, the track another
    foreign_ids: int = 0  # confident codes of beacons not in the map


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
    accepted_in_row: int = 0
    growths_px: list[float] = field(default_factory=list)
    last_rotation_wc: np.ndarray | None = None
    last_seen_s: float = field(default_factory=time.monotonic)

    def _template(self) -> Beacon | None:
        """A beacon at the origin standing for every map beacon, when they all look alike."""
        shapes = {_geometry(b) for b in self.beacon_map.beacons}
        if len(shapes) != 1:
            return None
        first = self.beacon_map.beacons[0]
        return first.model_copy(update={"center_m": [0.0, 0.0, 0.0]})

    def _panel_for(self, relative_m: np.ndarray, t_s: float, claimed: set[int]) -> PanelTrack:
        """The panel track this sighting continues, or a new one.

        After a walk of one beacon spacing the relative position to the next panel repeats the
        old one: without an established track (whose velocity predicts the change) a panel is
        only continued from the capture just before, so a walker cannot alias two panels.
        """
        established = self.track is not None and self.accepted_in_row >= self.rules.established_fixes
        velocity = self.track.velocity_mps if established else np.zeros(3)
        timeout = self.rules.panel_timeout_s if established else self.rules.unpredicted_timeout_s
        best, best_distance = None, self.rules.panel_gate_m
        for index, panel in enumerate(self.panels):
            if index in claimed or t_s - panel.t_s > timeout:
                continue
            # the camera moved by velocity * dt since that sighting, and so did its position relative to a
            # fixed panel; at a turn the walker did not, so standing still counts too. A neighbouring
            # panel is a beacon spacing (>= 1.2 m) off either way, twice the gate.
            moved = panel.relative_m + velocity * (t_s - panel.t_s)
            distance = min(float(np.linalg.norm(relative_m - moved)), float(np.linalg.norm(relative_m - panel.relative_m)))
            if distance < best_distance:
                best, best_distance = index, distance
        if best is None:
            evidence = IdEvidence(preferred=tuple(sorted(b.id for b in self.beacon_map.beacons)),
                                  rules=self.rules.room.stripes, max_frames=self.rules.evidence_frames)
            self.panels.append(PanelTrack(relative_m, t_s, evidence))
            best = len(self.panels) - 1
        claimed.add(best)
        panel = self.panels[best]
        panel.relative_m, panel.t_s = relative_m, t_s
        return panel

    def _carried(self, relative_m: np.ndarray, t_s: float) -> Beacon | None:
        """The map beacon the track predicts for this panel, when the track is established and unambiguous."""
        if self.track is None or self.accepted_in_row < self.rules.established_fixes:
            return None
        if t_s - self.track.t_s > self.rules.panel_timeout_s * 2:
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
        # stripes of each ID frame, attached to the nearest pose-frame blob
        stripes: dict[int, list] = {}
        for frame in id_frames:
            for panel in read_id_frame(frame, self.rules.room.candidates, self.rules.room.stripes).panels:
                if panel.observation is None or not blobs:
                    continue
                gaps = [np.hypot(*np.subtract(panel.centroid_norm,
                                              pose_frame.meta.fraction_of_full_frame(*b.centroid_px))) for b in blobs]
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
            named = self._name_panel(blob, relative, stripes.get(index, []), t_s, claimed)
            if named is not None:
                fixes.append(named)
        best = choose_and_fuse(fixes, self.rules.room)
        level = candidates.levels.threshold
        if best is None:
            partial = self._partial_fix(pose_frame, blobs, level, t_s)
            if not isinstance(partial, PanelFix) and template is not None:
                alone = self._cut_off_panels(pose_frame, blobs, stripes, level, t_s, claimed, template)
                partial = alone if alone is not None else partial
            if isinstance(partial, PanelFix):
                return self._track(partial, len(blobs), t_s)
            if partial is not None:
                refusals.insert(0, LocateResult(ok=False, reason=FailureReason.beacon_cut_off, message=partial))
            return self._no_fix(blobs, refusals, t_s)
        self._measure_growth(pose_frame, best, level)
        return self._track(best, len(blobs), t_s)

    def _name_panel(self, blob, relative: LocateResult, observations, t_s: float, claimed: set[int]) -> PanelFix | None:
        """The fix of a panel located relative to the template, once its beacon is named (VLC or track)."""
        relative_m = np.array(relative.position_m)
        panel = self._panel_for(relative_m, t_s, claimed)
        for observation in observations:
            panel.evidence.add(observation)
        reading = panel.reading
        if panel.beacon_id is None and panel.evidence.observations:  # decoding stops once the ID is known
            reading = panel.reading = vlc_reading(panel.evidence)
        if reading is not None and reading.confident and self.beacon_map.beacon(reading.beacon_id) is None:
            self.stats.foreign_ids += 1  # a confidently read code that is not in this map: not used
        elif reading is not None and reading.confident:
            if panel.beacon_id is not None and panel.beacon_id != reading.beacon_id:
                self.stats.conflicts += 1
            panel.beacon_id = reading.beacon_id
        carried = self._carried(relative_m, t_s)
        if panel.beacon_id is not None and carried is not None and carried.id != panel.beacon_id:
            # the established track and the panel's VLC evidence disagree: the evidence may mix two
            # panels (a mis-association), so it is dropped and the track's beacon is used
            self.stats.conflicts += 1
            panel.beacon_id = panel.reading = None
            panel.evidence.observations.clear()
        if panel.beacon_id is not None:
            beacon, source = self.beacon_map.beacon(panel.beacon_id), BeaconIdSource.vlc
        elif carried is not None:
            beacon, source = carried, BeaconIdSource.track
        else:
            return None
        result = relative.model_copy(update={
            "position_m": (relative_m + beacon.center_m).tolist(), "beacon_id": beacon.id,
            "beacon_id_source": source})
        return PanelFix(blob, beacon, source, result, reading)

    def _cut_off_panels(self, frame: LumaFrame, blobs, stripes, level: float, t_s: float, claimed: set[int],
                        template: Beacon) -> PanelFix | None:
        """Each cut-off panel located alone relative to the template (its growth fitted when none is
        known yet), then named like a complete panel: how a walk that starts between panels starts."""
        gravity = frame.meta.gravity_camera
        if gravity is None:
            return None
        pitch, roll = tilt_from_gravity(np.asarray(gravity))
        yaw = ypr_from_rotation(self.last_rotation_wc)[0] if self.last_rotation_wc is not None else template.yaw_deg
        rotation = rotation_from_ypr(yaw, pitch, roll)
        growth = float(np.median(self.growths_px)) if self.growths_px else None
        fixes = []
        for index, blob in enumerate(blobs):
            if not blob.cut_off:
                continue
            points = edge_points(frame.pixels, blob.bounding_box, level, self.rules.partial)
            distance_m = frame.camera.fx * template.side_m / max(blob.bounding_box[2], blob.bounding_box[3], 1)
            ray = rotation @ np.array([(blob.centroid_px[0] - frame.camera.cx) / frame.camera.fx,
                                       (blob.centroid_px[1] - frame.camera.cy) / frame.camera.fy, 1.0])
            start_m = -ray * distance_m / ray[2]
            fit = fit_partial([(template, points)], frame.camera, gravity, start_m, yaw, growth, self.rules.partial)
            if isinstance(fit, str):
                continue
            relative = LocateResult(
                ok=True, position_m=fit.position_m.tolist(), rotation_wc=fit.rotation_wc.tolist(),
                yaw_pitch_roll_deg=list(ypr_from_rotation(fit.rotation_wc)), reprojection_error_px=fit.rms_px,
                center_px=list(blob.centroid_px), gravity_used=True,
                warnings=[f"pose from the visible edges of a cut-off panel ({fit.points} points, "
                          f"sigma {fit.sigma_m * 1000:.1f} mm, growth {fit.growth_px:.2f} px)"])
            named = self._name_panel(blob, relative, stripes.get(index, []), t_s, claimed)
            if named is not None:
                fixes.append(named)
        return choose_and_fuse(fixes, self.rules.room)

    def _measure_growth(self, frame: LumaFrame, best: PanelFix, level: float) -> None:
        """The clipped panel's contour growth, from a complete panel whose pose is now known."""
        points = edge_points(frame.pixels, best.blob.bounding_box, level, self.rules.partial)
        growth = measure_growth(best.beacon, points, best.result.position_m, best.result.rotation_wc, frame.camera)
        if growth is not None:
            self.growths_px = (self.growths_px + [growth])[-10:]
        self.last_rotation_wc = np.array(best.result.rotation_wc)

    def _partial_fix(self, frame: LumaFrame, blobs, level: float, t_s: float) -> PanelFix | str | None:
        """A fix from the visible parts of panels named by the track; None when not even tried."""
        if (not blobs or self.track is None or self.accepted_in_row < self.rules.established_fixes
                or not self.growths_px or self.last_rotation_wc is None
                or t_s - self.track.t_s > self.rules.panel_timeout_s * 2):
            return None
        gravity = frame.meta.gravity_camera
        if gravity is None:
            return "cut-off panels need the gravity vector"
        predicted = predict(self.track, t_s, self.rules.motion).position_m
        yaw = ypr_from_rotation(self.last_rotation_wc)[0]
        pitch, roll = tilt_from_gravity(np.asarray(gravity))
        rotation = rotation_from_ypr(yaw, pitch, roll)
        centres = np.array([b.center_m for b in self.beacon_map.beacons], float)
        projected, _ = cv2.projectPoints((centres - predicted) @ rotation, np.zeros(3), np.zeros(3),
                                         camera_matrix(frame.camera), distortion_vector(frame.camera))
        projected = projected.reshape(-1, 2)
        panels, named = [], []
        for blob in blobs:
            gaps = np.linalg.norm(projected - blob.centroid_px, axis=1)
            order = np.argsort(gaps)
            # the nearest predicted panel names the blob when it is clearly nearer than the next one
            if len(order) > 1 and gaps[order[0]] > self.rules.partial_gate * gaps[order[1]]:
                continue
            beacon = self.beacon_map.beacons[int(order[0])]
            panels.append((beacon, edge_points(frame.pixels, blob.bounding_box, level, self.rules.partial)))
            named.append((blob, beacon))
        if not panels:
            return "no panel in view where the track expects one"
        # start where the largest named blob's centroid ray meets its panel at the predicted height
        blob, beacon = max(named, key=lambda item: item[0].area_px)
        ray = rotation @ np.array([(blob.centroid_px[0] - frame.camera.cx) / frame.camera.fx,
                                   (blob.centroid_px[1] - frame.camera.cy) / frame.camera.fy, 1.0])
        start_m = np.asarray(beacon.center_m) - ray * (beacon.center_m[2] - predicted[2]) / ray[2]
        fit = fit_partial(panels, frame.camera, gravity, start_m, yaw, float(np.median(self.growths_px)),
                          self.rules.partial)
        if isinstance(fit, str):
            return fit
        blob, beacon = named[0]
        centre, _ = cv2.projectPoints((np.array([beacon.center_m]) - fit.position_m) @ fit.rotation_wc,
                                      np.zeros(3), np.zeros(3), camera_matrix(frame.camera),
                                      distortion_vector(frame.camera))
        result = LocateResult(
            ok=True, position_m=fit.position_m.tolist(), rotation_wc=fit.rotation_wc.tolist(),
            yaw_pitch_roll_deg=list(ypr_from_rotation(fit.rotation_wc)), beacon_id=beacon.id,
            beacon_id_source=BeaconIdSource.track, center_px=centre.reshape(2).tolist(),
            reprojection_error_px=fit.rms_px, gravity_used=True,
            warnings=[f"pose from the visible edges of cut-off panels {[b.id for _, b in named]} "
                      f"({fit.points} points, sigma {fit.sigma_m * 1000:.1f} mm)"])
        return PanelFix(blob, beacon, BeaconIdSource.track, result, None)

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
            if step.restarted:
                self.accepted_in_row = 0
        self.accepted_in_row = 0 if outlier else self.accepted_in_row + 1
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
