"""Per-device state of the service: the tracking session and the ID frames waiting for a pose frame.

The phone uploads each capture as separate requests (docs/vlc.md): short-exposure ID frames,
then the pose frame, all with the same `X-Lumipose-Device`. ID frames wait here until the
device's next pose frame, which the device's session then locates with them (IDs read from the
stripes, combined over frames, carried by the track, motion-filtered). This state lives in
the process's memory: replicas keep a device on one process (docs/deployment.md).
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field

from server.ingest import LumaFrame
from server.pipeline import PipelineOptions, locate
from server.tracking.session import SessionStore
from server.vlc.capture import id_frame_problem, is_id_frame
from shared_schemas import BeaconMap, FailureReason, LocateResult

MAX_WAITING_ID_FRAMES = 4  # per device: a capture's burst (2) with room for one late burst
MAX_ID_FRAME_AGE_S = 2.0  # older ID frames than this before the pose frame are dropped, not combined
MAX_DEVICES_WAITING = 1000  # bounds the memory held by ID frames of devices that went away


@dataclass
class Devices:
    sessions: SessionStore = field(default_factory=SessionStore)
    waiting: dict[str, deque[LumaFrame]] = field(default_factory=dict)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _device_locks: dict[str, threading.Lock] = field(default_factory=dict)

    def locate(self, device: str | None, frame: LumaFrame, beacon_map: BeaconMap,
               options: PipelineOptions) -> LocateResult:
        """The device's session for a map of several beacons; the stateless pipeline otherwise."""
        if device is None or len(beacon_map.beacons) < 2 or options.beacon_id is not None:
            return locate(frame, beacon_map, options)
        with self._device_lock(device):  # one device's frames are taken in order, one at a time
            if is_id_frame(frame):
                return self._keep_id_frame(device, frame)
            id_frames = self._fresh_id_frames(device, frame)
            return self.sessions.get(device, beacon_map, options).locate(frame, id_frames)

    def _device_lock(self, device: str) -> threading.Lock:
        with self._lock:
            return self._device_locks.setdefault(device, threading.Lock())

    def _keep_id_frame(self, device: str, frame: LumaFrame) -> LocateResult:
        problem = id_frame_problem(frame)
        if problem is not None:
            return LocateResult(ok=False, reason=FailureReason.id_frame, message=f"ID frame not kept: {problem}")
        with self._lock:
            if device not in self.waiting and len(self.waiting) >= MAX_DEVICES_WAITING:
                self.waiting.pop(next(iter(self.waiting)))  # the device waiting longest gives way
            queue = self.waiting.setdefault(device, deque(maxlen=MAX_WAITING_ID_FRAMES))
            queue.append(frame)
            count = len(queue)
        return LocateResult(ok=False, reason=FailureReason.id_frame,
                            message=f"ID frame kept for this device's next pose frame ({count} waiting)")

    def _fresh_id_frames(self, device: str, pose_frame: LumaFrame) -> list[LumaFrame]:
        with self._lock:
            frames = list(self.waiting.pop(device, ()))
        pose_s = (pose_frame.meta.timestamp_ns or 0) * 1e-9
        return [f for f in frames if pose_frame.meta.timestamp_ns is None
                or abs(pose_s - f.meta.timestamp_ns * 1e-9) <= MAX_ID_FRAME_AGE_S]
