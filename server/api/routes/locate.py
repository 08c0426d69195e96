"""POST /v1/locate: one frame in, the contract's result out (a fix, or no fix with its reason)."""

from __future__ import annotations

from fastapi import APIRouter

from server.api.deps import ServicesDep
from server.api.errors import ERROR_RESPONSES
from server.api.guard import GuardedRoute
from server.api.locating import locate_upload
from server.api.params import FRAME_REQUEST_BODY, DeviceHeader, MapQuery, QueryDep, UploadDep
from server.api.routes import DAMAGED_RESPONSES
from shared_schemas import LocateResult

router = APIRouter(prefix="/v1", tags=["locate"], responses=ERROR_RESPONSES, route_class=GuardedRoute)


@router.post("/locate", response_model=LocateResult, openapi_extra=FRAME_REQUEST_BODY, responses=DAMAGED_RESPONSES)
async def locate_frame(
    services: ServicesDep, upload: UploadDep, query: QueryDep, device: DeviceHeader = None, map: MapQuery = None
) -> LocateResult:
    """Locate the camera. 200 with `ok: false` and a `reason` when the frame holds no usable beacon.

    With `X-Lumipose-Device` on a map of several beacons, the frame joins the device's session:
    ID frames (`frame_kind: id`) wait for its next pose frame (reason `id_frame`), and pose frames
    get beacon IDs from them and from the track, and a motion-filtered `track` (docs/vlc.md).
    """
    located = await locate_upload(services, upload, map, query, device)
    return located.result
