"""Everything that tunes how a frame is located, in one value passed down from the top.

The service (`server.api.config.Settings`) and the command line build one `LocateOptions`;
each layer takes its part: the one-panel pipeline `pipeline` (which holds the rules of every
vision and pose stage), rooms of several panels `room`, device sessions `session`.
"""

from __future__ import annotations

from dataclasses import dataclass

from server.pipeline import PipelineOptions
from server.rooms import RoomRules
from server.tracking.session import SessionRules


@dataclass(frozen=True)
class LocateOptions:
    pipeline: PipelineOptions = PipelineOptions()
    room: RoomRules = RoomRules()
    session: SessionRules = SessionRules()
