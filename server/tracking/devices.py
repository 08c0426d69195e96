"""Every device's state in this process: its session and the ID stripes waiting for its pose frame.

The phone uploads each capture as separate requests (docs/vlc.md): the pose frame, and a burst
of short-exposure ID frames, all with the same `X-Lumipose-Device`. An ID frame is read when it
arrives and only its stripes wait here (a few kilobytes, not the frame) until the device's next
pose frame, which the device's session then locates with them.

One owner, one lock: `Devices` keeps one record per device (its lock, session and waiting
stripes), so a lock is dropped together with its session. The store's lock is held only to
find, create or drop records; each device's own lock keeps one device's frames in order, one at
a time, while other devices run in parallel. Idle devices are dropped after `idle_s`, and the
least recently seen ones when there are more than `max_devices`, never one in use.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Protocol

from server.ingest import LumaFrame
from server.options import LocateOptions
from server.outcomes import Refusal, refused
from server.tracking.session import DeviceSession, IdSighting, SessionStats, WaitingIdFrame
from server.vlc.capture import ID_BURST_FRAMES, is_id_frame
from server.vlc.reader import read_id_frame
from shared_schemas import BeaconMap, FailureReason, LocateResult


@dataclass(frozen=True)
class DeviceRules:
    idle_s: float = 600.0  # a device silent for longer loses its session
    max_devices: int = 1000  # bounds the memory held for devices that went away
    id_frames_kept: int = ID_BURST_FRAMES  # a capture's burst; an older burst gives way to a newer one
    max_id_frame_age_s: float = 2.0  # ID frames further than this from the pose frame are not combined
    max_panels_per_id_frame: int = 8  # the largest panels of an ID frame keep their stripes
    max_waiting_bytes: int = 64 * 2**20  # stripes waiting, all devices together; the least recent give way


@dataclass
class DeviceRecord:
    """One device's state between its requests: its session and the ID stripes waiting for its pose frame."""

    session: DeviceSession | None = None
    waiting: deque[WaitingIdFrame] = field(default_factory=deque)


class DeviceSessions(Protocol):
    """Where devices' records live: this process (`Devices`) or a store shared by replicas
    (`server.tracking.shared.SharedDevices`); either takes one device's frames one at a time."""

    def locate(
        self, device_id: str, frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions = ...
    ) -> LocateResult: ...

    def unavailable(self) -> str | None:
        """Why the store cannot take frames now (its server does not answer), or None."""
        ...


class SessionStoreError(Exception):
    """The store of device sessions could not take a frame; `code`: 'redis_unavailable' (the shared store
    does not answer), 'busy' (the device's record kept changing under the update), 'session_too_large'."""

    def __init__(self, code: str, message: str):
        super().__init__(message)
        self.code, self.message = code, message


def locate_in_record(
    record: DeviceRecord, frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions, rules: DeviceRules
) -> LocateResult:
    """An ID frame's stripes are kept in the record for the device's next pose frame; a pose frame is
    located in the record's session (a new one for a new map), with the stripes waiting for it."""
    if is_id_frame(frame):
        return _keep(record, frame, options, rules)
    if record.session is None or record.session.beacon_map != beacon_map:
        record.session = DeviceSession(beacon_map, options.session)
    sightings = _fresh_sightings(record, frame, rules)
    return record.session.locate(frame, sightings, options.pipeline, options.room)


def _keep(record: DeviceRecord, frame: LumaFrame, options: LocateOptions, rules: DeviceRules) -> LocateResult:
    reading = read_id_frame(frame, options.room.candidates, options.room.stripes)
    if reading.problem is not None:
        return refused(Refusal(FailureReason.id_frame, f"ID frame not kept: {reading.problem}"))
    t_s = None if frame.meta.timestamp_ns is None else frame.meta.timestamp_ns * 1e-9
    read = [p for p in reading.panels if p.observation is not None][: rules.max_panels_per_id_frame]
    sightings = tuple(IdSighting(p.centroid_norm, p.observation) for p in read if p.observation is not None)
    record.waiting = deque([*record.waiting, WaitingIdFrame(t_s, sightings)][-rules.id_frames_kept :])
    return refused(
        Refusal(
            FailureReason.id_frame,
            f"ID frame kept for this device's next pose frame ({len(record.waiting)} waiting)",
        )
    )


