"""Write frames as the contract's fixtures: NAME.y (raw Y8) + NAME.json."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from shared_schemas import CameraIntrinsics, FrameMeta, GroundTruth
from simulator.render import CameraPose


def fixture_meta(camera: CameraIntrinsics, width: int, height: int, pose: CameraPose,
                 gravity_camera: list[float] | None = None, **extra) -> FrameMeta:
    """Frame metadata with ground truth, as the simulator records it (10 ms at ISO 100)."""
    return FrameMeta(
        width=width, height=height, row_stride=width, camera=camera, exposure_s=0.01, iso=100,
        gravity_camera=gravity_camera,
        ground_truth=GroundTruth(position_m=list(map(float, pose.position_m)),
                                 rotation_wc=np.asarray(pose.rotation_wc, dtype=float).tolist()),
        **extra,
    )


def write_fixture(stem: Path | str, image: np.ndarray, meta: FrameMeta) -> tuple[Path, Path]:
    """Write `image` (height, width) uint8 padded to `meta.stride`; returns both paths."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    padded = np.zeros((meta.height, meta.stride), np.uint8)
    padded[:, : meta.width] = image
    raw, text = stem.with_suffix(".y"), stem.with_suffix(".json")
    raw.write_bytes(padded.tobytes())
    text.write_text(meta.model_dump_json(by_alias=True, exclude_none=True, indent=2) + "\n")
    return raw, text
