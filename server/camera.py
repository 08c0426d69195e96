"""Camera intrinsics of a frame: given in the frame, or from a device profile scaled to it."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from pydantic import ValidationError

from server.outcomes import FrameError
from shared_schemas import CameraIntrinsics, DeviceProfile, FrameMeta, ProfileRef, device_profiles


def intrinsics_from_profile(profile: DeviceProfile, width: int, height: int) -> CameraIntrinsics:
    """The profile's pinhole at `width` x `height`: its measured `intrinsics`, else the datasheet's (paper eq. 9).

    Another size is the profile's image scaled by s = max(w / W, h / H) and centre-cropped: a
    pixel centre u of the profile's image lands at (u + 1/2) s - 1/2 less the crop's offset. The
    datasheet's principal point is the centre, (w - 1) / 2, (h - 1) / 2.
    """
    scale = max(width / profile.width, height / profile.height)
    measured = profile.intrinsics
    if measured is None:
        fx = fy = profile.focal_length_m / profile.pixel_size_m * scale
        cx, cy = (width - 1) / 2, (height - 1) / 2
    else:
        fx, fy = measured.fx * scale, measured.fy * scale
        cx = (measured.cx + 0.5) * scale - 0.5 - (profile.width * scale - width) / 2
        cy = (measured.cy + 0.5) * scale - 0.5 - (profile.height * scale - height) / 2
    return CameraIntrinsics(
        fx=fx,
        fy=fy,
        cx=cx,
        cy=cy,
        distortion=list(profile.distortion),
        pixel_size_m=profile.pixel_size_m / scale,
        focal_length_m=profile.focal_length_m,
        device=profile.name,
    )


ProfileTable = Mapping[str, DeviceProfile]  # the device profiles a frame's `camera.profile` may name, by id


def profile_table(extra: Iterable[DeviceProfile] = ()) -> dict[str, DeviceProfile]:
    """The bundled profiles and `extra` ones (for example calibrated profile files) by id.

    An extra profile may not take a bundled id, nor another extra one's: a frame naming an id must
    mean one camera (the service's profile store refuses a bundled id too).
    """
    table = dict(device_profiles())
    for profile in extra:
        if profile.id in table:
            taken = "a bundled profile's" if profile.id in device_profiles() else "another given profile's"
            raise ValueError(f"device profile '{profile.id}' has {taken} id; give it another id")
        table[profile.id] = profile
    return table


def resolve_camera(meta: FrameMeta, profiles: ProfileTable | None = None) -> CameraIntrinsics:
    """The intrinsics of the frame's own pixels; raises `server.outcomes.FrameError` for an unknown profile.

    `profiles` is what `camera.profile` may name (default: the bundled profiles); a calibrated
    profile (with `intrinsics`) is used as measured. A cropped frame's camera is the full frame's
    with the principal point moved by the window's offset, which is exact for the pinhole and for
    OpenCV's distortion (centred on the principal point).
    """
    camera = meta.camera
    if isinstance(camera, ProfileRef):
        camera = _profile_camera(camera, meta, device_profiles() if profiles is None else profiles)
    if meta.crop is None:
        return camera
    return camera.model_copy(update={"cx": camera.cx - meta.crop.x, "cy": camera.cy - meta.crop.y})


def _profile_camera(ref: ProfileRef, meta: FrameMeta, profiles: ProfileTable) -> CameraIntrinsics:
    profile = profiles.get(ref.profile)
    if profile is None:
        raise FrameError(
            f"unknown device profile '{ref.profile}'; known: {', '.join(sorted(profiles))}", field="camera.profile"
        )
    width, height = meta.full_size
    if (width > height) != (profile.width > profile.height):
        raise FrameError(
            f"frame {width}x{height} is turned against profile {profile.width}x{profile.height}", field="width"
        )
    try:
        return intrinsics_from_profile(profile, width, height)
    except ValidationError as error:  # a frame far smaller or larger than the profile's native size
        problem = error.errors()[0]
        raise FrameError(
            f"frame {width}x{height} scales profile '{ref.profile}' ({profile.width}x{profile.height}) out of the "
            f"contract's range: {'.'.join(map(str, problem['loc']))}: {problem['msg']}",
            field="width",
        ) from None
