"""Run the pipeline for an uploaded frame, off the event loop and within the core budget."""

from __future__ import annotations

from dataclasses import dataclass, replace

from starlette.concurrency import run_in_threadpool

from server.annotate import annotate
from server.api.deps import Services
from server.api.params import LocateQuery
from server.api.upload import FrameUpload
from server.camera import ProfileTable
from server.diagnostics import Diagnostics
from server.ingest import decode_frame
from server.locator import locate
from shared_schemas import BeaconMap, LocateResult, ProfileRef


@dataclass(frozen=True)
class Located:
    result: LocateResult
    map_name: str
    picture: bytes | None = None  # PNG of what the pipeline saw, when asked (`server.annotate`)


def _locate_now(
    services: Services,
    upload: FrameUpload,
    beacon_map: BeaconMap,
    profiles: ProfileTable | None,
    query: LocateQuery,
    device: str | None,
    annotated: bool,
) -> tuple[LocateResult, bytes | None]:
    frame = decode_frame(upload.data, upload.meta, profiles)
    options, diagnostics = query.options, Diagnostics() if annotated else None
    if diagnostics is not None:
        options = replace(options, pipeline=replace(options.pipeline, diagnostics=diagnostics))
    result = locate(frame, beacon_map, options, beacon_id=query.beacon_id, device_id=device, devices=services.devices)
    return result, None if diagnostics is None else annotate(frame, diagnostics, result)


async def locate_upload(
    services: Services,
    upload: FrameUpload,
    map_name: str | None,
    query: LocateQuery,
    device: str | None = None,
    annotated: bool = False,
) -> Located:
    """The result for `upload` in map `map_name` (default: the active map); with a `device`, in its
    session (tracking, ID frames combined) when the map has several beacons; `annotated`: with a
    picture of what the pipeline saw."""
    name = map_name if map_name else await run_in_threadpool(services.maps.active_name)
    beacon_map = await run_in_threadpool(services.maps.get, name)  # reads the data folder: off the event loop
    camera = upload.meta.camera
    # Only a frame naming a profile needs the table (bundled and stored); one naming a damaged stored
    # profile is refused by name (409) rather than as unknown.
    profiles = None
    if isinstance(camera, ProfileRef):
        profiles = await run_in_threadpool(services.profiles.table, camera.profile)
    async with services.pipeline_limiter:
        result, picture = await run_in_threadpool(
            _locate_now, services, upload, beacon_map, profiles, query, device, annotated
        )
    services.metrics.record_result(result)
    return Located(result=result, map_name=name, picture=picture)
