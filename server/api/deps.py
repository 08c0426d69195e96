"""Dependencies shared by the routes: settings, stores, the pipeline limiter, the API key."""

from __future__ import annotations

import hmac
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass, field, replace
from typing import Annotated

import anyio
from fastapi import Depends, Header, Request
from starlette.responses import Response

from server.api.child import TimedChild
from server.api.config import Settings
from server.api.errors import ApiError
from server.api.metrics import Metrics, StatusWindow
from server.api.upload import BufferLease, ReceiveBuffers
from server.live import LiveBoard
from server.options import LocateOptions
from server.pipeline import CornerMethod
from server.pose.solve import GravityMode
from server.store import MapStore, ProfileStore, SampleStore
from server.tracking.devices import DeviceSessions


class FrameSlots:
    """How many frame uploads a worker holds at once (each up to `max_upload_bytes`), and the buffers
    they are received into: each slot lends its request one (`ReceiveBuffers`: kept for the next)."""

    def __init__(self, slots: int) -> None:
        self._semaphore = anyio.Semaphore(slots)
        self.buffers = ReceiveBuffers(keep=slots)

    async def run(self, wait_s: float, work: Callable[[BufferLease], Awaitable[Response]]) -> Response:
        with anyio.move_on_after(wait_s) as waited:
            await self._semaphore.acquire()
        if waited.cancelled_caught:
            raise ApiError(503, "busy", "too many frames are being received; try again", field="body").closing()
        lease = BufferLease(self.buffers)
        try:
            return await work(lease)
        finally:  # answered (or refused): the frame is no longer read
            lease.close()
            self._semaphore.release()


class WorkSlots:
    """At most `running` jobs of one kind at once and `waiting` more in line for a slot; beyond, 503 `busy`
    with Retry-After at once: a kind of slow work (calibrations, surveys, pictures) never holds the
    pipeline's threads, and its queue cannot grow without bound.

    Its counts are the event loop's alone (changed only between awaits, never from a worker thread).
    """

    def __init__(self, what: str, running: int, waiting: int, retry_after_s: int) -> None:
        self.what, self.running, self.waiting, self.retry_after_s = what, running, waiting, retry_after_s
        self._limiter = anyio.CapacityLimiter(running)
        self._queued = 0

    @property
    def held(self) -> int:
        """Jobs running or waiting now."""
        return int(self._limiter.borrowed_tokens) + self._queued

    @asynccontextmanager
    async def slot(self) -> AsyncIterator[None]:
        if self.held >= self.running + self.waiting:
            error = ApiError(
                503,
                "busy",
                f"{self.what}: {self.running} running and {self.waiting} waiting, the most this server takes at "
                f"once; try again in {self.retry_after_s} s",
            )
            error.headers["Retry-After"] = str(self.retry_after_s)
            raise error
        self._queued += 1
        try:
            await self._limiter.acquire()
        finally:
            self._queued -= 1
        try:
            yield
        finally:
            self._limiter.release()


@dataclass(frozen=True)
class Services:
    """What the app holds for its lifetime; built once by `create_app`."""

    settings: Settings
    maps: MapStore
    profiles: ProfileStore  # bundled and stored device profiles: what a frame's camera may name
    samples: SampleStore
    metrics: Metrics
    options: LocateOptions  # from the settings; a request's query refines its pipeline part
    devices: DeviceSessions  # this process's, or Redis's with --redis: see docs/deployment.md
    pipeline_limiter: anyio.CapacityLimiter  # CPU-bound work: no more threads than cores
    survey_slots: WorkSlots  # surveys (seconds to a minute each): one at a time, apart from the pipeline
    calibration_slots: WorkSlots  # calibrations (up to tens of seconds of fitting): apart from the pipeline
    calibrator: TimedChild  # where calibrations run: a child process stopped at the time limit
    picture_slots: WorkSlots  # the live page's pictures (tens of ms each): apart from the pipeline
    live_limiter: anyio.CapacityLimiter  # the live board's shared JSON and status for the streams: one thread
    frame_slots: FrameSlots  # frame uploads held at once (server.api.guard)
    live: LiveBoard  # devices as the operator's page shows them (per worker, as `devices`)
    status_window: StatusWindow  # request rates and latencies of the last minute, for the page
    started_s: float  # unix time this worker started
    _chosen: dict[tuple[GravityMode, CornerMethod], LocateOptions] = field(default_factory=dict, init=False, repr=False)

    def options_for(self, gravity: GravityMode, corners: CornerMethod) -> LocateOptions:
        """`options` with a request's choice of gravity and corners, made once for each pair (so that the
        next request's are the same object: `server.locator` then makes its options for the map once too)."""
        chosen = self._chosen.get((gravity, corners))
        if chosen is None:
            pipeline = replace(self.options.pipeline, gravity_mode=gravity, corner_method=corners)
            chosen = self._chosen[(gravity, corners)] = replace(self.options, pipeline=pipeline)
        return chosen


# The dependencies are coroutines though they never wait: FastAPI runs a plain function's dependency in a
# worker thread, a hop of its own (~0.1 ms, a few on a busy machine) for every request.
async def _services(request: Request) -> Services:
    return request.app.state.services


ServicesDep = Annotated[Services, Depends(_services)]


def api_key_problem(expected: str | None, given: str | None) -> ApiError | None:
    """Why a write with `given` as its X-API-Key is refused by a server whose key is `expected`."""
    if expected is None:
        return None
    if given is None:
        return ApiError(401, "unauthorized", "this server needs an X-API-Key header for writes", field="X-API-Key")
    if not hmac.compare_digest(given.encode(), expected.encode()):
        return ApiError(401, "unauthorized", "the X-API-Key is wrong", field="X-API-Key")
    return None


async def require_api_key(
    services: ServicesDep,
    x_api_key: Annotated[str | None, Header(description="needed when the server has a key")] = None,
) -> None:
    """The write routes' dependency: it documents the header; `server.api.guard` checks it before the body."""
    problem = api_key_problem(services.settings.api_key, x_api_key)
    if problem is not None:
        raise problem


WriteAccess = Depends(require_api_key)
