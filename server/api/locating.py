"""Run the pipeline for an uploaded frame, off the event loop and within the core budget."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import anyio.to_thread

from server.annotate import FrameSeen, picture, seen_in
from server.api.deps import Services
from server.api.params import LocateQuery
from server.api.upload import FrameUpload
from server.camera import ProfileTable
from server.diagnostics import Diagnostics
from server.ingest import decode_frame
from server.locator import in_device_session, locate
from shared_schemas import BeaconMap, FailureReason, LocateResult, ProfileRef


@dataclass(frozen=True)
class Located:
    result: LocateResult
    map_name: str
    picture: bytes | None = None  # PNG of what the pipeline saw, when asked (`server.annotate`)


def _stored_inputs(
    services: Services, upload: FrameUpload, map_name: str | None
) -> tuple[str, BeaconMap, ProfileTable | None]:
    """The map's name and map (the active map's read as one), and the profile table when the frame
    names a profile (a damaged stored profile is refused by name, 409, rather than as unknown)."""
    name, beacon_map = (map_name, services.maps.get(map_name)) if map_name else services.maps.active()
    camera = upload.meta.camera
    profiles = services.profiles.table(camera.profile) if isinstance(camera, ProfileRef) else None
    return name, beacon_map, profiles


def _locate_now(
    services: Services,
    upload: FrameUpload,
    beacon_map: BeaconMap,
    profiles: ProfileTable | None,
    query: LocateQuery,
    device: str | None,
    annotated: bool,
) -> tuple[LocateResult, FrameSeen | None, bytes | None]:
    """The result; what a picture of the frame needs, when one is asked for or kept for the web page;
    the picture, when asked for."""
    frame = decode_frame(upload.data, upload.meta, profiles)
    if upload.camera_used is not None:  # a photo: its intrinsics' source, not "the frame's"
        frame = replace(frame, camera_used=upload.camera_used)
    watched = annotated or (device is not None and services.live.keeps_frames)
    options, diagnostics = query.options, Diagnostics() if watched else None
    if diagnostics is not None:
        options = replace(options, pipeline=replace(options.pipeline, diagnostics=diagnostics))
    result = locate(frame, beacon_map, options, beacon_id=query.beacon_id, device_id=device, devices=services.devices)
    if diagnostics is None or (result.reason is FailureReason.id_frame and not annotated):
        return result, None, None  # an ID frame's stripes are not kept for the page: nothing to see
    seen = seen_in(frame, diagnostics, result, in_device_session(beacon_map, query.beacon_id, device))
    return result, seen, picture(seen, result) if annotated else None


async def locate_upload(
    services: Services,
    upload: FrameUpload,
    map_name: str | None,
    query: LocateQuery,
    device: str | None = None,
    annotated: bool = False,
    started: float | None = None,
) -> Located:
    """The result for `upload` in map `map_name` (default: the active map); with a `device`, in its
    session (tracking, ID frames combined) when the map has several beacons, and on the live board
    (`started`: the request's `time.perf_counter()`, for its latency); `annotated`: with a picture
    of what the pipeline saw."""
    # The data folder (or Redis) is read in a hop of its own, outside the pipeline's limiter: an unknown
    # map or profile is answered at once, not after the frames ahead of it, and no pipeline thread
    # waits on the disk.
    name, beacon_map, profiles = await anyio.to_thread.run_sync(_stored_inputs, services, upload, map_name)
    result, seen, drawn = await anyio.to_thread.run_sync(
        _locate_now,
        services,
        upload,
        beacon_map,
        profiles,
        query,
        device,
        annotated,
        limiter=services.pipeline_limiter,
    )
    services.metrics.record_result(result)
    if device is not None:
        latency_ms = None if started is None else 1000 * (time.perf_counter() - started)
        services.live.record(device, name, result, latency_ms, seen)
    return Located(result=result, map_name=name, picture=drawn)