def _fresh_sightings(record: DeviceRecord, pose_frame: LumaFrame, rules: DeviceRules) -> list[IdSighting]:
    waiting, record.waiting = list(record.waiting), deque()
    stamp = pose_frame.meta.timestamp_ns
    return [
        s
        for w in waiting
        if stamp is None or w.t_s is None or abs(stamp * 1e-9 - w.t_s) <= rules.max_id_frame_age_s
        for s in w.sightings
    ]


@dataclass
class _Device:
    lock: threading.Lock = field(default_factory=threading.Lock)
    record: DeviceRecord = field(default_factory=DeviceRecord)
    waiting_bytes: int = 0  # of `record.waiting`; changed under the store's lock only
    last_seen_s: float = 0.0
    users: int = 0  # requests holding or waiting for `lock`: such a record is never dropped


class Devices:
    """Device sessions by device id; safe to call from many threads at once."""

    def __init__(self, rules: DeviceRules = DeviceRules(), clock: Callable[[], float] = time.monotonic):
        self.rules = rules
        self._clock = clock
        self._lock = threading.Lock()
        self._devices: OrderedDict[str, _Device] = OrderedDict()  # least recently seen first
        self._waiting_bytes = 0  # all devices' waiting stripes

    def locate(
        self, device_id: str, frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions = LocateOptions()
    ) -> LocateResult:
        """The frame located in the device's record (`locate_in_record`), one at a time per device."""
        with self._checked_out(device_id) as device:
            try:
                return locate_in_record(device.record, frame, beacon_map, options, self.rules)
            finally:  # the stripes it keeps (or used up, even when it raised) count against all devices' budget
                with self._lock:
                    self._set_waiting(device, device.record.waiting)
                    self._within_budget(device)

    def unavailable(self) -> str | None:
        return None  # this process's memory is always there

    def stats(self, device_id: str) -> SessionStats | None:
        with self._lock:
            device = self._devices.get(device_id)
        if device is None:
            return None
        with device.lock:
            return None if device.record.session is None else device.record.session.stats

    def __len__(self) -> int:
        with self._lock:
            return len(self._devices)

    @property
    def waiting_bytes(self) -> int:
        """Memory held by the stripes of ID frames waiting for their pose frames, all devices."""
        with self._lock:
            return self._waiting_bytes

    @contextmanager
    def _checked_out(self, device_id: str) -> Iterator[_Device]:
        with self._lock:
            self._drop_idle()
            device = self._devices.get(device_id)
            if device is None:
                self._make_room()
                device = self._devices[device_id] = _Device()
            self._devices.move_to_end(device_id)
            device.users += 1
        try:
            with device.lock:  # one device's frames are taken one at a time
                yield device
        finally:
            with self._lock:
                device.users -= 1
                device.last_seen_s = self._clock()

    def _drop_idle(self) -> None:
        """Drop the devices idle for longer than `idle_s` (the store's lock is held)."""
        now = self._clock()
        for device_id, device in list(self._devices.items()):
            if device.users == 0 and now - device.last_seen_s > self.rules.idle_s:
                self._forget(device_id)

    def _make_room(self) -> None:
        """Drop the least recently seen devices not in use until a new one fits (the store's lock is held)."""
        idle = [k for k, d in self._devices.items() if d.users == 0]
        for device_id in idle[: max(0, len(self._devices) + 1 - self.rules.max_devices)]:
            self._forget(device_id)

    def _forget(self, device_id: str) -> None:
        self._waiting_bytes -= self._devices.pop(device_id).waiting_bytes

    def _set_waiting(self, device: _Device, waiting: deque[WaitingIdFrame]) -> None:
        """Replace a device's waiting frames and keep the byte count (the store's lock is held)."""
        nbytes = sum(w.nbytes for w in waiting)
        self._waiting_bytes += nbytes - device.waiting_bytes
        device.record.waiting, device.waiting_bytes = waiting, nbytes

    def _within_budget(self, keeping: _Device) -> None:
        """Drop the waiting frames of the least recently seen devices not in use until the total fits."""
        for device in list(self._devices.values()):
            if self._waiting_bytes <= self.rules.max_waiting_bytes:
                return
            if device is not keeping and device.users == 0 and device.record.waiting:
                self._set_waiting(device, deque())
