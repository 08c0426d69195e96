"""Parameters shared by the routes that take a frame upload (locate, samples)."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from typing import Annotated, Any, get_args, get_origin, get_type_hints

import numpy as np
from fastapi import Depends, Header, Query, Request
from fastapi import params as declared
from fastapi.exceptions import RequestValidationError
from pydantic import TypeAdapter, ValidationError
from starlette.concurrency import run_in_threadpool

from server.api.deps import Services, ServicesDep
from server.api.errors import ApiError
from server.api.upload import FRAME_HEADER, FrameUpload, PhotoUpload, receive_body, receive_frame
from server.options import LocateOptions
from server.pipeline import CornerMethod
from server.pose.solve import GravityMode
from shared_schemas.captures import PHOTO_CAMERA_QUERY

FRAME_REQUEST_BODY = {
    "requestBody": {
        "required": True,
        "description": f"The frame bytes as the contract's fixture file holds them, with the frame JSON in the "
        f"{FRAME_HEADER} header; or multipart with 'meta' and 'frame' parts; or a photo (JPEG, PNG, HEIC) "
        "without frame JSON, its camera from the 'profile' or 'camera' query parameter or its EXIF. "
        "Content-Encoding gzip or zstd is accepted.",
        "content": {
            "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
            "image/png": {"schema": {"type": "string", "format": "binary"}},
            "image/jpeg": {"schema": {"type": "string", "format": "binary"}},
            "image/heic": {"schema": {"type": "string", "format": "binary"}},
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "required": ["meta", "frame"],
                    "properties": {
                        "meta": {"type": "string", "description": "frame JSON (lumipose.frame/1)"},
                        "frame": {"type": "string", "format": "binary"},
                    },
                }
            },
        },
    }
}

FrameHeader = Annotated[str | None, Header(alias=FRAME_HEADER, description="frame JSON (lumipose.frame/1)")]
DeviceHeader = Annotated[
    str | None, Header(alias="X-Lumipose-Device", max_length=128, description="device or session id of the sender")
]
MapQuery = Annotated[str | None, Query(description="map name; default: the active map")]
BeaconQuery = Annotated[int | None, Query(ge=0, le=255, description="the beacon in view, when known otherwise")]
GravityQuery = Annotated[GravityMode, Query(description="use the frame's gravity vector")]
ProfileQuery = Annotated[
    str | None, Query(max_length=128, description="a photo's device profile id (bundled or stored); default: EXIF")
]
CameraQuery = Annotated[
    str | None,
    Query(max_length=400, description="a photo's intrinsics fx,fy,cx,cy[,k1,k2,p1,p2,k3]; wins over profile"),
]
CornersQuery = Annotated[CornerMethod, Query(description="corner method: rounded (default) or the paper's square")]


@dataclass(frozen=True)
class LocateQuery:
    """A request's way of locating: the service's options with the query's choices, and the beacon in view."""

    options: LocateOptions
    beacon_id: int | None = None


async def _locate_query(  # a coroutine: no worker thread for it (server.api.deps)
    services: ServicesDep,
    beacon_id: BeaconQuery = None,
    gravity: GravityQuery = GravityMode.auto,
    corners: CornersQuery = CornerMethod.rounded,
) -> LocateQuery:
    return _query(services, beacon_id, gravity, corners)


def _query(services: Services, beacon_id: int | None, gravity: GravityMode, corners: CornerMethod) -> LocateQuery:
    return LocateQuery(services.options_for(gravity, corners), beacon_id)


async def frame_upload(
    request: Request,
    services: ServicesDep,
    frame_json: FrameHeader = None,
    profile: ProfileQuery = None,
    camera: CameraQuery = None,
) -> FrameUpload:
    settings = services.settings
    upload = await receive_frame(request, frame_json, settings.max_upload_bytes, settings.read_timeout_s)
    if isinstance(upload, PhotoUpload):
        async with services.pipeline_limiter:  # decoding a photo is CPU work like the pipeline's
            return await run_in_threadpool(_photo_frame, services, upload, profile, camera)
    return upload


def photo_pixel_limit(services) -> int:
    """A photo's pixels over HTTP: no more than a Y8 frame of the upload limit holds (max_upload_mb), so a
    small, well-compressed PNG cannot make the service decode a hundred megapixels."""
    return services.settings.max_upload_bytes


