"""The operator page's live board: each device's recent results, its track, and its last frames' pictures.

The page (`server.dashboard`) shows every device that sent frames with `X-Lumipose-Device`:
its marker, its filtered track, its fix rate and refusals, and what the camera saw in its last
few pose frames. `LiveBoard` keeps all of it in this worker's memory, bounded: the last
`track_points` fixes and `frames_kept` pictures' sources (`server.annotate.FrameSeen`, a small copy
of the frame around the panel, not the frame) per device, at most `max_frame_bytes` of them in all
(the least recently seen devices give theirs up first) and `max_devices` devices. Pictures are
drawn only when the page asks for one.

One owner, one lock: every change and every read holds the board's lock for a few microseconds.
Event streams `listen` for changes, at most `max_listeners` at once: each gets an `asyncio.Event`, set
from whatever thread records a change, and reads the devices changed since the version it last saw.
What they read is shared (`shared_json`): the JSON of the devices changed since a version is built once
per board version, under a second lock, however many streams (and `GET /v1/live/devices`) ask for it.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections import Counter, OrderedDict, deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field

from server.annotate import FrameSeen, picture
from shared_schemas import FailureReason, LocateResult
from shared_schemas.api import DeviceLive, KeptFrameInfo, LiveDevices


@dataclass(frozen=True)
class LiveRules:
    frames_kept: int = 3  # pictures' sources per device; 0: none (the pipeline then keeps no diagnostics)
    track_points: int = 200  # fixes drawn as a device's fading track
    window_s: float = 10.0  # of the fix rate and the refusal shares
    max_devices: int = 1000  # as many as the device sessions (`DeviceRules.max_devices`)
    max_frame_bytes: int = 64 * 2**20  # all devices' kept pictures' sources and results together
    max_listeners: int = 32  # event streams at once (`--max-event-streams`)


@dataclass(frozen=True, eq=False)
class KeptFrame:
    seq: int
    time_s: float
    map: str
    result: LocateResult
    seen: FrameSeen
    nbytes: int  # what it keeps: the picture's sources and the result (as JSON)

    def info(self) -> KeptFrameInfo:
        return KeptFrameInfo(
            seq=self.seq, time_s=self.time_s, map=self.map, result=self.result, window_px=self.seen.part
        )


@dataclass
class _DeviceLog:
    map: str
    last_seen_s: float = 0.0
    frames: int = 0
    id_frames: int = 0
    fixes: int = 0
    recent: deque[tuple[float, FailureReason | None]] = field(default_factory=deque)  # pose frames in the window
    recent_counts: Counter[FailureReason | None] = field(default_factory=Counter)  # of `recent`, by reason
    last: LocateResult | None = None
    last_latency_ms: float | None = None
    track: deque[tuple[int, tuple[float, float, float, float]]] = field(default_factory=deque)  # (version, t x y z)
    kept: deque[KeptFrame] = field(default_factory=deque)
    kept_bytes: int = 0
    version: int = 0  # the board's version when it last changed


class Listener:
    def __init__(self) -> None:
        self.loop = asyncio.get_running_loop()
        self.changed = asyncio.Event()

    def wake(self) -> None:
        with suppress(RuntimeError):  # its loop has closed: the stream is gone with it
            self.loop.call_soon_threadsafe(self.changed.set)


class BoardFull(Exception):
    """As many event streams listen as the board takes."""


class LiveBoard:
    """The devices' live state in this worker; safe to call from many threads at once."""

    def __init__(self, rules: LiveRules = LiveRules(), clock: Callable[[], float] = time.time) -> None:
        self.rules = rules
        self._clock = clock
        self._lock = threading.Lock()
        self._devices: OrderedDict[str, _DeviceLog] = OrderedDict()  # least recently seen first
        self._version = 0
        # a kept frame's number names its picture's URL, which browsers cache: unique across restarts and workers
        self._seq = time.time_ns() // 1000
        self._frame_bytes = 0
        self._listeners: set[Listener] = set()
        self._building = threading.Lock()  # one build of the shared JSON at a time; `_shared` is this lock's
        self._shared: dict[int, tuple[int, bytes | None]] = {}  # since-version -> (board version, JSON)

    @property
    def keeps_frames(self) -> bool:
        return self.rules.frames_kept > 0

    def record(
        self,
        device: str,
        map_name: str,
        result: LocateResult,
        latency_ms: float | None = None,
        seen: FrameSeen | None = None,
    ) -> None:
        """A frame of `device` was answered with `result` (`seen`: what its picture needs, if kept)."""
        now = self._clock()
        # a kept result counts against the budget with its pictures' sources (its text is bounded by the contract)
        kept_bytes = 0 if seen is None else seen.nbytes + len(result.model_dump_json())
        with self._lock:
            log = self._devices.get(device)
            if log is None:
                self._make_room()
                log = self._devices[device] = _DeviceLog(map=map_name)
            self._devices.move_to_end(device)
            self._version += 1
            log.version, log.last_seen_s, log.map = self._version, now, map_name
            if result.reason is FailureReason.id_frame:
                log.id_frames += 1
            else:
                self._add_pose_frame(log, now, result, latency_ms, seen, kept_bytes)
            listeners = list(self._listeners)
        for listener in listeners:
            listener.wake()

    def devices(self, since_version: int = 0) -> tuple[int, LiveDevices]:
        """The board's version and the devices changed after `since_version` (0: all), most recent first,
        with the points of their tracks added after it (an event stream's update: the page appends them)."""
        now = self._clock()
        with self._lock:
            changed = [(name, log) for name, log in reversed(self._devices.items()) if log.version > since_version]
            devices = [self._device_live(name, log, now, since_version) for name, log in changed]
            version = self._version
        return version, LiveDevices(time_s=now, window_s=self.rules.window_s, devices=devices)

    def shared_json(self, since_version: int = 0) -> tuple[int, bytes | None]:
        """`devices(since_version)` as JSON (None when no device changed after it, for a version above 0),
        built once per board version and since-version: every caller asking at the same version gets the
        same bytes. Blocks while another caller builds."""
        with self._building:
            with self._lock:
                version = self._version
            cached = self._shared.get(since_version)
            if cached is not None and cached[0] == version:
                return cached
            version, live = self.devices(since_version)
            data = live.model_dump_json(by_alias=True).encode() if live.devices or since_version == 0 else None
            if any(built != version for built, _ in self._shared.values()):
                self._shared = {}  # the board changed: what was built before is stale
            self._shared[since_version] = (version, data)
            return version, data

    def kept_frames(self, device: str) -> list[KeptFrame] | None:
        """The device's kept frames, newest first; None for a device not on the board."""
        with self._lock:
            log = self._devices.get(device)
            return None if log is None else list(reversed(log.kept))

    def picture(self, device: str, seq: int) -> bytes | None:
        """The PNG of the device's kept frame `seq`, drawn now (tens of ms, outside the lock), or None."""
        with self._lock:
            log = self._devices.get(device)
            kept = None if log is None else next((k for k in log.kept if k.seq == seq), None)
        return None if kept is None else picture(kept.seen, kept.result)

    def expire_windows(self) -> None:
        """Let the window of the fix rate and refusal shares pass for devices that sent nothing since: those
        whose counts change are marked changed, so event streams send their figures going down to zero."""
        now = self._clock()
        with self._lock:
            since = now - self.rules.window_s
            stale = [log for log in self._devices.values() if log.recent and log.recent[0][0] < since]
            for log in stale:
                self._forget_old(log, now)
                self._version += 1
                log.version = self._version
            listeners = list(self._listeners) if stale else []
        for listener in listeners:
            listener.wake()

    def __len__(self) -> int:
        with self._lock:
            return len(self._devices)

    @property
    def frame_bytes(self) -> int:
        with self._lock:
            return self._frame_bytes

    @contextmanager
    def listen(self) -> Iterator[asyncio.Event]:
        """An event set whenever the board changes, for as long as the block runs (call on the event loop);
        `BoardFull` when `max_listeners` listen already."""
        listener = self.add_listener()
        try:
            yield listener.changed
        finally:
            self.remove_listener(listener)

    def add_listener(self) -> Listener:
        """A listener whose `changed` is set whenever the board changes, until `remove_listener` (call on the
        event loop); `BoardFull` when `max_listeners` listen already."""
        listener = Listener()
        with self._lock:
            if len(self._listeners) >= self.rules.max_listeners:
                raise BoardFull(f"{len(self._listeners)} event streams are open, the most this worker takes")
            self._listeners.add(listener)
        return listener

    def remove_listener(self, listener: Listener) -> None:
        with self._lock:
            self._listeners.discard(listener)

    def _add_pose_frame(
        self,
        log: _DeviceLog,
        now: float,
        result: LocateResult,
        latency_ms: float | None,
        seen: FrameSeen | None,
        kept_bytes: int,
    ) -> None:
        """(The board's lock is held.)"""
        log.frames += 1
        log.last, log.last_latency_ms = result, latency_ms
        log.recent.append((now, result.reason))
        log.recent_counts[result.reason] += 1
        self._forget_old(log, now)
        if result.ok and result.position_m is not None:
            log.fixes += 1
            x, y, z = result.track.filtered_position_m if result.track is not None else result.position_m
            log.track.append((self._version, (now, x, y, z)))
            while len(log.track) > self.rules.track_points:
                log.track.popleft()
        if seen is not None and self.keeps_frames:
            self._seq += 1
            log.kept.append(KeptFrame(self._seq, now, log.map, result, seen, kept_bytes))
            self._set_kept_bytes(log, log.kept_bytes + kept_bytes)
            while len(log.kept) > self.rules.frames_kept:
                self._set_kept_bytes(log, log.kept_bytes - log.kept.popleft().nbytes)
            self._within_budget(log)

    def _device_live(self, name: str, log: _DeviceLog, now: float, since_version: int) -> DeviceLive:
        """(The board's lock is held.)"""
        self._forget_old(log, now)  # kept counts: an event costs the same whatever the frame rate
        frames = len(log.recent)
        refused = {reason.value: n / frames for reason, n in log.recent_counts.items() if reason is not None and n}
        return DeviceLive(
            device=name,
            map=log.map,
            last_seen_s=log.last_seen_s,
            frames=log.frames,
            id_frames=log.id_frames,
            fixes=log.fixes,
            fix_rate_hz=log.recent_counts[None] / self.rules.window_s,
            refused=refused,
            last_latency_ms=log.last_latency_ms,
            last=log.last,
            track=[point for version, point in log.track if version > since_version],
            frames_kept=[k.seq for k in log.kept],
        )

    def _forget_old(self, log: _DeviceLog, now: float) -> None:
        """Drop the pose frames older than the window from the counts (the board's lock is held)."""
        while log.recent and log.recent[0][0] < now - self.rules.window_s:
            log.recent_counts[log.recent.popleft()[1]] -= 1

    def _set_kept_bytes(self, log: _DeviceLog, nbytes: int) -> None:
        self._frame_bytes += nbytes - log.kept_bytes
        log.kept_bytes = nbytes

    def _within_budget(self, keeping: _DeviceLog) -> None:
        """Drop the least recently seen devices' kept frames until all fit; `keeping`'s newest stays."""
        for log in self._devices.values():
            while log.kept and self._frame_bytes > self.rules.max_frame_bytes:
                if log is keeping and len(log.kept) == 1:
                    return
                self._set_kept_bytes(log, log.kept_bytes - log.kept.popleft().nbytes)
            if self._frame_bytes <= self.rules.max_frame_bytes:
                return

    def _make_room(self) -> None:
        """Drop the least recently seen devices until a new one fits (the board's lock is held)."""
        while len(self._devices) >= self.rules.max_devices:
            _, log = self._devices.popitem(last=False)
            self._frame_bytes -= log.kept_bytes
