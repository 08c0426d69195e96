"""POST /v1/locate: one frame in, the contract's result out (a fix, or no fix with its reason)."""

from __future__ import annotations

from fastapi import APIRouter, Request

from server.api.deps import ServicesDep
from server.api.locating import locate_upload
from server.api.errors import ERROR_RESPONSES
from server.api.routes.frames import (FRAME_REQUEST_BODY, BeaconQuery, CornersQuery,
                                      DeviceHeader, FrameHeader, GravityQuery, MapQuery, frame_upload,
                                      pipeline_options)
from server.pipeline import CornerMethod
from server.pose.solve import GravityMode
from shared_schemas import LocateResult

router = APIRouter(prefix="/v1", tags=["locate"], responses=ERROR_RESPONSES)


@router.post("/locate", response_model=LocateResult, openapi_extra=FRAME_REQUEST_BODY)
async def locate_frame(request: Request, services: ServicesDep, frame_json: FrameHeader = None,
                       device: DeviceHeader = None, map: MapQuery = None, beacon_id: BeaconQuery = None,
                       gravity: GravityQuery = GravityMode.auto,
                       corners: CornersQuery = CornerMethod.rounded) -> LocateResult:
    """Locate the camera. 200 with `ok: false` and a `reason` when the frame holds no usable beacon.

    With `X-Lumipose-Device` on a map of several beacons, the frame joins the device's session:
    ID frames (`frame_kind: id`) wait for its next pose frame (reason `id_frame`), and pose frames
    get beacon IDs from them and from the track, and a motion-filtered `track` (docs/vlc.md).
    """
    upload = await frame_upload(request, services, frame_json)
    located = await locate_upload(services, upload, map, pipeline_options(beacon_id, gravity, corners), device)
    return located.result
