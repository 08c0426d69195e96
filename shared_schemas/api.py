"""Models of the HTTP API beyond the contract's frame, map and result: samples, maps, profiles, health.

The service (`server/api/`) answers with these and the Python client (`lumipose_client`)
reads them; `shared_schemas/openapi.json` is exported from the app that uses them.
"""

from __future__ import annotations

import json
import re
from datetime import datetime
from typing import Final

from pydantic import BaseModel, ConfigDict, Field

from shared_schemas.models import Facing, FrameMeta, LocateResult, Vec3

NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$"
# `POST /v1/locate?annotate=1` answers with a PNG and the result in this header (compact JSON, ASCII:
# non-ASCII characters escaped); 1-3 KB, within every hop's limit for a response's head (httpx/h11:
# 16 KB; the bundled nginx: proxy_buffer_size 16k)
RESULT_HEADER: Final = "X-Lumipose-Result"
CELL_LABEL = re.compile(r"^\s*(-?\d+)\s*,\s*(-?\d+)\s*$")


class Health(BaseModel):
    status: str = Field(
        description="'ok' when the service can locate frames and its stored files are whole; "
        "'degraded' when some are damaged (listed in `damaged`) or a shared store does not answer "
        "(named in `unavailable`): the service still answers"
    )
    version: str
    active_map: str
    damaged: list[str] = Field(
        default_factory=list,
        description="stored files that cannot be read, relative to the data folder (maps/NAME.json, "
        "active_map.json, samples/ID/sample.json, ...): skipped in listings, refused by name (409)",
    )
    unavailable: list[str] = Field(
        default_factory=list,
        description="shared stores that do not answer, each with the reason (Redis, with `serve --redis`: 'maps: ...', "
        "'device sessions: ...'); until it is back the routes that read maps answer 503 `redis_unavailable` "
        "(`active_map` is then the default map's name), and frames in a device's session 503; and a data folder "
        "whose last map, profile or sample write found no room ('data folder DIR: no room to write ...'; those "
        "writes answer 507 `insufficient_storage` until one succeeds)",
    )


class MapSummary(BaseModel):
    name: str
    beacons: int
    active: bool
    source: str = Field(description="'bundled', 'startup' (the --map file) or 'stored' (data folder)")


class ProfileSummary(BaseModel):
    """A device profile in `GET /v1/profiles`; `GET /v1/profiles/{id}` gives the whole profile."""

    id: str = Field(description="what a frame's `camera.profile` names")
    name: str
    facing: Facing
    width: int = Field(description="the profile's image width, pixels (native, or the calibration photos')")
    height: int = Field(description="the profile's image height, pixels")
    calibrated: bool = Field(description="it carries a calibration's measured `intrinsics` (else the datasheet's)")
    source: str = Field(description="'bundled' (shipped with the service, read-only) or 'stored' (data folder)")


