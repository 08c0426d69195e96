"""The contract of a beacon survey: frames that each see two or more panels in, a map out.

`lumipose survey` (files) and `POST /v1/surveys` (stored samples) fit every panel's position and
yaw and every frame's pose together, anchored by one panel and levelled by gravity.
"""

from __future__ import annotations

from typing import Final, Literal

from pydantic import ConfigDict, Field, field_validator

from shared_schemas.api import NAME_PATTERN
from shared_schemas.models import BeaconMap, PositionM, Strict, Vec3

SURVEY_SCHEMA: Final = "lumipose.survey/1"
SURVEY_REPORT_SCHEMA: Final = "lumipose.survey-report/1"
# A survey of a room takes tens of frames; the fit's cost grows with them (and a request runs for minutes past
# a few hundred), so the cap leaves room for a large room without letting one request hold the server
MAX_SURVEY_FRAMES: Final = 200


class PanelLabel(Strict):
    """A person's label of a panel on a frame without readable stripes: a pixel inside the panel's image."""

    beacon_id: int = Field(ge=0, le=255)
    x_px: float = Field(ge=0, description="full-frame pixel column inside the panel's image")
    y_px: float = Field(ge=0, description="full-frame pixel row inside the panel's image")


class SurveySample(Strict):
    """A stored sample (`POST /v1/samples`) to survey from, with labels for panels its stripes do not name."""

    sample_id: str
    labels: list[PanelLabel] = Field(default_factory=list)


class SurveyRequest(Strict):
    """`POST /v1/surveys`."""

    schema_: Literal["lumipose.survey/1"] = Field(default=SURVEY_SCHEMA, alias="schema")
    name: str = Field(pattern=NAME_PATTERN, description="name of the map the survey writes")
    sketch: str | BeaconMap = Field(
        description="the room's panels (IDs, shapes, sizes; positions only roughly, or not at all, except the "
        "anchor's): a stored map's name or the map itself"
    )
    anchor: int = Field(ge=0, le=255, description="the panel whose sketch position and yaw fix the map's frame")
    samples: list[SurveySample] = Field(min_length=1, max_length=MAX_SURVEY_FRAMES)
    store: bool = Field(default=False, description="store the surveyed map under `name` (needs write access)")

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)

    @field_validator("samples")
    @classmethod
    def _each_sample_once(cls, samples: list[SurveySample]) -> list[SurveySample]:
        # a repeated frame would count its panels twice and shrink their sigmas by the square root of the repeats
        first: dict[str, int] = {}
        for k, sample in enumerate(samples):
            if sample.sample_id in first:
                raise ValueError(
                    f"samples {first[sample.sample_id]} and {k} are the same sample '{sample.sample_id}': "
                    f"name each sample once"
                )
            first[sample.sample_id] = k
        return samples


class SurveyedBeacon(Strict):
    beacon_id: int = Field(ge=0, le=255)
    center_m: PositionM
    yaw_deg: float
    center_sigma_m: Vec3 = Field(description="1-sigma of the centre along X, Y, Z")
    yaw_sigma_deg: float = Field(ge=0)
    frames: int = Field(ge=0, description="frames that saw the panel")


class SkippedFrame(Strict):
    name: str
    why: str


class SurveyReport(Strict):
    """The surveyed map, every panel's uncertainty, and what was left out."""

    schema_: Literal["lumipose.survey-report/1"] = Field(default=SURVEY_REPORT_SCHEMA, alias="schema")
    map: BeaconMap
    beacons: list[SurveyedBeacon]
    frames_used: int = Field(ge=0)
    skipped: list[SkippedFrame] = Field(default_factory=list)
    rms_px: float = Field(ge=0, description="reprojection RMS of the panels' points over the frames used")
    bearing_deg: float | None = Field(default=None, description="compass bearing of +X (also in `map`)")
    bearing_sigma_deg: float | None = Field(default=None, ge=0)
    stored: bool = Field(default=False, description="the map was stored under its name")

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)
