"""The endpoints are written once (`_Endpoints`); `Client` runs them with httpx.Client and
`AsyncClient` with httpx.AsyncClient, so both always speak the same API."""

from __future__ import annotations

import gzip
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, TypeVar

import httpx
import zstandard
from pydantic import BaseModel, ValidationError

from shared_schemas import BeaconMap, DeviceProfile, ErrorBody, FrameMeta, LocateResult
from shared_schemas.api import (
    RESULT_HEADER,
    ActiveMap,
    Evaluation,
    Health,
    MapSummary,
    ProfileSummary,
    SampleInfo,
    SampleList,
    result_from_header,
)
from shared_schemas.calibration import BoardSpec, BoardView, CalibrationReport, CalibrationRequest
from shared_schemas.fixture_files import read_fixture_files
from shared_schemas.survey import SurveyReport, SurveyRequest

FRAME_HEADER = "X-Lumipose-Frame"
T = TypeVar("T")


class LumiposeError(Exception):
    """The service refused a request; `body` is its ErrorBody (error code, field, message)."""

    def __init__(self, status: int, body: ErrorBody):
        super().__init__(f"HTTP {status} {body.error}: {body.message}")
        self.status, self.body = status, body


@dataclass(frozen=True)
class _Call(Generic[T]):
    method: str
    path: str
    parse: Callable[[httpx.Response], T]
    params: dict[str, Any] = field(default_factory=dict)
    headers: dict[str, str] = field(default_factory=dict)
    content: bytes | None = None
    json: Any = None

    def request_args(self) -> dict[str, Any]:
        params = {name: value for name, value in self.params.items() if value is not None}
        return {
            "method": self.method,
            "url": self.path,
            "params": params,
            "headers": self.headers,
            "content": self.content,
            "json": self.json,
        }


def _raise_for_error(response: httpx.Response) -> None:
    if response.status_code < 400:
        return
    try:
        body = ErrorBody.model_validate_json(response.content)
    except ValidationError:
        body = ErrorBody(error="http_error", message=response.text[:500] or response.reason_phrase)
    raise LumiposeError(response.status_code, body)


def _model(model: type[BaseModel]) -> Callable[[httpx.Response], Any]:
    def parse(response: httpx.Response):
        _raise_for_error(response)
        return model.model_validate_json(response.content)

    return parse


def _models(model: type[BaseModel]) -> Callable[[httpx.Response], list]:
    def parse(response: httpx.Response):
        _raise_for_error(response)
        return [model.model_validate(item) for item in response.json()]

    return parse


def _nothing(response: httpx.Response) -> None:
    _raise_for_error(response)


def _frame(response: httpx.Response) -> tuple[FrameMeta, bytes]:
    _raise_for_error(response)
    return FrameMeta.model_validate_json(response.headers[FRAME_HEADER]), response.content


@dataclass(frozen=True)
class AnnotatedResult:
    """A frame's result and the service's PNG of what its pipeline saw (`locate(..., annotate=True)`)."""

    result: LocateResult
    png: bytes


def _annotated(response: httpx.Response) -> AnnotatedResult:
    _raise_for_error(response)
    return AnnotatedResult(result_from_header(response.headers[RESULT_HEADER]), response.content)


@dataclass(frozen=True)
class EncodedFrame:
    """Frame bytes with their Content-Encoding, encoded once (for example to send the same frame often)."""

    data: bytes
    encoding: str | None


def encode_frame(data: bytes, encoding: str | None = "gzip") -> EncodedFrame:
    """gzip (level 1: fast, most of the gain on a dark luma plane), zstd, or None."""
    if encoding == "gzip":
        return EncodedFrame(gzip.compress(data, compresslevel=1), "gzip")
    if encoding == "zstd":
        return EncodedFrame(zstandard.ZstdCompressor(level=1).compress(data), "zstd")
    if encoding is None:
        return EncodedFrame(bytes(data), None)
    raise ValueError(f"unknown encoding {encoding!r}: use 'gzip', 'zstd' or None")


def _frame_request(meta: FrameMeta, frame: bytes | EncodedFrame, compress: str | None) -> dict[str, Any]:
    encoded = frame if isinstance(frame, EncodedFrame) else encode_frame(frame, compress)
    headers = {
        "Content-Type": "application/octet-stream",
        FRAME_HEADER: meta.model_dump_json(by_alias=True, exclude_none=True),
    }
    if encoded.encoding:
        headers["Content-Encoding"] = encoded.encoding
    return {"headers": headers, "content": encoded.data}


