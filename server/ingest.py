"""Frame ingest: raw Camera2 luma bytes (Y8 / NV21 / I420 with row stride), 8-bit PNG, or a phone photo.

Every inconsistency is a `FrameError` naming the field and what is wrong; raw frames are
never copied (the pixels are a strided view of the bytes).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
import pydantic_core
from pydantic import ValidationError

from server.camera import (
    PhotoCamera,
    ProfileTable,
    frame_camera_used,
    photo_camera,
    reduced_intrinsics,
    resolve_camera,
)
from server.outcomes import FrameError
from server.photos import PhotoError, read_photo
from shared_schemas import CameraIntrinsics, CameraUsed, DeviceProfile, FrameFormat, FrameMeta, device_profiles
from shared_schemas.fixture_files import PNG_SIGNATURE, photo_type, read_fixture_files
from shared_schemas.models import MAX_EXPOSURE_S, MAX_ISO, MIN_EXPOSURE_S, MIN_ISO

MAX_PIXELS = 100_000_000


@dataclass(frozen=True)
class LumaFrame:
    pixels: np.ndarray  # (height, width) uint8, read-only
    meta: FrameMeta
    camera: CameraIntrinsics
    camera_used: CameraUsed | None = None  # where `camera` came from and how sure (LocateResult.camera_used)


def parse_meta(text: str | bytes | dict) -> FrameMeta:
    """Validate frame metadata; NaN and Infinity are refused by the models, naming the field.

    The JSON parser is pydantic's, whose nesting limit turns a header nested thousands deep into
    a clear error instead of a RecursionError.
    """
    try:
        data = text if isinstance(text, dict) else pydantic_core.from_json(text)
    except ValueError as error:
        raise FrameError(f"frame metadata is not valid JSON: {error}") from None
    try:
        meta = FrameMeta.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        location = [str(p) for p in first["loc"] if not str(p).startswith(("CameraIntrinsics", "ProfileRef"))]
        field = ".".join(location) or None
        raise FrameError(f"{field}: {first['msg']}" if field else first["msg"], field=field) from None
    if meta.width * meta.height > MAX_PIXELS:
        raise FrameError(
            f"frame {meta.width}x{meta.height} exceeds {MAX_PIXELS // 1_000_000} megapixels", field="width"
        )
    return meta


def _raw_luma(data: memoryview, meta: FrameMeta) -> np.ndarray:
    width, height, stride = meta.width, meta.height, meta.stride
    luma_size = height * stride
    chroma = {FrameFormat.y8: 0, FrameFormat.nv21: luma_size // 2, FrameFormat.i420: luma_size // 2}[meta.format]
    if meta.format is not FrameFormat.y8 and (width % 2 or height % 2):
        raise FrameError(f"{meta.format.value} needs an even width and height, got {width}x{height}", field="width")
    expected = luma_size + chroma
    short_last_row = expected - (stride - width)  # Camera2 may drop the last row's padding
    if len(data) not in (expected, short_last_row):
        raise FrameError(
            f"frame has {len(data)} bytes but {meta.format.value} {width}x{height} with row_stride {stride} "
            f"needs {expected}",
            field="row_stride" if len(data) % height == 0 else "frame",
        )
    buffer = np.frombuffer(data, dtype=np.uint8)
    rows = np.lib.stride_tricks.as_strided(buffer, shape=(height, width), strides=(stride, 1), writeable=False)
    return rows


def png_header(data: bytes | memoryview) -> tuple[int, int, int, int] | None:
    """(width, height, bit depth, colour type) from a PNG's IHDR chunk, or None when `data` does not
    start like a PNG."""
    if len(data) < 26 or bytes(data[:8]) != PNG_SIGNATURE or bytes(data[12:16]) != b"IHDR":
        return None
    width, height, depth, colour = struct.unpack(">IIBB", bytes(data[16:26]))
    return width, height, depth, colour


def _png_luma(data: memoryview, meta: FrameMeta) -> np.ndarray:
    # The header says size, depth and colours before anything is decoded: a small file may hold
    # 20000 x 20000 pixels, or 16-bit colour (8 bytes a pixel), gigabytes once decoded.
    header = png_header(data)
    if header is None:
        raise FrameError("frame is not a readable PNG", field="frame")
    width, height, depth, colour = header
    if (width, height) != (meta.width, meta.height):
        raise FrameError(f"PNG is {width}x{height} but metadata says {meta.width}x{meta.height}", field="width")
    if depth != 8:
        raise FrameError(f"PNG must be 8-bit, got {depth}-bit", field="frame")
    if colour != 0:
        channels = {2: "3 channels (RGB)", 3: "a palette", 4: "2 channels (grey + alpha)", 6: "4 channels (RGBA)"}
        got = channels.get(colour, f"colour type {colour}")
        raise FrameError(f"PNG must be single-channel luma, got {got}", field="frame")
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None or image.dtype != np.uint8 or image.shape != (meta.height, meta.width):
        raise FrameError("frame is not a readable PNG", field="frame")
    image.flags.writeable = False
    return image


def decode_luma(data: bytes | memoryview, meta: FrameMeta) -> np.ndarray:
    """The luma plane (height, width) uint8 of `data` as described by `meta`, whatever its camera."""
    view = memoryview(data)
    return _png_luma(view, meta) if meta.format is FrameFormat.png else _raw_luma(view, meta)


def decode_frame(data: bytes | memoryview, meta: FrameMeta, profiles: ProfileTable | None = None) -> LumaFrame:
    """The luma plane of `data` as described by `meta`, with its camera; `profiles`: what `camera.profile`
    may name (default: the bundled profiles)."""
    camera = resolve_camera(meta, profiles)
    used = frame_camera_used(meta, camera, profiles)
    return LumaFrame(pixels=decode_luma(data, meta), meta=meta, camera=camera, camera_used=used)


def read_fixture(path: Path | str, profiles: ProfileTable | None = None) -> LumaFrame:
    """A recorded frame from NAME.json and its sibling NAME.y / NAME.yuv / NAME.png, in the format
    of the file found (the client reads fixtures with the same function)."""
    try:
        meta, data = read_fixture_files(path, parse_meta)
    except FileNotFoundError as error:
        raise FrameError(str(error)) from None
    return decode_frame(data, meta, profiles)


def _within(value: float | None, low: float, high: float) -> float | None:
    return value if value is not None and low <= value <= high else None


def decode_photo(
    data: bytes,
    name: str,
    profiles: ProfileTable | None = None,
    camera: CameraIntrinsics | None = None,
    profile: DeviceProfile | None = None,
    max_pixels: int = MAX_PIXELS,
    ask: tuple[str, str] | None = None,
) -> tuple[LumaFrame, PhotoCamera]:
    """A phone photo (JPEG, PNG, HEIC) as a frame: its luma, EXIF exposure and ISO, and the intrinsics
    `server.camera.photo_camera` chooses for the upright photo (`ask`: how the caller names a profile and
    intrinsics, for the message when there are none)."""
    try:
        photo = read_photo(data, name, max_pixels)
    except PhotoError as error:
        raise FrameError(str(error), field=error.field) from None
    pixels = photo.pixels  # upright (server.photos: one orientation rule on every path)
    height, width = pixels.shape
    table = device_profiles() if profiles is None else profiles
    if camera is not None:  # given for the photo's own pixels; a large JPEG's are decoded at 1/reduction
        camera = reduced_intrinsics(camera, photo.reduction)
    chosen = photo_camera(photo.exif, (width, height), table, camera, profile, *([ask] if ask else []))
    if photo.exif.orientation != 1:
        chosen = replace(
            chosen, detail=f"{chosen.detail} (photo turned upright: EXIF orientation {photo.exif.orientation})"
        )
    if photo.reduction != 1:
        full = f"{photo.stored_size[0]}x{photo.stored_size[1]}"
        note = f" (decoded at 1/{photo.reduction}, {width}x{height} of {full}: intrinsics in the decoded pixels)"
        chosen = replace(chosen, detail=chosen.detail + note)
    try:
        meta = FrameMeta(
            width=width,
            height=height,
            format=FrameFormat.y8,
            camera=chosen.intrinsics,
            exposure_s=_within(photo.exif.exposure_s, MIN_EXPOSURE_S, MAX_EXPOSURE_S),
            iso=_within(photo.exif.iso, MIN_ISO, MAX_ISO),
        )
    except ValidationError as error:  # for example --camera's principal point far outside the photo
        problem = error.errors()[0]
        raise FrameError(f"camera: {problem['msg']}", field="camera") from None
    return LumaFrame(pixels=pixels, meta=meta, camera=chosen.intrinsics, camera_used=chosen.used()), chosen


def is_photo(path: Path) -> bool:
    """A JPEG or HEIC file, or a PNG with no frame JSON beside it (a recorded PNG frame has one)."""
    return photo_type(path) is not None


def read_photo_file(
    path: Path,
    profiles: ProfileTable | None = None,
    camera: CameraIntrinsics | None = None,
    profile: DeviceProfile | None = None,
) -> tuple[LumaFrame, PhotoCamera]:
    """`decode_photo` of a file."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise FrameError(f"cannot read {path}: {error.strerror}", field="frame") from None
    return decode_photo(data, path.name, profiles, camera, profile)