def _photo_frame(services, upload: PhotoUpload, profile_id: str | None, camera_text: str | None) -> FrameUpload:
    """A photo as a Y8 frame with the intrinsics `server.camera.photo_camera` chooses (as `lumipose locate PHOTO`);
    the luma plane is passed on as decoded, not copied."""
    from server.camera import parse_camera_arg
    from server.ingest import decode_photo

    try:
        camera = None if camera_text is None else parse_camera_arg(camera_text)
    except ValueError as error:
        message = str(error).replace("--camera", "camera")
        raise ApiError(400, "bad_frame", message, field="camera") from None
    profiles = services.profiles.table(profile_id)
    if profile_id is not None and profile_id not in profiles:
        raise ApiError(
            404,
            "not_found",
            f"unknown device profile '{profile_id}'; known: {', '.join(sorted(profiles))}",
            field="profile",
        )
    profile = None if profile_id is None else profiles[profile_id]
    limit = photo_pixel_limit(services)
    # the query's way to give a camera; `lumipose client` says its flags instead (PHOTO_CAMERA_FLAGS)
    frame, _ = decode_photo(bytes(upload.data), "the photo", profiles, camera, profile, limit, PHOTO_CAMERA_QUERY)
    return FrameUpload(meta=frame.meta, data=frame.pixels.reshape(-1).data, camera_used=frame.camera_used)


async def board_upload(request: Request, services: ServicesDep, frame_json: FrameHeader = None) -> np.ndarray:
    """The luma of a board view's upload: a frame as to /v1/locate, or a photo, which needs no camera (the board
    is found on the pixels alone), turned upright by its EXIF orientation as every photo is."""
    from server.ingest import decode_luma
    from server.photos import PhotoError, read_grey

    settings = services.settings
    upload = await receive_frame(request, frame_json, settings.max_upload_bytes, settings.read_timeout_s)
    if not isinstance(upload, PhotoUpload):
        return decode_luma(upload.data, upload.meta)
    async with services.pipeline_limiter:
        try:
            return await run_in_threadpool(read_grey, bytes(upload.data), "the photo", photo_pixel_limit(services))
        except PhotoError as error:
            raise ApiError(400, "bad_frame", str(error), field=error.field) from None


async def photos_body(request: Request, services: ServicesDep) -> bytes:
    """A body of photos (a calibration's): read here within the upload limit and time, as a frame is."""
    settings = services.settings
    return bytes(await receive_body(request, settings.max_upload_bytes, settings.read_timeout_s))


@dataclass(frozen=True)
class RequestParam:
    """One query or header parameter read as FastAPI reads it (by its alias, with its declared type and
    rules; its default when absent, unchecked; invalid: `RequestValidationError` at the same place, so the
    same 422), without FastAPI's per-request solving of a route's parameters: ~25 us a parameter and more
    a dependency, ~0.4 ms for /v1/locate's nine, a fifth of a window upload's time outside the pipeline."""

    where: str  # "query" or "header"
    alias: str
    default: Any
    adapter: TypeAdapter = field(repr=False)

    def read(self, request: Request) -> Any:
        value = (request.query_params if self.where == "query" else request.headers).get(self.alias)
        if value is None:
            return self.default
        try:
            return self.adapter.validate_python(value)
        except ValidationError as error:
            problem = error.errors(include_url=False)[0]
            raise RequestValidationError([{**problem, "loc": (self.where, self.alias, *problem["loc"])}]) from None


@cache
def declared_params(function: Callable[..., Any]) -> dict[str, RequestParam]:
    """`function`'s query and header parameters as a route or dependency declares them (`Annotated` with
    `Query(...)` or `Header(alias=...)`), by parameter name: the queries, then the headers, as FastAPI
    checks them."""
    hints = get_type_hints(function, include_extras=True)
    found: dict[str, RequestParam] = {}
    for name, parameter in inspect.signature(function).parameters.items():
        hint: Any = hints.get(name)
        if get_origin(hint) is not Annotated:
            continue
        rules = [item for item in get_args(hint)[1:] if isinstance(item, declared.Param)]
        if not rules:
            continue
        where = "header" if isinstance(rules[0], declared.Header) else "query"
        if where == "header" and not rules[0].alias:  # FastAPI's underscores-to-hyphens is not done here
            raise TypeError(f"{function.__name__}: header parameter '{name}' needs its alias")
        found[name] = RequestParam(where, rules[0].alias or name, parameter.default, TypeAdapter(hint))
    return dict(sorted(found.items(), key=lambda item: item[1].where != "query"))


def read_params(function: Callable[..., Any], request: Request) -> dict[str, Any]:
    """The values of `function`'s declared query and header parameters in `request` (the first invalid one
    raises, as FastAPI's first error is the 422's)."""
    return {name: param.read(request) for name, param in declared_params(function).items()}


async def read_frame_upload(request: Request, services: Services) -> FrameUpload:
    """`frame_upload` with its parameters read directly (`RequestParam`): the frame routes' fast path."""
    return await frame_upload(request, services, **read_params(frame_upload, request))


def read_locate_query(request: Request, services: Services) -> LocateQuery:
    return _query(services, **read_params(_locate_query, request))


# Route parameters: the pipeline's query options, and the uploaded frame (read by `frame_upload`
# itself, with its own limits; `server.api.guard` has checked the key and the length before).
QueryDep = Annotated[LocateQuery, Depends(_locate_query)]
UploadDep = Annotated[FrameUpload, Depends(frame_upload)]
BoardPixelsDep = Annotated[np.ndarray, Depends(board_upload)]
PhotosBodyDep = Annotated[bytes, Depends(photos_body)]
