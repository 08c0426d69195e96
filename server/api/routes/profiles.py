"""Device profiles bundled with the service (read-only)."""

from __future__ import annotations

from fastapi import APIRouter

from server.api.errors import ERROR_RESPONSES, ApiError
from server.api.guard import GuardedRoute
from shared_schemas import DeviceProfile, device_profiles

router = APIRouter(prefix="/v1/profiles", tags=["profiles"], responses=ERROR_RESPONSES, route_class=GuardedRoute)


@router.get("", response_model=list[DeviceProfile])
async def list_profiles() -> list[DeviceProfile]:
    return list(device_profiles().values())


@router.get("/{profile_id}", response_model=DeviceProfile)
async def get_profile(profile_id: str) -> DeviceProfile:
    profile = device_profiles().get(profile_id)
    if profile is None:
        raise ApiError(
            404,
            "not_found",
            f"no device profile '{profile_id}'; known: {', '.join(sorted(device_profiles()))}",
            field="profile_id",
        )
    return profile
