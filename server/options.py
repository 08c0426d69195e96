"""Everything that tunes how a frame is located, in one value passed down from the top.

The service (`server.api.config.Settings`) and the command line build one `LocateOptions`;
each layer takes its part: the one-panel pipeline `pipeline` (which holds the rules of every
vision and pose stage), rooms of several panels `room`, device sessions `session`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from server.pipeline import PipelineOptions
from server.rooms import RoomRules
from server.tracking.session import SessionRules
from shared_schemas import BeaconMap


@dataclass(frozen=True)
class LocateOptions:
    pipeline: PipelineOptions = PipelineOptions()
    room: RoomRules = RoomRules()
    session: SessionRules = SessionRules()

    def for_map(self, beacon_map: BeaconMap) -> LocateOptions:
        """These options with what the map states: the position error a fix must reach, and the
        looks of its panels (rooms and device sessions judge blobs by them)."""
        fit = replace(self.pipeline.outline_fit, max_sigma_m=beacon_map.required_sigma_m)
        candidates = self.room.candidates.for_beacons(beacon_map.beacons)
        return replace(
            self,
            pipeline=replace(self.pipeline, outline_fit=fit),
            room=replace(self.room, candidates=candidates),
        )
