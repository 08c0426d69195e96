"""The operator page's data: devices live (JSON and server-sent events), their frames' pictures, the status.

The page itself is static (`server.dashboard`); these routes read the live board
(`server.live.LiveBoard`) and the metrics, and change nothing: no API key.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator
from typing import Annotated

import anyio
from fastapi import APIRouter, Path, Response
from fastapi.responses import StreamingResponse
from pydantic import BaseModel
from starlette.concurrency import run_in_threadpool
from starlette.types import Receive, Scope, Send

from server.api import VERSION
from server.api.deps import Services, ServicesDep
from server.api.errors import ERROR_RESPONSES, ApiError
from server.api.guard import GuardedRoute
from server.live import BoardFull, Listener, LiveBoard
from shared_schemas import FailureReason
from shared_schemas.api import KeptFrameInfo, LiveDevices, Status

router = APIRouter(tags=["live"], responses=ERROR_RESPONSES, route_class=GuardedRoute)

UPDATE_GAP_S = 0.25  # devices events at most 4 a second, however many frames arrive
STATUS_EVERY_S = 2.0  # a status event this often (it is the stream's heartbeat too)
STREAM_S = 300.0  # a stream ends after this long and the browser reconnects: no connection held forever
RETRY_MS = 1000  # how soon the browser reconnects

EVENTS_PATH = "/v1/live/events"
DeviceName = Annotated[str, Path(min_length=1, max_length=128, description="the X-Lumipose-Device of its frames")]


async def _shared_json(services: Services, since_version: int) -> tuple[int, bytes | None]:
    """The board's shared JSON (`LiveBoard.shared_json`), built off the event loop on the live board's own
    thread: however many streams and pages ask, they hold one thread of the pool, and /healthz finds one."""
    return await anyio.to_thread.run_sync(services.live.shared_json, since_version, limiter=services.live_limiter)


@router.get("/v1/live/devices", response_model=LiveDevices)
async def live_devices(services: ServicesDep) -> Response:
    """Every device that sent frames with `X-Lumipose-Device` to this worker (the least recently seen are
    forgotten past `--max-devices`), most recent first."""
    _, data = await _shared_json(services, 0)
    return Response(data, media_type="application/json")


@router.get(
    EVENTS_PATH,
    response_class=StreamingResponse,
    responses={200: {"content": {"text/event-stream": {}}, "description": "server-sent events"}},
)
async def live_events(services: ServicesDep) -> StreamingResponse:
    """Server-sent events: `devices` (LiveDevices: the devices changed since the last event, their tracks'
    new points only; all of them first), at most 4 a second and only on change; `status` (Status) every
    2 s; `bye` before the stream ends (after 5 minutes: the browser's EventSource reconnects).
    503 `busy` when `--max-event-streams` streams are open already."""
    try:
        listener = services.live.add_listener()  # taken now, so no more streams open than the limit
    except BoardFull as full:
        error = ApiError(503, "busy", f"{full}; try again later", field=None)
        error.headers["Retry-After"] = str(RETRY_MS // 1000 * 10)
        raise error from None
    return _EventStream(
        services.live,
        listener,
        _events(services, listener.changed),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"},  # nginx: pass each event on at once
    )


class _EventStream(StreamingResponse):
    """A stream that gives its listener back when it ends, however it ends (also if it never started)."""

    def __init__(self, board: LiveBoard, listener: Listener, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._board, self._listener = board, listener

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await super().__call__(scope, receive, send)
        finally:
            self._board.remove_listener(self._listener)


@router.get("/v1/live/devices/{device:path}/frames", response_model=list[KeptFrameInfo])
async def kept_frames(device: DeviceName, services: ServicesDep) -> list[KeptFrameInfo]:
    """The device's last pose frames whose pictures are kept (newest first): results and the windows shown."""
    kept = services.live.kept_frames(device)
    if kept is None:
        raise ApiError(404, "unknown_device", f"no device '{device}' on the live board", field="device")
    return [frame.info() for frame in kept]


@router.get(
    "/v1/live/devices/{device:path}/frames/{seq}.png",
    response_class=Response,
    responses={200: {"content": {"image/png": {}}, "description": "what the pipeline saw (the paper's Fig. 8)"}},
)
async def kept_frame_picture(
    device: DeviceName, seq: Annotated[int, Path(ge=0, description="from `frames_kept`")], services: ServicesDep
) -> Response:
    """The picture of a kept frame: the window around its panels with contour, sides, corners, centre, result."""
    if services.live.kept_frames(device) is None:
        raise ApiError(404, "unknown_device", f"no device '{device}' on the live board", field="device")
    # drawing is CPU work, in slots of its own (503 when full): a flood of pictures never holds up locating
    async with services.picture_slots.slot():
        png = await run_in_threadpool(services.live.picture, device, seq)
    if png is None:
        raise ApiError(404, "unknown_frame", f"frame {seq} of '{device}' is no longer kept", field="seq")
    return Response(png, media_type="image/png", headers={"Cache-Control": "private, max-age=300"})


@router.get("/v1/status", response_model=Status)
async def status(services: ServicesDep) -> Status:
    """Version, uptime, request rates and latency quantiles of this worker (from its metrics)."""
    return await run_in_threadpool(service_status, services)


def service_status(services: Services) -> Status:
    window_s, routes = services.status_window.routes()
    fixes, refused = services.metrics.outcomes()
    id_frames = refused.pop(FailureReason.id_frame.value, 0)  # kept for a pose frame: not refused
    return Status(
        version=VERSION,
        started_s=services.started_s,
        uptime_s=time.time() - services.started_s,
        active_map=services.maps.active_name(),
        devices=len(services.live),
        fixes=fixes,
        id_frames=id_frames,
        refused=refused,
        window_s=window_s,
        routes=routes,
    )


def _event(kind: str, data: BaseModel | dict | bytes, event_id: int) -> bytes:
    if isinstance(data, bytes):  # the board's shared JSON: sent as it is, not copied per stream
        return b"".join((f"id: {event_id}\nevent: {kind}\ndata: ".encode(), data, b"\n\n"))
    text = data.model_dump_json() if isinstance(data, BaseModel) else json.dumps(data)
    return f"id: {event_id}\nevent: {kind}\ndata: {text}\n\n".encode()


async def _events(services: Services, changed: asyncio.Event) -> AsyncIterator[bytes]:
    board, event_id = services.live, 0
    yield f"retry: {RETRY_MS}\n\n".encode()
    version, first = 0, True
    end = anyio.current_time() + STREAM_S
    next_status = anyio.current_time()
    while anyio.current_time() < end:
        if first or changed.is_set():
            changed.clear()
            version, data = await _shared_json(services, version)
            if data is not None:
                event_id += 1
                yield _event("devices", data, event_id)
            first = False
            await anyio.sleep(UPDATE_GAP_S)
        if anyio.current_time() >= next_status:
            board.expire_windows()  # a device gone quiet: its rate and shares go to zero on the page
            event_id += 1
            status = await anyio.to_thread.run_sync(service_status, services, limiter=services.live_limiter)
            yield _event("status", status, event_id)
            next_status = anyio.current_time() + STATUS_EVERY_S
        with anyio.move_on_after(max(0.0, min(next_status, end) - anyio.current_time())):
            await changed.wait()
    yield _event("bye", {"reconnect_ms": RETRY_MS}, event_id + 1)
