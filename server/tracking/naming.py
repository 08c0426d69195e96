"""Which map beacon a panel in view is: panels followed across captures, named by VLC or the track.

A panel located relative to a template beacon (every map beacon looks alike) gives the camera's
position relative to that panel. From capture to capture that relative position changes only by
the walked distance, while neighbouring panels are a beacon spacing apart, so it follows one
physical panel and lets its ID frames keep adding evidence to one `IdEvidence`. A panel is
named by a confident VLC decision among the map's IDs (the decoder's hypotheses: those and "none
of them", `IdEvidence.map_ids`); without one, an established track carries the ID of the map
beacon where it predicts the camera to be, when that is unambiguous; when the two disagree the
track wins and the panel's evidence is dropped (it may mix two panels). Stripes that read as a
code outside the map never name a panel; the capture's result says what they read (`notes`),
and when they are surely of none of the map's beacons the evidence is dropped too.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from server.geometry import rotation_z
from server.outcomes import Fix
from server.rooms import PanelFix, foreign_note, vlc_reading
from server.tracking.track import Track
from server.vision.beacons import BeaconBlob
from server.vlc.decoder import IdEvidence, StripeObservation, StripeRules
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, VlcReading


@dataclass(frozen=True)
class NamingRules:
    panel_gate_m: float = 0.6  # relative-position jump allowed between captures (0.5 s at 0.8 m/s, turning)
    carry_gate_m: float = 0.30  # track prediction to the carried beacon's hypothesis
    carry_ratio: float = 2.5  # the next hypothesis must be this much farther
    panel_timeout_s: float = 1.2  # a panel unseen for longer is forgotten (with an established track)
    unpredicted_timeout_s: float = 0.6  # without one: only from one capture to the next
    evidence_frames: int = 16
    stripes: StripeRules = StripeRules()


@dataclass
class PanelTrack:
    """One physical panel followed across captures."""

    relative_m: np.ndarray  # camera position minus panel centre at the last sighting
    t_s: float
    evidence: IdEvidence
    beacon_id: int | None = None  # confidently decoded ID, kept once known
    reading: VlcReading | None = None  # the decision that named it


@dataclass
class NamingStats:
    vlc_ids: int = 0
    carried_ids: int = 0
    conflicts: int = 0  # VLC said one beacon, the track another
    foreign_ids: int = 0  # readings of a code not in the map ("none of the map's" won): not used


@dataclass
class PanelNamer:
    """The panels of one device's session and the names they have earned."""

    beacon_map: BeaconMap
    rules: NamingRules = NamingRules()
    panels: list[PanelTrack] = field(default_factory=list)
    stats: NamingStats = field(default_factory=NamingStats)
    notes: list[str] = field(default_factory=list)  # this capture's: what stripes outside the map read

    def new_capture(self, t_s: float) -> set[int]:
        """Forget panels unseen for too long and the last capture's notes; the (empty) set of panels
        claimed in this capture."""
        self.panels = [p for p in self.panels if t_s - p.t_s <= self.rules.panel_timeout_s]
        self.notes = []
        return set()

    def name(
        self,
        blob: BeaconBlob,
        relative: Fix,
        observations: list[StripeObservation],
        t_s: float,
        track: Track,
        claimed: set[int],
    ) -> PanelFix | None:
        """The fix of a panel located relative to the template, once its beacon is named; None until then."""
        relative_m = np.asarray(relative.position_m)
        panel = self._panel_for(relative_m, t_s, track, claimed)
        for observation in observations:
            panel.evidence.add(observation)
        reading = panel.reading
        if panel.beacon_id is None and panel.evidence.observations:  # decoding stops once the ID is known
            reading = panel.reading = vlc_reading(panel.evidence)
        where = f"at ({blob.centroid_px[0]:.0f}, {blob.centroid_px[1]:.0f}) px"
        note = foreign_note(reading, self.beacon_map, where)
        if reading is not None and note is not None:
            self.stats.foreign_ids += 1
            self.notes.append(note)
            if reading.confidence >= self.rules.stripes.confident_posterior:
                # surely none of the map's: a foreign panel reads so again, mixed evidence starts afresh
                panel.evidence.observations.clear()
                panel.reading = None
        elif reading is not None and reading.confident:
            if panel.beacon_id is not None and panel.beacon_id != reading.beacon_id:
                self.stats.conflicts += 1
            panel.beacon_id = reading.beacon_id
        carried = self._carried(relative_m, t_s, track)
        if panel.beacon_id is not None and carried is not None and carried.id != panel.beacon_id:
            self.stats.conflicts += 1
            panel.beacon_id = panel.reading = None
            panel.evidence.observations.clear()
        beacon = self.beacon_map.beacon(panel.beacon_id) if panel.beacon_id is not None else carried
        if beacon is None:
            return None
        source = BeaconIdSource.vlc if panel.beacon_id is not None else BeaconIdSource.track
        # the template is the map's first beacon at the origin (`session.template_beacon`); a beacon whose
        # yaw differs from it by a little (a surveyed map) turns the relative fix by the difference
        turn = rotation_z(beacon.yaw_deg - self.beacon_map.beacons[0].yaw_deg)
        covariance = None if relative.covariance_m2 is None else turn @ relative.covariance_m2 @ turn.T
        named = replace(
            relative,
            position_m=np.asarray(beacon.center_m) + turn @ relative_m,
            rotation_wc=turn @ np.asarray(relative.rotation_wc),
            covariance_m2=covariance,
            beacon_id=beacon.id,
            id_source=source,
        )
        return PanelFix(blob, beacon, named, reading)

    def new_evidence(self) -> IdEvidence:
        """An empty accumulator for a new panel: the map's IDs (and "none of them") its hypotheses."""
        return IdEvidence(
            map_ids=tuple(sorted(b.id for b in self.beacon_map.beacons)),
            rules=self.rules.stripes,
            max_frames=self.rules.evidence_frames,
        )

    def count(self, source: BeaconIdSource | None) -> None:
        """Count a fix that was used, by how its beacon was named."""
        if source is BeaconIdSource.vlc:
            self.stats.vlc_ids += 1
        else:
            self.stats.carried_ids += 1

    def _panel_for(self, relative_m: np.ndarray, t_s: float, track: Track, claimed: set[int]) -> PanelTrack:
        """The panel track this sighting continues, or a new one.

        After a walk of one beacon spacing the relative position to the next panel repeats the
        old one: without an established track (whose velocity predicts the change) a panel is
        only continued from the capture just before, so a walker cannot alias two panels.
        """
        velocity = track.velocity_mps()
        timeout = self.rules.panel_timeout_s if track.established else self.rules.unpredicted_timeout_s
        best, best_distance = None, self.rules.panel_gate_m
        for index, panel in enumerate(self.panels):
            if index in claimed or t_s - panel.t_s > timeout:
                continue
            # the camera moved by velocity * dt since that sighting, and so did its position relative to a
            # fixed panel; at a turn the walker did not, so standing still counts too. A neighbouring
            # panel is a beacon spacing (>= 1.2 m) off either way, twice the gate.
            moved = panel.relative_m + velocity * (t_s - panel.t_s)
            distance = min(
                float(np.linalg.norm(relative_m - moved)), float(np.linalg.norm(relative_m - panel.relative_m))
            )
            if distance < best_distance:
                best, best_distance = index, distance
        if best is None:
            self.panels.append(PanelTrack(relative_m, t_s, self.new_evidence()))
            best = len(self.panels) - 1
        claimed.add(best)
        panel = self.panels[best]
        panel.relative_m, panel.t_s = relative_m, t_s
        return panel

    def _carried(self, relative_m: np.ndarray, t_s: float, track: Track) -> Beacon | None:
        """The map beacon the track predicts for this panel, when the track is established and unambiguous."""
        predicted = track.predicted_m(t_s)
        if predicted is None:
            return None
        distances = sorted(
            (float(np.linalg.norm(relative_m + b.center_m - predicted)), b.id) for b in self.beacon_map.beacons
        )
        if distances[0][0] > self.rules.carry_gate_m:
            return None
        if len(distances) > 1 and distances[1][0] < self.rules.carry_ratio * distances[0][0]:
            return None
        return self.beacon_map.beacon(distances[0][1])
