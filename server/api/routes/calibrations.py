"""Camera calibration: find the board on one photo, or calibrate from views or photos (issue 14).

HTTP only: the work is `server.calibration`'s. Finding a board on one photo runs in a worker thread under
the pipeline limiter, as a locate; a calibration (up to tens of seconds of fitting) takes one of its own
slots (`Services.calibration_slots`: one running, one waiting, 503 beyond) and runs in a child process
stopped at `--calibration-timeout-s` (`server.api.child`), so locates never wait behind it.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Annotated, Any, cast

import pydantic_core
from fastapi import APIRouter, Header, Query, Request
from pydantic import TypeAdapter, ValidationError
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile
from starlette.formparsers import MultiPartException, MultiPartParser

from server.api.child import WorkTimedOut
from server.api.deps import Services, ServicesDep
from server.api.errors import ERROR_RESPONSES, ApiError
from server.api.guard import GuardedRoute
from server.api.params import FRAME_REQUEST_BODY, BoardPixelsDep, PhotosBodyDep, photo_pixel_limit
from server.calibration.board import describe_board, find_board
from server.calibration.photos import PhotoError, UnreadablePhotos, find_views, photo_sizes
from server.calibration.report import CalibrationInputError, calibrate, no_board_report
from shared_schemas import DeviceProfile
from shared_schemas.calibration import (
    MAX_VIEW_NAME,
    MAX_VIEWS,
    BoardSpec,
    BoardView,
    CalibrationReport,
    CalibrationRequest,
)

BOARD_HEADER = "X-Lumipose-Board"
MULTIPART = "multipart/form-data"
JSON = "application/json"

router = APIRouter(
    prefix="/v1/calibrations", tags=["calibrations"], responses=ERROR_RESPONSES, route_class=GuardedRoute
)

BoardHeader = Annotated[str | None, Header(alias=BOARD_HEADER, description="the board spec (lumipose.board/1) as JSON")]
# the JSON request's own rule for the id, for the multipart field
PROFILE_ID: TypeAdapter[str] = TypeAdapter(cast(Any, Annotated[str, CalibrationRequest.model_fields["profile_id"]]))
NameQuery = Annotated[str, Query(max_length=MAX_VIEW_NAME, description="the photo's name in the view")]

CALIBRATION_REQUEST_BODY: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "description": "Views found on the photos (CalibrationRequest, JSON), or the photos themselves: multipart "
        "with a 'board' field (board spec JSON), a 'device' field (a profile id or profile JSON), an optional "
        "'profile_id' field and one 'photos' file per photo (PNG, JPEG or HEIC).",
        "content": {
            JSON: {"schema": {"$ref": "#/components/schemas/CalibrationRequest"}},
            MULTIPART: {
                "schema": {
                    "type": "object",
                    "required": ["board", "device", "photos"],
                    "properties": {
                        "board": {"type": "string", "description": "board spec JSON (lumipose.board/1)"},
                        "device": {"type": "string", "description": "a bundled profile id, or a profile's JSON"},
                        "profile_id": {"type": "string"},
                        "photos": {"type": "array", "items": {"type": "string", "format": "binary"}},
                    },
                }
            },
        },
    }
}


def _invalid(field: str, error: ValidationError | ValueError) -> ApiError:
    if isinstance(error, ValidationError):
        problem = error.errors()[0]
        where = ".".join(str(part) for part in problem["loc"])
        message = f"{field}{'.' + where if where else ''}: {problem['msg']}"
    else:
        message = f"{field}: {error}"
    return ApiError(422, "invalid_request", message, field=field)


def _invalid_body(error: ValidationError) -> ApiError:
    """A JSON body's first problem, named by its place in the body (for example 'views.0.corners_px.3.0')."""
    problem = error.errors()[0]
    field = ".".join(str(part) for part in problem["loc"]) or "body"
    return ApiError(422, "invalid_request", f"{field}: {problem['msg']}", field=field)


def _board(text: str | None, field: str) -> BoardSpec:
    if not text:
        raise ApiError(422, "invalid_request", f"{field}: the board spec (JSON) is missing", field=field)
    try:
        return BoardSpec.model_validate(pydantic_core.from_json(text))
    except ValidationError as error:
        raise _invalid(field, error) from None
    except ValueError as error:
        raise ApiError(422, "invalid_request", f"{field}: not valid JSON: {error}", field=field) from None


def _device(value: str | DeviceProfile, profiles: dict[str, DeviceProfile]) -> DeviceProfile:
    """The datasheet base of a calibration: the profile given, or one the service knows (bundled or stored)."""
    if isinstance(value, DeviceProfile):
        return value
    if value.lstrip().startswith("{"):
        try:
            return DeviceProfile.model_validate_json(value)
        except ValidationError as error:
            raise _invalid("device", error) from None
    profile = profiles.get(value)
    if profile is None:
        known = ", ".join(sorted(profiles))
        raise ApiError(422, "invalid_request", f"device: no device profile '{value}'; known: {known}", field="device")
    return profile


async def _profiles(services: Services) -> dict[str, DeviceProfile]:
    """Bundled and stored profiles (the data folder is read off the event loop)."""
    return await run_in_threadpool(services.profiles.table)


@router.post("/views", response_model=BoardView, openapi_extra=FRAME_REQUEST_BODY)
async def find_view(
    services: ServicesDep, pixels: BoardPixelsDep, board: BoardHeader = None, name: NameQuery = "photo"
) -> BoardView:
    """The board's corners on one photo (a frame upload, as to /v1/locate, or a photo; no camera is needed).

    The app keeps these small views and sends them to `POST /v1/calibrations` instead of the photos.
    422 when the board spec is missing or invalid, or when no board is found.
    """
    spec = _board(board, BOARD_HEADER)
    async with services.pipeline_limiter:
        view = await run_in_threadpool(find_board, pixels, spec, name)
    if view is None:
        raise ApiError(
            422,
            "no_board",
            f"no {describe_board(spec)} found on the photo, as it is, inverted or mirrored "
            "(or too few of its corners): does the board spec match the printed board?",
            field="frame",
        )
    return view


