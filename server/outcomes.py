"""What locating a frame can end in, and the one place that turns it into the contract's result.

- `FrameError`: input that cannot be read at all (the API answers 4xx, the CLI exits 2);
- `Refusal`: a readable frame without a fix, with the contract's reason and a sentence;
- `Fix`: a camera pose found in the frame, in the frame's own pixels.

Stages return a `Refusal` or their own typed result; the layers above pass `Fix` records
along (shifting, naming or fusing them with `dataclasses.replace`) and build the contract's
`LocateResult` once, with `located` or `refused`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from server.geometry import ypr_from_rotation
from shared_schemas import (
    BeaconIdSource,
    CameraUsed,
    FailureReason,
    LocateResult,
    OrientationRule,
    TrackState,
    VlcReading,
)
from shared_schemas.models import MAX_MESSAGE_CHARS, MAX_WARNING_CHARS, MAX_WARNINGS

CUT = "..."  # ends a text cut to the contract's length


class FrameError(ValueError):
    """A frame or its metadata that cannot be read; `field` is the dotted field at fault."""

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.message = message
        self.field = field


@dataclass(frozen=True)
class Refusal:
    """Why a frame gave no fix: the contract's reason and a sentence for people (and, from the
    pipeline, what it noticed and how long it took on the way)."""

    reason: FailureReason
    message: str
    warnings: tuple[str, ...] = ()
    timing_ms: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class Fix:
    """A camera pose from one frame.

    `position_m` (3,) is the camera's optical centre in the map frame, `rotation_wc` (3, 3)
    maps camera to map coordinates; `corners_px` (4, 2) in the beacon model's corner order and
    `center_px` (2,) are in the frame's own (distorted) pixels, pixel centres at integers.
    """

    position_m: np.ndarray
    rotation_wc: np.ndarray
    beacon_id: int | None
    id_source: BeaconIdSource | None
    reprojection_error_px: float
    gravity_used: bool
    center_px: np.ndarray | None = None
    corners_px: np.ndarray | None = None
    orientation_rule: OrientationRule | None = None
    ambiguity_ratio: float | None = None
    covariance_m2: np.ndarray | None = None  # (3, 3) of position_m, map frame, from the fit
    growth_px: float | None = None  # how far the panel's mid-level contour lies outside its outline
    # how far the sides' own growths lie from `growth_px` when their blur differs (motion; px, 0 when even):
    # each side was moved in by its own, so `growth_px` put back leaves the corners off by up to this much
    uneven_px: float = 0.0
    from_outline: bool = False  # the outline fit's: its corners are projected from the pose, not measured
    warnings: tuple[str, ...] = ()
    timing_ms: Mapping[str, float] = field(default_factory=dict)

    def shifted(self, offset_px: Sequence[float]) -> Fix:
        """The same fix with its pixels moved by `offset_px` (from a crop back to the full frame)."""
        offset = np.asarray(offset_px, dtype=float)
        return replace(
            self,
            center_px=None if self.center_px is None else self.center_px + offset,
            corners_px=None if self.corners_px is None else self.corners_px + offset,
        )

    def warned(self, *warnings: str) -> Fix:
        return replace(self, warnings=self.warnings + tuple(warnings))


def bounded(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """`text` within `limit` characters: cut, ending in "...", when longer (a result's text quotes input such
    as EXIF strings, which has no length of its own)."""
    return text if len(text) <= limit else text[: limit - len(CUT)] + CUT


def _warnings(warnings: Sequence[str]) -> list[str]:
    return [bounded(text, MAX_WARNING_CHARS) for text in warnings[:MAX_WARNINGS]]


def with_camera(result: LocateResult, camera: CameraUsed | None) -> LocateResult:
    """`result` saying which intrinsics it rests on (`camera.detail` within the contract's length)."""
    if camera is not None and len(camera.detail) > MAX_MESSAGE_CHARS:
        camera = camera.model_copy(update={"detail": bounded(camera.detail)})
    return result.model_copy(update={"camera_used": camera})


def _list(array: np.ndarray | None) -> list | None:
    return None if array is None else np.asarray(array, dtype=float).tolist()


def located(
    fix: Fix, *, vlc: VlcReading | None = None, beacons_in_view: int | None = None, track: TrackState | None = None
) -> LocateResult:
    """The contract's result for a fix."""
    return LocateResult(
        ok=True,
        position_m=_list(fix.position_m),
        rotation_wc=_list(fix.rotation_wc),
        yaw_pitch_roll_deg=list(ypr_from_rotation(np.asarray(fix.rotation_wc))),
        beacon_id=fix.beacon_id,
        beacon_id_source=fix.id_source,
        orientation_rule=fix.orientation_rule,
        corners_px=_list(fix.corners_px),
        center_px=_list(fix.center_px),
        reprojection_error_px=fix.reprojection_error_px,
        ambiguity_ratio=fix.ambiguity_ratio,
        gravity_used=fix.gravity_used,
        position_sigma_m=None if fix.covariance_m2 is None else np.sqrt(np.diag(fix.covariance_m2)).tolist(),
        position_covariance_m2=_list(fix.covariance_m2),
        warnings=_warnings(fix.warnings),
        timing_ms=dict(fix.timing_ms),
        vlc=vlc,
        beacons_in_view=beacons_in_view,
        track=track,
    )


def refused(
    refusal: Refusal,
    *,
    vlc: VlcReading | None = None,
    beacons_in_view: int | None = None,
    track: TrackState | None = None,
) -> LocateResult:
    """The contract's result for a frame without a fix."""
    return LocateResult(
        ok=False,
        reason=refusal.reason,
        message=bounded(refusal.message),
        warnings=_warnings(refusal.warnings),
        timing_ms=dict(refusal.timing_ms),
        vlc=vlc,
        beacons_in_view=beacons_in_view,
        track=track,
    )
