"""Device sessions in Redis, shared by replicas: any replica takes any device's next frame.

Each device's record (`server.tracking.state`: JSON) is one key, `{prefix}device:{id}`, written with
an expiry of `idle_s`, so Redis forgets a silent device as `Devices` does. An update is optimistic:
WATCH the key, GET, locate the frame in the record, then MULTI / SET / EXEC; when another replica or
thread changed the device meanwhile, EXEC fails and the frame is located again on the newer record
after a short random wait, at most `MAX_ATTEMPTS` times, then answered 'busy'. No lock is taken, so a
replica that dies mid-frame leaves nothing held. A device's concurrent frames are thus each located
once per attempt: cheap for the app's few requests per capture, costly for a device that floods.

Memory is Redis's to bound (`maxmemory` with `maxmemory-policy volatile-lru`: every key here expires),
not a per-process budget as in `Devices`; `max_devices` does not apply either. Redis not answering is
a `SessionStoreError('redis_unavailable')` within the client's socket timeouts, never a hang.
"""

from __future__ import annotations

import logging
import random
import threading
import time
from typing import cast

import redis
from redis.exceptions import ConnectionError as RedisConnectionError
from redis.exceptions import RedisError, WatchError
from redis.exceptions import TimeoutError as RedisTimeoutError

from server.ingest import LumaFrame
from server.options import LocateOptions
from server.redis_store import connect, describe, lost_at_exec
from server.store import UNAVAILABLE
from server.tracking.devices import DeviceRecord, DeviceRules, SessionStoreError, locate_in_record
from server.tracking.state import StateError, dump_device, load_device
from shared_schemas import BeaconMap, LocateResult

LOG = logging.getLogger("lumipose.sessions")
MAX_ATTEMPTS = 10  # updates of one frame that lost to another writer before it is answered 'busy'
MAX_RECORD_BYTES = 4 * 2**20  # records are kilobytes (tests/server/tracking/test_state.py); more is a fault
MAX_RETRY_WAIT_S = 0.5
CONNECT_TIMEOUT_S = 1.0
SOCKET_TIMEOUT_S = 2.0


def _said(error: RedisError) -> str:
    """Redis's own words: redis-py quotes a failed pipeline's whole command (the record) before them."""
    text = str(error)
    return text.split(" of pipeline caused error: ", 1)[-1][:200]


class SharedDevices:
    """Device sessions by device id in Redis; safe to call from many threads and many processes at once."""

    def __init__(
        self, client: redis.Redis, rules: DeviceRules = DeviceRules(), prefix: str = "lumipose:", name: str = "Redis"
    ):
        self.rules = rules
        self._client = client
        self._prefix = prefix
        self._name = name  # how errors name the server, e.g. "Redis at redis://host:6379/0"
        self._lock = threading.Lock()
        self.conflicts = 0  # updates retried because another writer changed the device first

    @classmethod
    def from_url(cls, url: str, rules: DeviceRules = DeviceRules(), prefix: str = "lumipose:") -> SharedDevices:
        return cls(connect(url), rules, prefix, name=describe(url))

    def key(self, device_id: str) -> str:
        return f"{self._prefix}device:{device_id}"

    def locate(
        self, device_id: str, frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions = LocateOptions()
    ) -> LocateResult:
        """The frame located in the device's stored record (`locate_in_record`), the record written back."""
        try:
            for attempt in range(MAX_ATTEMPTS):
                started_s = time.monotonic()
                result = self._attempt(device_id, frame, beacon_map, options)
                if result is not None:
                    return result
                with self._lock:
                    self.conflicts += 1
                # writers that collided wait apart, randomly and longer each time, on the scale of one attempt:
                # then one does not lose every round to the others
                took_s = time.monotonic() - started_s
                time.sleep(random.uniform(0, min(MAX_RETRY_WAIT_S, took_s * 2**attempt)))
        except (RedisConnectionError, RedisTimeoutError) as error:
            raise SessionStoreError(UNAVAILABLE, f"{self._name} did not answer: {_said(error)}") from None
        except RedisError as error:  # e.g. out of memory under maxmemory-policy noeviction
            raise SessionStoreError(UNAVAILABLE, f"{self._name} refused the session: {_said(error)}") from None
        raise SessionStoreError(
            "busy", f"device '{device_id}': its session changed under {MAX_ATTEMPTS} updates in a row; try again"
        )

    def unavailable(self) -> str | None:
        try:
            self._client.ping()
        except RedisError as error:
            return f"{self._name} does not answer: {error}"
        return None

    def _attempt(
        self, device_id: str, frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions
    ) -> LocateResult | None:
        """The result, or None when another writer changed the device's record before this one was written."""
        key = self.key(device_id)
        diagnostics = options.pipeline.diagnostics
        if diagnostics is not None:  # a retried frame's panels are recorded afresh, not twice
            diagnostics.panels.clear()
        with self._client.pipeline() as pipe:
            pipe.watch(key)
            stored = cast(bytes | None, pipe.get(key))  # the client leaves replies as bytes
            record = self._loaded(device_id, stored, beacon_map, options)
            result = locate_in_record(record, frame, beacon_map, options, self.rules)
            data = dump_device(record.session, record.waiting)
            if len(data) > MAX_RECORD_BYTES:
                raise SessionStoreError(
                    "session_too_large",
                    f"device '{device_id}': its session would take {len(data)} bytes, over the "
                    f"{MAX_RECORD_BYTES} a record may; not stored",
                )
            pipe.multi()
            pipe.set(key, data, px=max(1, round(self.rules.idle_s * 1000)))
            try:
                pipe.execute()
            except WatchError as error:
                if lost_at_exec(error):  # Redis may have stored it: locating the frame again would count it twice
                    raise SessionStoreError(
                        UNAVAILABLE,
                        f"{self._name} did not confirm device '{device_id}''s session; its frame may be kept",
                    ) from None
                return None
        return result

    def _loaded(
        self, device_id: str, data: bytes | None, beacon_map: BeaconMap, options: LocateOptions
    ) -> DeviceRecord:
        """The stored record; a new one when there is none (a new or expired device) or it cannot be read."""
        if data is None:
            return DeviceRecord()
        try:
            return DeviceRecord(*load_device(data, beacon_map, options.session))
        except StateError as error:
            LOG.warning("device '%s' starts afresh: %s", device_id, error)
            return DeviceRecord()
