"""Device profiles: the bundled ones (read-only) and stored ones (calibrated: put, get, delete)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Response
from starlette.concurrency import run_in_threadpool

from server.api.deps import ServicesDep, WriteAccess
from server.api.errors import ERROR_RESPONSES
from server.api.guard import GuardedRoute
from server.api.routes import DAMAGED_RESPONSES
from shared_schemas import DeviceProfile, ErrorBody
from shared_schemas.api import ProfileSummary

router = APIRouter(prefix="/v1/profiles", tags=["profiles"], responses=ERROR_RESPONSES, route_class=GuardedRoute)

BUNDLED_RESPONSES: dict[int | str, dict[str, Any]] = {
    409: {"model": ErrorBody, "description": "`bundled_profile`: a bundled profile is never replaced or deleted"}
}


@router.get("", response_model=list[ProfileSummary])
async def list_profiles(services: ServicesDep) -> list[ProfileSummary]:
    """Bundled and stored profiles (`source`); a damaged stored one is left out (named by /healthz)."""
    return await run_in_threadpool(services.profiles.summaries)


@router.get("/{profile_id}", response_model=DeviceProfile, responses=DAMAGED_RESPONSES)
async def get_profile(profile_id: str, services: ServicesDep) -> DeviceProfile:
    return await run_in_threadpool(services.profiles.get, profile_id)


@router.put("/{profile_id}", response_model=DeviceProfile, dependencies=[WriteAccess], responses=BUNDLED_RESPONSES)
async def put_profile(profile_id: str, profile: DeviceProfile, services: ServicesDep) -> DeviceProfile:
    """Store (or replace) the profile `profile_id`, for example a calibrated one; the body's `id` must
    match, and a bundled profile's id is refused (409 `bundled_profile`)."""
    return await run_in_threadpool(services.profiles.put, profile_id, profile)


@router.delete("/{profile_id}", status_code=204, dependencies=[WriteAccess], responses=BUNDLED_RESPONSES)
async def delete_profile(profile_id: str, services: ServicesDep) -> Response:
    """Remove a stored profile, also a damaged one; a bundled one is refused (409 `bundled_profile`)."""
    await run_in_threadpool(services.profiles.delete, profile_id)
    return Response(status_code=204)
