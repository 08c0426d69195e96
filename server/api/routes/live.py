"""The operator page's data: devices live (JSON and server-sent events), their frames' pictures, the status.

The page itself is static (`server.dashboard`); these routes read the live board
(`server.live.LiveBoard`) and the metrics, and change nothing: no API key.
"""

from __future__ import annotations

import json
import time
from collections.abc import AsyncIterator
from typing import Annotated

import anyio
from fastapi import APIRouter, Path, Response
from fastapi.responses import StreamingResponse
from pydantic import BaseModel
from starlette.concurrency import run_in_threadpool

from server.api import VERSION
from server.api.deps import Services, ServicesDep
from server.api.errors import ERROR_RESPONSES, ApiError
from server.api.guard import GuardedRoute
from shared_schemas import FailureReason
from shared_schemas.api import KeptFrameInfo, LiveDevices, Status

router = APIRouter(tags=["live"], responses=ERROR_RESPONSES, route_class=GuardedRoute)

UPDATE_GAP_S = 0.25  # devices events at most 4 a second, however many frames arrive
STATUS_EVERY_S = 2.0  # a status event this often (it is the stream's heartbeat too)
STREAM_S = 300.0  # a stream ends after this long and the browser reconnects: no connection held forever
RETRY_MS = 1000  # how soon the browser reconnects

EVENTS_PATH = "/v1/live/events"
DeviceName = Annotated[str, Path(min_length=1, max_length=128, description="the X-Lumipose-Device of its frames")]


@router.get("/v1/live/devices", response_model=LiveDevices)
async def live_devices(services: ServicesDep) -> LiveDevices:
    """Every device that sent frames with `X-Lumipose-Device` to this worker (the least recently seen are
    forgotten past `--max-devices`), most recent first."""
    return (await run_in_threadpool(services.live.devices))[1]  # many devices: milliseconds, off the event loop


@router.get(
    EVENTS_PATH,
    response_class=StreamingResponse,
    responses={200: {"content": {"text/event-stream": {}}, "description": "server-sent events"}},
)
async def live_events(services: ServicesDep) -> StreamingResponse:
    """Server-sent events: `devices` (LiveDevices: the devices changed since the last event, their tracks'
    new points only; all of them first), at most 4 a second and only on change; `status` (Status) every
    2 s; `bye` before the stream ends (after 5 minutes: the browser's EventSource reconnects)."""
    return StreamingResponse(
        _events(services),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"},  # nginx: pass each event on at once
    )


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
    async with services.pipeline_limiter:  # drawing is CPU work: it takes its turn with the frames
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


def _event(kind: str, data: BaseModel | dict, event_id: int) -> str:
    text = data.model_dump_json() if isinstance(data, BaseModel) else json.dumps(data)
    return f"id: {event_id}\nevent: {kind}\ndata: {text}\n\n"


async def _events(services: Services) -> AsyncIterator[str]:
    board, event_id = services.live, 0
    yield f"retry: {RETRY_MS}\n\n"
    with board.listen() as changed:
        version, first = 0, True
        end = anyio.current_time() + STREAM_S
        next_status = anyio.current_time()
        while anyio.current_time() < end:
            if first or changed.is_set():
                changed.clear()
                version, live = await run_in_threadpool(board.devices, version)
                if first or live.devices:
                    event_id += 1
                    yield _event("devices", live, event_id)
                first = False
                await anyio.sleep(UPDATE_GAP_S)
            if anyio.current_time() >= next_status:
                board.expire_windows()  # a device gone quiet: its rate and shares go to zero on the page
                event_id += 1
                yield _event("status", await run_in_threadpool(service_status, services), event_id)
                next_status = anyio.current_time() + STATUS_EVERY_S
            with anyio.move_on_after(max(0.0, min(next_status, end) - anyio.current_time())):
                await changed.wait()
    yield _event("bye", {"reconnect_ms": RETRY_MS}, event_id + 1)
