"""The Lumipose contract as pydantic models, with the bundled device profiles and demo map."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from shared_schemas.models import (
    Beacon,
    BeaconIdSource,
    BeaconMap,
    CameraIntrinsics,
    CameraSource,
    CameraUsed,
    Crop,
    DeviceProfile,
    ErrorBody,
    FailureReason,
    FrameFormat,
    FrameKind,
    FrameMeta,
    GroundTruth,
    LocateResult,
    OrientationRule,
    PanelShape,
    ProfileRef,
    ToneCurve,
    TrackState,
    VlcReading,
)

PACKAGE_DIR = Path(__file__).parent
DEMO_MAP_PATH = PACKAGE_DIR / "maps" / "demo.json"


@cache
def device_profiles() -> dict[str, DeviceProfile]:
    """The bundled device profiles, by id."""
    profiles = (
        DeviceProfile.model_validate_json(path.read_text())
        for path in sorted((PACKAGE_DIR / "profiles").glob("*.json"))
    )
    return {profile.id: profile for profile in profiles}


def load_map(path: Path | str = DEMO_MAP_PATH) -> BeaconMap:
    """Read and validate a beacon map file (the bundled demo map by default)."""
    return BeaconMap.model_validate_json(Path(path).read_text())


__all__ = [
    "Beacon",
    "BeaconIdSource",
    "BeaconMap",
    "CameraIntrinsics",
    "CameraSource",
    "CameraUsed",
    "Crop",
    "DEMO_MAP_PATH",
    "DeviceProfile",
    "ErrorBody",
    "FailureReason",
    "FrameFormat",
    "FrameKind",
    "FrameMeta",
    "GroundTruth",
    "LocateResult",
    "OrientationRule",
    "PanelShape",
    "ProfileRef",
    "ToneCurve",
    "TrackState",
    "VlcReading",
    "device_profiles",
    "load_map",
]
