"""Liveness and metrics, outside the versioned API."""

from __future__ import annotations

from fastapi import APIRouter, Response
from prometheus_client import CONTENT_TYPE_LATEST
from starlette.concurrency import run_in_threadpool

from server.api import VERSION
from server.api.deps import Services, ServicesDep
from server.store import UNAVAILABLE, StoreError
from shared_schemas.api import Health

router = APIRouter(tags=["health"])


@router.get("/healthz", response_model=Health)
async def health(services: ServicesDep) -> Health:
    """200 while the service runs; 'degraded' names the stored files that cannot be read, a shared store
    (Redis) that does not answer, and a data folder whose last write found no room."""
    return await run_in_threadpool(_health, services)


def _health(services: Services) -> Health:
    # Redis away is 'degraded' with a 200, not the maps routes' 503: the process still runs (a liveness probe
    # must not restart it for Redis), and the body says what does not answer
    unavailable = []
    try:
        damaged_maps, active_map = services.maps.damaged(), services.maps.active_name()
    except StoreError as error:
        if error.code != UNAVAILABLE:
            raise
        damaged_maps, active_map = [], services.maps.default_name()
        unavailable.append(f"maps: {error.message}")
    sessions_problem = services.devices.unavailable()
    if sessions_problem is not None:
        unavailable.append(f"device sessions: {sessions_problem}")
    stores = (services.maps, services.profiles, services.samples)
    unavailable += [problem for problem in (store.unwritable() for store in stores) if problem is not None]
    damaged = sorted(damaged_maps + services.profiles.damaged() + services.samples.damaged())
    return Health(
        status="degraded" if damaged or unavailable else "ok",
        version=VERSION,
        active_map=active_map,
        damaged=damaged,
        unavailable=unavailable,
    )


@router.get(
    "/metrics",
    response_class=Response,
    responses={200: {"content": {"text/plain": {}}, "description": "Prometheus text format"}},
)
async def metrics(services: ServicesDep) -> Response:
    return Response(services.metrics.exposition(), media_type=CONTENT_TYPE_LATEST)