class ActiveMap(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = Field(pattern=NAME_PATTERN)


class SampleInfo(BaseModel):
    """A stored frame with its label and the result it gave when it was stored."""

    id: str
    label: str | None = Field(default=None, description="free text; 'i,j' names a test-bench grid cell")
    created: datetime
    device: str | None = None
    map: str = Field(description="the map the frame was located in when stored")
    frame_bytes: int
    meta: FrameMeta
    result: LocateResult


class SampleList(BaseModel):
    samples: list[SampleInfo]


class EvaluationRow(BaseModel):
    id: str
    label: str | None
    ok: bool
    reason: str | None = None
    truth_m: Vec3 | None = Field(default=None, description="from ground_truth, or the label's grid cell")
    position_m: Vec3 | None = None
    error_2d_mm: float | None = None


class Evaluation(BaseModel):
    """The paper's Table 2 from stored samples: error statistics and coverage."""

    map: str
    samples: int
    with_truth: int
    fixes: int
    coverage: float = Field(description="fixes / samples")
    mean_mm: float | None = None
    std_mm: float | None = None
    min_mm: float | None = None
    max_mm: float | None = None
    rows: list[EvaluationRow]


class DeviceLive(BaseModel):
    """One device as the operator's page shows it live (`GET /v1/live/devices`, the `devices` event)."""

    device: str
    map: str = Field(description="the map its last frame was located in")
    last_seen_s: float = Field(description="unix time of its last frame")
    frames: int = Field(description="pose frames since it first came (a device is forgotten only to make room)")
    id_frames: int = Field(description="ID frames kept for its pose frames")
    fixes: int
    fix_rate_hz: float = Field(description="fixes per second over the last `window_s`")
    refused: dict[str, float] = Field(
        description="reason -> share of the pose frames of the last `window_s` refused for it (0-1)"
    )
    last_latency_ms: float | None = Field(description="its last pose frame: from the request's start to its answer")
    last: LocateResult | None = Field(description="the result of its last pose frame")
    track: list[tuple[float, float, float, float]] = Field(
        description="t (unix s), x, y, z (m) of its recent fixes, filtered when tracked; oldest first"
    )
    frames_kept: list[int] = Field(description="seq of the pictures kept of its last pose frames, newest last")


class LiveDevices(BaseModel):
    time_s: float = Field(description="the server's unix time")
    window_s: float = Field(description="the window of fix_rate_hz and refused")
    devices: list[DeviceLive] = Field(description="most recently seen first")


class KeptFrameInfo(BaseModel):
    """A device's pose frame whose picture the service keeps (`GET /v1/live/devices/{device}/frames`)."""

    seq: int
    time_s: float
    map: str
    result: LocateResult
    window_px: tuple[int, int, int, int] = Field(description="x0, y0, x1, y1: the frame pixels the picture enlarges")


class RouteStatus(BaseModel):
    route: str = Field(description="the route's path template, e.g. /v1/locate")
    requests: int = Field(description="since the service started")
    errors: int = Field(description="answers 5xx since the service started")
    rate_hz: float = Field(description="requests per second over the status window")
    p50_ms: float | None = Field(description="latency quantiles over the status window (from histogram buckets)")
    p90_ms: float | None
    p99_ms: float | None


class Status(BaseModel):
    """The service at a glance (`GET /v1/status`, the page's Health view), from the metrics it keeps."""

    version: str
    started_s: float = Field(description="unix time the worker started")
    uptime_s: float
    active_map: str
    devices: int = Field(description="devices on the live board")
    fixes: int = Field(description="frames located since the start")
    id_frames: int = Field(description="ID frames kept for their devices' pose frames since the start")
    refused: dict[str, int] = Field(description="frames without a fix since the start, by reason (ID frames apart)")
    window_s: float = Field(
        description="the window of the rates and quantiles: the last minute, longer after a quiet spell (the counters "
        "are sampled when the status is asked), or since the start"
    )
    routes: list[RouteStatus]


# The label of a sample stored to be surveyed from (the app's survey: `survey:<map name>:<n>`): a photo of
# several panels from anywhere, with no truth of its own, which the evaluation leaves out
SURVEY_LABEL_PREFIX: Final = "survey:"


def is_survey_label(label: str | None) -> bool:
    return label is not None and label.startswith(SURVEY_LABEL_PREFIX)


def cell_label(i: int, j: int) -> str:
    """The label of grid cell (i, j): 'i,j', as `cell_truth_m` reads it (e.g. '-8,11')."""
    return f"{i},{j}"


def cell_truth_m(label: str | None, cell_m: float, height_m: float = 0.0) -> list[float] | None:
    """The test-bench position of a grid-cell label 'i,j' (paper Section II-B), or None."""
    match = CELL_LABEL.match(label or "")
    if match is None:
        return None
    return [int(match[1]) * cell_m, int(match[2]) * cell_m, height_m]


def result_header(result: LocateResult) -> str:
    """`result` as the value of `RESULT_HEADER`."""
    return json.dumps(result.model_dump(mode="json", by_alias=True, exclude_none=True), separators=(",", ":"))


def result_from_header(value: str) -> LocateResult:
    """The result a `RESULT_HEADER` value holds (raises pydantic's ValidationError when it holds none)."""
    return LocateResult.model_validate_json(value)
