"""POST /v1/locate: one frame in, the contract's result out (a fix, or no fix with its reason)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response

from server.api.deps import ServicesDep
from server.api.errors import ERROR_RESPONSES
from server.api.guard import GuardedRoute, answers_directly
from server.api.locating import locate_upload
from server.api.metrics import REQUEST_START
from server.api.params import (
    FRAME_REQUEST_BODY,
    DeviceHeader,
    MapQuery,
    QueryDep,
    UploadDep,
    read_frame_upload,
    read_locate_query,
    read_params,
)
from server.api.routes import DAMAGED_RESPONSES
from shared_schemas import LocateResult
from shared_schemas.api import RESULT_HEADER, result_header

router = APIRouter(prefix="/v1", tags=["locate"], responses=ERROR_RESPONSES, route_class=GuardedRoute)

AnnotateQuery = Annotated[
    bool,
    Query(description=f"answer with a PNG of what the pipeline saw, the result in the {RESULT_HEADER} header"),
]
PICTURE_RESPONSE: dict[int | str, dict[str, Any]] = {
    200: {
        "description": f"the result; with `annotate=1` a PNG, the result (compact JSON) in {RESULT_HEADER}",
        "content": {"image/png": {"schema": {"type": "string", "format": "binary"}}},
        "headers": {RESULT_HEADER: {"description": "with annotate=1: the result", "schema": {"type": "string"}}},
    }
}


@router.post(
    "/locate",
    response_model=LocateResult,
    openapi_extra=FRAME_REQUEST_BODY,
    responses={**DAMAGED_RESPONSES, **PICTURE_RESPONSE},
)
async def locate_frame(
    request: Request,
    services: ServicesDep,
    upload: UploadDep,
    query: QueryDep,
    device: DeviceHeader = None,
    map: MapQuery = None,
    annotate: AnnotateQuery = False,
) -> Response:
    """Locate the camera. 200 with `ok: false` and a `reason` when the frame holds no usable beacon.

    With `X-Lumipose-Device` on a map of several beacons, the frame joins the device's session:
    ID frames (`frame_kind: id`) wait for its next pose frame (reason `id_frame`), and pose frames
    get beacon IDs from them and from the track, and a motion-filtered `track` (docs/vlc.md).
    With `annotate=1` the answer is a PNG of what the pipeline saw (panel, contour, sides, corners,
    centre, the result or the refusal) and the result travels in the `X-Lumipose-Result` header.
    """
    device = device.strip() if device else None  # a blank header names no device
    started = getattr(request.state, REQUEST_START, None)
    located = await locate_upload(services, upload, map, query, device, annotated=annotate, started=started)
    if located.picture is not None:
        return Response(located.picture, media_type="image/png", headers={RESULT_HEADER: result_header(located.result)})
    # The result is a LocateResult already: as `response_model` FastAPI would validate it again, dump it and
    # encode that with `json` (~0.15 ms of the event loop's, ten times pydantic's own JSON).
    return Response(located.result.model_dump_json(by_alias=True), media_type="application/json")


async def locate_directly(request: Request) -> Response:
    """`locate_frame` with its parameters read directly, in FastAPI's order (`server.api.params.RequestParam`):
    the frame's (its body received once they are valid), the pipeline's, the route's own."""
    services = request.app.state.services
    upload = await read_frame_upload(request, services)
    query = read_locate_query(request, services)
    return await locate_frame(request, services, upload, query, **read_params(locate_frame, request))


answers_directly(locate_frame, locate_directly)
