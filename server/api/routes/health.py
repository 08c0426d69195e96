"""Liveness and metrics, outside the versioned API."""

from __future__ import annotations

from fastapi import APIRouter, Response
from prometheus_client import CONTENT_TYPE_LATEST
from starlette.concurrency import run_in_threadpool

from server.api import VERSION
from server.api.deps import Services, ServicesDep
from shared_schemas.api import Health

router = APIRouter(tags=["health"])


@router.get("/healthz", response_model=Health)
async def health(services: ServicesDep) -> Health:
    """200 while the service runs; 'degraded' names the stored files that cannot be read, and a shared
    store (Redis) that does not answer."""
    return await run_in_threadpool(_health, services)


def _health(services: Services) -> Health:
    damaged = sorted(services.maps.damaged() + services.profiles.damaged() + services.samples.damaged())
    sessions_problem = services.devices.unavailable()
    unavailable = [] if sessions_problem is None else [f"device sessions: {sessions_problem}"]
    return Health(
        status="degraded" if damaged or unavailable else "ok",
        version=VERSION,
        active_map=services.maps.active_name(),
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