class _Endpoints:
    """Each method returns what `_run` returns: a value (Client) or an awaitable (AsyncClient)."""

    def _run(self, call: _Call):  # pragma: no cover - implemented by the two clients
        raise NotImplementedError

    def health(self):
        return self._run(_Call("GET", "/healthz", _model(Health)))

    def locate(
        self,
        data: bytes | EncodedFrame,
        meta: FrameMeta,
        *,
        map: str | None = None,
        beacon_id: int | None = None,
        gravity: str | None = None,
        compress: str | None = "gzip",
        device: str | None = None,
        annotate: bool = False,
    ):
        """Locate the camera of one frame: LocateResult (ok, or ok=False with a reason).

        `data` is sent with `compress` ('gzip', 'zstd' or None) unless it is already an EncodedFrame.
        With `device`, the frame joins that device's session on the server (ID frames, tracking).
        With `annotate`, an `AnnotatedResult` instead: the result and a PNG of what the pipeline saw.
        """
        params = {"map": map, "beacon_id": beacon_id, "gravity": gravity}
        return self._locate_call(params, device, annotate, **_frame_request(meta, data, compress))

    def calibrate_view(
        self,
        data: bytes | EncodedFrame,
        meta: FrameMeta,
        board: BoardSpec,
        *,
        name: str = "photo",
        compress: str | None = "gzip",
    ):
        """The board's corners on one photo (sent as a frame): a BoardView; 422 when no board is found."""
        request = _frame_request(meta, data, compress)
        request["headers"] |= {"X-Lumipose-Board": board.model_dump_json(by_alias=True)}
        return self._run(_Call("POST", "/v1/calibrations/views", _model(BoardView), params={"name": name}, **request))

    def calibrate(self, request: CalibrationRequest):
        """Calibrate from views: a CalibrationReport (ok with the profile, or ok=False with advice)."""
        body = request.model_dump(mode="json", by_alias=True, exclude_none=True)
        return self._run(_Call("POST", "/v1/calibrations", _model(CalibrationReport), json=body))

    def locate_fixture(self, path: Path | str, **options):
        meta, data = read_fixture_files(path)
        return self.locate(data, meta, **options)

    def locate_photo(
        self,
        data: bytes,
        content_type: str = "image/jpeg",
        *,
        map: str | None = None,
        profile: str | None = None,
        camera: str | None = None,
        beacon_id: int | None = None,
        device: str | None = None,
        annotate: bool = False,
    ):
        """Locate the camera of a phone photo (image/jpeg, image/png or image/heic) sent without frame JSON;
        its camera is the `profile` id (bundled or stored), `camera` 'fx,fy,cx,cy[,k1,...]' (pixels of the
        upright photo), or the photo's EXIF. `device` and `annotate` as for `locate`."""
        params = {"map": map, "profile": profile, "camera": camera, "beacon_id": beacon_id}
        return self._locate_call(params, device, annotate, headers={"Content-Type": content_type}, content=bytes(data))

    def _locate_call(self, params: dict, device: str | None, annotate: bool, **request):
        """POST /v1/locate of a frame or a photo (`request`: its headers and body), in a device's session when
        `device` is given; an AnnotatedResult with `annotate`, else a LocateResult."""
        request["headers"] = request["headers"] | ({"X-Lumipose-Device": device} if device else {})
        parse = _annotated if annotate else _model(LocateResult)
        return self._run(
            _Call("POST", "/v1/locate", parse, params=params | {"annotate": 1 if annotate else None}, **request)
        )

    def maps(self):
        return self._run(_Call("GET", "/v1/maps", _models(MapSummary)))

    def get_map(self, name: str):
        return self._run(_Call("GET", f"/v1/maps/{name}", _model(BeaconMap)))

    def put_map(self, beacon_map: BeaconMap):
        return self._run(
            _Call(
                "PUT",
                f"/v1/maps/{beacon_map.name}",
                _model(BeaconMap),
                json=beacon_map.model_dump(mode="json", by_alias=True),
            )
        )

    def delete_map(self, name: str):
        return self._run(_Call("DELETE", f"/v1/maps/{name}", _nothing))

    def active_map(self):
        return self._run(_Call("GET", "/v1/maps/active", _model(ActiveMap)))

    def set_active_map(self, name: str):
        return self._run(_Call("PUT", "/v1/maps/active", _model(ActiveMap), json={"name": name}))

    def profiles(self):
        """Every device profile the service knows: ProfileSummary (id, size, `calibrated`, `source`)."""
        return self._run(_Call("GET", "/v1/profiles", _models(ProfileSummary)))

    def profile(self, profile_id: str):
        """The DeviceProfile `profile_id`, bundled or stored."""
        return self._run(_Call("GET", f"/v1/profiles/{profile_id}", _model(DeviceProfile)))

    def put_profile(self, profile: DeviceProfile):
        """Store (or replace) `profile` under its own id (a calibrated one); a bundled id is refused."""
        return self._run(
            _Call(
                "PUT",
                f"/v1/profiles/{profile.id}",
                _model(DeviceProfile),
                json=profile.model_dump(mode="json", by_alias=True, exclude_none=True),
            )
        )

    def delete_profile(self, profile_id: str):
        return self._run(_Call("DELETE", f"/v1/profiles/{profile_id}", _nothing))

    def store_sample(
        self,
        data: bytes | EncodedFrame,
        meta: FrameMeta,
        *,
        label: str | None = None,
        device: str | None = None,
        map: str | None = None,
        compress: str | None = "gzip",
    ):
        request = _frame_request(meta, data, compress)
        request["headers"] |= {"X-Lumipose-Device": device} if device else {}
        return self._run(
            _Call("POST", "/v1/samples", _model(SampleInfo), params={"label": label, "map": map}, **request)
        )

    def samples(self):
        return self._run(_Call("GET", "/v1/samples", _model(SampleList)))

    def sample(self, sample_id: str):
        return self._run(_Call("GET", f"/v1/samples/{sample_id}", _model(SampleInfo)))

    def sample_frame(self, sample_id: str):
        """(FrameMeta, frame bytes) of a stored sample."""
        return self._run(_Call("GET", f"/v1/samples/{sample_id}/frame", _frame))

    def delete_sample(self, sample_id: str):
        return self._run(_Call("DELETE", f"/v1/samples/{sample_id}", _nothing))

    def survey(self, request: SurveyRequest):
        """`POST /v1/surveys`: a room's map from stored samples (a `SurveyReport`); `store` needs the API key."""
        return self._run(
            _Call("POST", "/v1/surveys", _model(SurveyReport), json=request.model_dump(mode="json", by_alias=True))
        )

    def evaluate_samples(self, *, map: str | None = None, cell_m: float = 0.05, height_m: float = 0.0):
        return self._run(
            _Call(
                "GET",
                "/v1/samples/evaluation",
                _model(Evaluation),
                params={"map": map, "cell_m": cell_m, "height_m": height_m},
            )
        )


