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
        "'degraded' when some are damaged (listed in `damaged`): the service still answers"
    )
    version: str
    active_map: str
    damaged: list[str] = Field(
        default_factory=list,
        description="stored files that cannot be read, relative to the data folder (maps/NAME.json, "
        "active_map.json, samples/ID/sample.json, ...): skipped in listings, refused by name (409)",
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
