"""Beacon maps: list, get, replace (validated, atomic), delete a stored one, and the active map."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Response
from starlette.concurrency import run_in_threadpool

from server.api.deps import ServicesDep, WriteAccess
from server.api.errors import ERROR_RESPONSES
from server.api.guard import GuardedRoute
from server.api.routes import DAMAGED_RESPONSES
from shared_schemas import BeaconMap, ErrorBody
from shared_schemas.api import ActiveMap, MapSummary

router = APIRouter(prefix="/v1/maps", tags=["maps"], responses=ERROR_RESPONSES, route_class=GuardedRoute)


@router.get("", response_model=list[MapSummary])
async def list_maps(services: ServicesDep) -> list[MapSummary]:
    """Every map that can be read: a damaged stored map is left out (logged, and named by /healthz)."""
    return await run_in_threadpool(services.maps.summaries)


@router.get("/active", response_model=ActiveMap)
async def get_active_map(services: ServicesDep) -> ActiveMap:
    return ActiveMap(name=await run_in_threadpool(services.maps.active_name))


@router.put("/active", response_model=ActiveMap, dependencies=[WriteAccess], responses=DAMAGED_RESPONSES)
async def set_active_map(active: ActiveMap, services: ServicesDep) -> ActiveMap:
    await run_in_threadpool(services.maps.set_active, active.name)
    return active


@router.get("/{name}", response_model=BeaconMap, responses=DAMAGED_RESPONSES)
async def get_map(name: str, services: ServicesDep) -> BeaconMap:
    return await run_in_threadpool(services.maps.get, name)


@router.put("/{name}", response_model=BeaconMap, dependencies=[WriteAccess])
async def put_map(name: str, beacon_map: BeaconMap, services: ServicesDep) -> BeaconMap:
    """Replace (or create) the map `name`; the body's `name` must match."""
    return await run_in_threadpool(services.maps.put, name, beacon_map)


DELETE_RESPONSES: dict[int | str, dict[str, Any]] = {
    409: {
        "model": ErrorBody,
        "description": "`active_map`: activate another map first; `fixed_map`: the bundled or startup map",
    }
}


@router.delete("/{name}", status_code=204, dependencies=[WriteAccess], responses=DELETE_RESPONSES)
async def delete_map(name: str, services: ServicesDep) -> Response:
    """Remove a stored map, also a damaged one; the active map and the bundled or startup map are refused (409)."""
    await run_in_threadpool(services.maps.delete, name)
    return Response(status_code=204)