async def _multipart(request: Request, body: bytes) -> tuple[str | None, str | None, str | None, list]:
    async def stream():
        yield body

    try:
        form = await MultiPartParser(request.headers, stream(), max_files=MAX_VIEWS, max_fields=8).parse()
    except MultiPartException as error:
        raise ApiError(400, "bad_multipart", f"the multipart body cannot be read: {error.message}", "body") from None
    fields = {}
    for key in ("board", "device", "profile_id"):
        value = form.get(key)
        fields[key] = (await value.read()).decode("utf-8", "replace") if isinstance(value, UploadFile) else value
    photos = []
    for index, item in enumerate(form.getlist("photos")):
        if not isinstance(item, UploadFile):
            raise ApiError(422, "invalid_request", "photos: each photo must be a file part", field="photos")
        name = item.filename or f"photo {index + 1}"
        if len(name) > MAX_VIEW_NAME:  # it names the photo's view (BoardView.name) and its line in the report
            raise ApiError(
                400,
                "bad_multipart",
                f"photos: part {index + 1}'s file name has {len(name)} characters; at most {MAX_VIEW_NAME}",
                field="photos",
            )
        photos.append((name, await item.read()))
    await form.close()
    return fields["board"], fields["device"], fields["profile_id"], photos


def _calibrate_photos(
    photos: list, spec: BoardSpec, device: DeviceProfile, profile_id: str | None, max_pixels: int
) -> CalibrationReport:
    views, skipped = find_views(photos, spec, max_pixels)
    if not views:
        return no_board_report(skipped)
    report = calibrate(views, spec, device, profile_id)
    return report.model_copy(update={"views": report.views + skipped})


def _in_child(work: Callable[[], CalibrationReport]) -> CalibrationReport | tuple[int, str, str, str]:
    """(In the child process.) The report, or the refused input as (status, code, field, message): plain
    values cross back."""
    try:
        return work()
    except UnreadablePhotos as error:  # as /v1/calibrations/views answers one unreadable photo
        return (400, "bad_frame", "photos", str(error))
    except (CalibrationInputError, PhotoError) as error:
        return (422, "invalid_request", "photos" if isinstance(error, PhotoError) else "views", str(error))


@router.post("", response_model=CalibrationReport, openapi_extra=CALIBRATION_REQUEST_BODY)
async def create_calibration(request: Request, services: ServicesDep, body: PhotosBodyDep) -> CalibrationReport:
    """Calibrate a camera: 200 with the report, `ok: true` and the calibrated `profile` when the set passes,
    `ok: false` with `advice` (what to shoot next) when it does not. 422 for bad input (views of
    different sizes, a board spec the views do not fit, an unknown device, no readable photo).
    503 `busy` while one calibration runs and another waits; 503 `timeout` past `--calibration-timeout-s`."""
    content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if content_type not in (JSON, MULTIPART):
        raise ApiError(
            415,
            "unsupported_media_type",
            f"Content-Type '{content_type or '(none)'}' is not accepted; "
            f"send {JSON} (CalibrationRequest) or {MULTIPART} (photos)",
            field="Content-Type",
        )
    async with services.calibration_slots.slot():  # before the body is parsed: a refused one costs nothing more
        work = await _work(request, services, body, content_type)
        try:
            answer = await run_in_threadpool(services.calibrator.run, _in_child, work)
        except WorkTimedOut:
            limit_s = services.calibrator.limit_s
            message = f"the calibration took longer than {limit_s:g} s and was stopped: send fewer views or photos"
            raise ApiError(503, "timeout", message, field="views") from None
    if isinstance(answer, tuple):
        status, code, field, message = answer
        raise ApiError(status, code, message, field=field)
    return answer


async def _work(request: Request, services: Services, body: bytes, content_type: str) -> Callable[[], Any]:
    """The calibration the body asks for, checked, ready to run."""
    if content_type == JSON:
        try:
            # up to 64 MB of views: parsed off the event loop
            calibration = await run_in_threadpool(CalibrationRequest.model_validate_json, body)
        except ValidationError as error:
            raise _invalid_body(error) from None
        spec, device = calibration.board, _device(calibration.device, await _profiles(services))
        return partial(calibrate, calibration.views, spec, device, calibration.profile_id)
    board, device_text, profile_id, photos = await _multipart(request, body)
    spec = _board(board, "board")
    if not device_text:
        raise ApiError(422, "invalid_request", "device: a profile id or profile JSON is needed", field="device")
    if not photos:
        raise ApiError(422, "invalid_request", "photos: no photo was sent", field="photos")
    if profile_id is not None:
        try:
            PROFILE_ID.validate_python(profile_id)
        except ValidationError as error:
            raise _invalid("profile_id", error) from None
    device = _device(device_text, await _profiles(services))
    limit = photo_pixel_limit(services)
    try:  # the headers first, here: a body of huge or broken photos costs no child process
        await run_in_threadpool(photo_sizes, photos, limit)
    except UnreadablePhotos as error:
        raise ApiError(400, "bad_frame", str(error), field="photos") from None
    except PhotoError as error:
        raise ApiError(422, "invalid_request", str(error), field="photos") from None
    return partial(_calibrate_photos, photos, spec, device, profile_id, limit)
