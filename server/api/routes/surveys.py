"""Beacon surveys: stored samples in, a room's map out (`server.survey`, docs/survey.md)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Annotated

from fastapi import APIRouter, Header
from starlette.concurrency import run_in_threadpool

from server.api.deps import Services, ServicesDep, api_key_problem
from server.api.errors import ERROR_RESPONSES, ApiError
from server.api.guard import GuardedRoute
from server.api.routes import DAMAGED_RESPONSES
from server.ingest import decode_frame
from server.outcomes import FrameError
from server.store import StoreError, check_new_map_name
from server.survey.rules import SurveyInputError, SurveyRefused
from server.survey.run import SurveyFrame, check_request, survey
from shared_schemas import BeaconMap, ProfileRef
from shared_schemas.survey import SurveyReport, SurveyRequest

router = APIRouter(prefix="/v1/surveys", tags=["surveys"], responses=ERROR_RESPONSES, route_class=GuardedRoute)


def _sketch(services: Services, request: SurveyRequest) -> BeaconMap:
    if isinstance(request.sketch, BeaconMap):
        return request.sketch
    try:
        return services.maps.get(request.sketch)
    except StoreError as error:
        if error.code == "not_found":
            message = f"no stored map named '{request.sketch}' to take as the sketch"
            raise ApiError(404, "not_found", message, "sketch") from None
        raise


def _frames(services: Services, request: SurveyRequest, deadline_s: float) -> Iterator[SurveyFrame]:
    """Each sample's frame, read from the store when the survey asks for it (one image held at a time); an
    unknown or unreadable one names its place in the request. Past `deadline_s` (`time.monotonic()`) the
    survey is stopped before its next frame."""
    limit_s = services.settings.survey_timeout_s
    for k, sample in enumerate(request.samples):
        field = f"samples.{k}.sample_id"
        if time.monotonic() > deadline_s:
            message = f"the survey took longer than {limit_s:g} s and was stopped at sample {k}: send fewer samples"
            raise ApiError(503, "timeout", message, "samples")
        try:
            info = services.samples.get(sample.sample_id)
            camera = info.meta.camera
            named = camera.profile if isinstance(camera, ProfileRef) else None
            table = services.profiles.table(named)  # a damaged profile the sample names raises, naming its file
            if named is not None and named not in table:
                message = (
                    f"sample '{sample.sample_id}': its camera.profile '{named}' is no device profile on this server "
                    f"(deleted since the sample was stored?); PUT /v1/profiles/{named} again"
                )
                raise ApiError(404, "not_found", message, field)
            frame = decode_frame(services.samples.frame(sample.sample_id), info.meta, table)
        except StoreError as error:
            if error.code == "not_found":
                raise ApiError(404, "not_found", f"no stored sample '{sample.sample_id}'", field) from None
            raise StoreError(error.code, error.message, field) from None
        except FrameError as error:
            raise ApiError(409, "damaged_sample", f"sample '{sample.sample_id}': {error.message}", field) from None
        yield SurveyFrame(sample.sample_id, frame, sample.labels)


def _survey_now(services: Services, request: SurveyRequest) -> SurveyReport:
    deadline_s = time.monotonic() + services.settings.survey_timeout_s
    check_new_map_name(request.name)  # the map is stored (or may be) under it
    sketch = _sketch(services, request)
    try:
        # what the request gets wrong is said before any frame is read
        check_request(sketch, request.anchor, [(s.sample_id, s.labels) for s in request.samples])
        profiles = services.profiles.table()  # a sample's camera may name a stored (calibrated) profile
        report = survey(_frames(services, request, deadline_s), sketch, request.anchor, request.name, profiles=profiles)
    except SurveyInputError as error:
        raise ApiError(422, "invalid_request", error.message, error.field) from None
    except SurveyRefused as error:
        raise ApiError(422, "survey_refused", error.message, "samples") from None
    if request.store:
        services.maps.put(request.name, report.map)
        report = report.model_copy(update={"stored": True})
    return report


@router.post("", response_model=SurveyReport, responses=DAMAGED_RESPONSES)
async def post_survey(
    request: SurveyRequest,
    services: ServicesDep,
    x_api_key: Annotated[str | None, Header(description="needed with `store: true` when the server has a key")] = None,
) -> SurveyReport:
    """Survey the room's panels from stored samples (each sees two or more panels); with `store`, store the map.

    Refused with 422 `survey_refused` (naming the panel) when the samples leave a sketch panel unconnected to
    the anchor or no sample sees two named panels."""
    if request.store:
        problem = api_key_problem(services.settings.api_key, x_api_key)
        if problem is not None:
            raise problem
    # one survey at a time (one more waiting, 503 beyond), apart from the locate pipeline's threads: a survey
    # runs for seconds to a minute
    async with services.survey_slots.slot():
        return await run_in_threadpool(_survey_now, services, request)
