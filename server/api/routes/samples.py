"""Recorded samples: store a frame with its label, list, fetch, delete, and evaluate the set."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Response
from starlette.concurrency import run_in_threadpool

from server.api.deps import ServicesDep, WriteAccess
from server.api.errors import ERROR_RESPONSES
from server.api.guard import GuardedRoute
from server.api.locating import locate_upload
from server.api.params import FRAME_REQUEST_BODY, DeviceHeader, LocateQuery, MapQuery, QueryDep, UploadDep
from server.api.routes import DAMAGED_RESPONSES
from server.api.upload import FRAME_HEADER, FrameUpload
from server.evaluation import evaluate
from server.outcomes import FrameError
from server.store import StoreError
from shared_schemas import LocateResult
from shared_schemas.api import Evaluation, SampleInfo, SampleList, is_survey_label

router = APIRouter(prefix="/v1/samples", tags=["samples"], responses=ERROR_RESPONSES, route_class=GuardedRoute)

LabelQuery = Annotated[str | None, Query(max_length=200, description="free text; 'i,j' names a grid cell")]


@router.post(
    "",
    status_code=201,
    response_model=SampleInfo,
    openapi_extra=FRAME_REQUEST_BODY,
    dependencies=[WriteAccess],
    responses=DAMAGED_RESPONSES,
)
async def store_sample(
    services: ServicesDep,
    upload: UploadDep,
    query: QueryDep,
    device: DeviceHeader = None,
    label: LabelQuery = None,
    map: MapQuery = None,
) -> SampleInfo:
    """Store a frame with its label and the result it gives now (a frame without a fix is kept too)."""
    located = await locate_upload(services, upload, map, query)
    return await run_in_threadpool(
        services.samples.add,
        upload.data,
        upload.meta,
        located.result,
        label=label,
        device=device,
        map_name=located.map_name,
    )


@router.get("", response_model=SampleList)
async def list_samples(services: ServicesDep) -> SampleList:
    """Every whole sample: a damaged one is left out (logged, and named by /healthz)."""
    return SampleList(samples=await run_in_threadpool(services.samples.all))


@router.get("/evaluation", response_model=Evaluation, responses=DAMAGED_RESPONSES)
async def evaluate_samples(
    services: ServicesDep,
    map: MapQuery = None,
    cell_m: Annotated[float, Query(gt=0, le=10, description="grid cell side")] = 0.05,
    height_m: Annotated[float, Query(ge=-100, le=100, description="z of the grid plane")] = 0.0,
) -> Evaluation:
    """Re-locate every stored sample in `map` and compare with its truth (paper Table 2).

    Damaged samples are left out, and so is one deleted or damaged while this runs; one whose
    camera names a stored profile deleted or damaged since is a row without a fix (`bad_frame`,
    `damaged_profile`)."""
    name: str = map if map else (await run_in_threadpool(services.maps.active))[0]  # name and map read as one
    await run_in_threadpool(services.maps.get, name)
    located: list[tuple[SampleInfo, LocateResult | str]] = []
    for sample in await run_in_threadpool(services.samples.all):
        if is_survey_label(sample.label):  # survey photos: no truth, and not what a phone sees when it locates
            continue
        try:
            data = await run_in_threadpool(services.samples.frame, sample.id)
        except StoreError:
            continue
        upload = FrameUpload(meta=sample.meta, data=data)
        try:
            result: LocateResult | str = (
                await locate_upload(services, upload, name, LocateQuery(services.options))
            ).result
        except FrameError:
            result = "bad_frame"
        except StoreError as error:
            if error.code != "damaged_profile":
                raise
            result = error.code
        located.append((sample, result))
    return evaluate(name, located, cell_m, height_m)


@router.get("/{sample_id}", response_model=SampleInfo, responses=DAMAGED_RESPONSES)
async def get_sample(sample_id: str, services: ServicesDep) -> SampleInfo:
    return await run_in_threadpool(services.samples.get, sample_id)


@router.get(
    "/{sample_id}/frame",
    response_class=Response,
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": f"frame bytes; metadata in {FRAME_HEADER}"},
        **DAMAGED_RESPONSES,
    },
)
async def get_sample_frame(sample_id: str, services: ServicesDep) -> Response:
    info = await run_in_threadpool(services.samples.get, sample_id)
    data = await run_in_threadpool(services.samples.frame, sample_id)
    return Response(
        data,
        media_type="application/octet-stream",
        headers={FRAME_HEADER: info.meta.model_dump_json(by_alias=True, exclude_none=True)},
    )


@router.delete("/{sample_id}", status_code=204, dependencies=[WriteAccess])
async def delete_sample(sample_id: str, services: ServicesDep) -> Response:
    """Remove the sample, also a damaged one."""
    await run_in_threadpool(services.samples.delete, sample_id)
    return Response(status_code=204)
