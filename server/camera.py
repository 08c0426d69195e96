"""Camera intrinsics of a frame: given in the frame, or from a device profile scaled to it."""

from __future__ import annotations

from shared_schemas import CameraIntrinsics, DeviceProfile, FrameMeta, ProfileRef, device_profiles


def intrinsics_from_profile(profile: DeviceProfile, width: int, height: int) -> CameraIntrinsics:
    """The profile's pinhole (paper eq. 9) at `width` x `height`.

    Another size is the native image scaled by s = max(w / W, h / H) and centre-cropped.
    The principal point is centred with pixel centres at integers: (w - 1) / 2, (h - 1) / 2.
    """
    scale = max(width / profile.width, height / profile.height)
    focal_px = profile.focal_length_m / profile.pixel_size_m * scale
    return CameraIntrinsics(
        fx=focal_px, fy=focal_px, cx=(width - 1) / 2, cy=(height - 1) / 2,
        distortion=list(profile.distortion), pixel_size_m=profile.pixel_size_m / scale,
        focal_length_m=profile.focal_length_m, device=profile.name,
    )


def resolve_camera(meta: FrameMeta) -> CameraIntrinsics:
    """The frame's intrinsics; raises `server.ingest.FrameError` for an unknown profile."""
    if not isinstance(meta.camera, ProfileRef):
        return meta.camera
    from server.ingest import FrameError

    profile = device_profiles().get(meta.camera.profile)
    if profile is None:
        raise FrameError(f"unknown device profile '{meta.camera.profile}'; known: {', '.join(sorted(device_profiles()))}",
                         field="camera.profile")
    if (meta.width > meta.height) != (profile.width > profile.height):
        raise FrameError(f"frame {meta.width}x{meta.height} is turned against profile "
                         f"{profile.width}x{profile.height}", field="width")
    return intrinsics_from_profile(profile, meta.width, meta.height)
