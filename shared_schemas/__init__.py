"""The Lumipose contract as pydantic models, with the bundled device profiles and demo map."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from shared_schemas.models import (
    Beacon,
    BeaconIdSource,
    BeaconMap,
    CameraIntrinsics,
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
DEMO_MAP_NAME = "test-bench"  # the name inside DEMO_MAP_PATH: what `--map` defaults to


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


@cache
def bundled_maps() -> dict[str, Path]:
    """The bundled maps' files, by map name (the demo map is 'test-bench')."""
    return {load_map(path).name: path for path in sorted((PACKAGE_DIR / "maps").glob("*.json"))}


def find_map_file(value: str | Path, data_dir: Path | None = None) -> Path:
    """The map file a `--map` value means: the file at `value` if there is one, else the map named
    `value` stored in `data_dir` (DATA/maps/NAME.json, as the service stores it), else the bundled
    map of that name. A ValueError naming both readings when neither exists."""
    if Path(value).is_file():
        return Path(value)
    name = str(value)
    stored = {} if data_dir is None else {path.stem: path for path in sorted((data_dir / "maps").glob("*.json"))}
    known = {**bundled_maps(), **stored}  # a stored map hides the bundled one of its name, as in the service
    if name in known:
        return known[name]
    where = f"stored in {data_dir / 'maps'} or bundled" if data_dir is not None else "bundled"
    raise ValueError(f"no map file '{name}', and no map named '{name}' {where} (maps: {', '.join(sorted(known))})")


__all__ = [
    "Beacon",
    "BeaconIdSource",
    "BeaconMap",
    "CameraIntrinsics",
    "Crop",
    "DEMO_MAP_NAME",
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
    "bundled_maps",
    "device_profiles",
    "find_map_file",
    "load_map",
]