def _auth(api_key: str | None) -> dict[str, str]:
    return {"X-API-Key": api_key} if api_key else {}


class Client(_Endpoints):
    """Synchronous client; use as a context manager or call `close()`."""

    def __init__(
        self,
        base_url: str,
        *,
        api_key: str | None = None,
        timeout_s: float = 30.0,
        transport: httpx.BaseTransport | None = None,
    ):
        self._http = httpx.Client(base_url=base_url, headers=_auth(api_key), timeout=timeout_s, transport=transport)

    def _run(self, call: _Call[T]) -> T:
        return call.parse(self._http.request(**call.request_args()))

    def close(self) -> None:
        self._http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class AsyncClient(_Endpoints):
    """Asynchronous client: the same methods, awaited."""

    def __init__(
        self,
        base_url: str,
        *,
        api_key: str | None = None,
        timeout_s: float = 30.0,
        transport: httpx.AsyncBaseTransport | None = None,
    ):
        self._http = httpx.AsyncClient(
            base_url=base_url, headers=_auth(api_key), timeout=timeout_s, transport=transport
        )

    async def _run(self, call: _Call[T]) -> T:
        return call.parse(await self._http.request(**call.request_args()))

    async def aclose(self) -> None:
        await self._http.aclose()

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc) -> None:
        await self.aclose()
