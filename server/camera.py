"""Camera intrinsics of a frame: given in the frame, or from a device profile scaled to it."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from pydantic import ValidationError

from server.outcomes import FrameError
from server.photos import PhotoExif
from shared_schemas import (
    CameraIntrinsics,
    CameraSource,
    CameraUsed,
    DeviceProfile,
    FrameMeta,
    ProfileRef,
    device_profiles,
)
from shared_schemas.cli import describe_file_error


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


def reduced_intrinsics(camera: CameraIntrinsics, reduction: int) -> CameraIntrinsics:
    """`camera` of a photo for the photo decoded at 1/`reduction` (libjpeg's scaled IDCT: an output pixel covers
    r x r input pixels, so a pixel centre u lands at (u + 1/2) / r - 1/2); distortion is in normalised
    coordinates and does not change."""
    if reduction == 1:
        return camera
    pixel = None if camera.pixel_size_m is None else camera.pixel_size_m * reduction
    return camera.model_copy(
        update={
            "fx": camera.fx / reduction,
            "fy": camera.fy / reduction,
            "cx": (camera.cx + 0.5) / reduction - 0.5,
            "cy": (camera.cy + 0.5) / reduction - 0.5,
            "pixel_size_m": pixel,
        }
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
    return scaled_profile(profile, width, height, "frame", field="width")


def scaled_profile(profile: DeviceProfile, width: int, height: int, what: str, field: str) -> CameraIntrinsics:
    """`intrinsics_from_profile`, or a FrameError naming `what` ("frame", "photo") when the size is far from the
    profile's native one (the scaled focal or pixel size leaves the contract's range)."""
    try:
        return intrinsics_from_profile(profile, width, height)
    except ValidationError as error:
        problem = error.errors()[0]
        raise FrameError(
            f"{what} {width}x{height} scales profile '{profile.id}' ({profile.width}x{profile.height}) out of the "
            f"contract's range: {'.'.join(map(str, problem['loc']))}: {problem['msg']}",
            field=field,
        ) from None


# How sure a photo's intrinsics are: the relative (1-sigma) error of the focal length in pixels, which
# is the relative error of the fix's distance (an error of focal_sigma_rel x distance along the ray).
# - calibrated profile: a board calibration's fx is good to a few 1e-4 (docs/calibration.md);
# - datasheet profile: the nominal focal length and pixel pitch are rounded and vary unit to unit, ~1-2 %;
# - EXIF 35 mm equivalent: an integer (26 mm +- 0.5 mm is +-1.9 %, 1.1 % as a sigma), focus breathing
#   (~2 %) and makers' diagonal conventions (~2 %) together ~4 %.
FOCAL_SIGMA_CALIBRATED = 0.0005
FOCAL_SIGMA_DATASHEET = 0.015
FOCAL_SIGMA_EXIF_35MM = 0.04
# EXIF FocalLength is the module's nominal focal length, rounded (4.216 mm written 4.22 or 4.2): 10 % takes
# that and a datasheet's error, while a phone's lenses differ by 30 % or more (ultra-wide 1.8, wide 4.3, tele 6)
EXIF_LENS_MATCH = 0.10
FULL_FRAME_DIAGONAL_MM = 43.2666  # of a 36 x 24 mm frame: the 35 mm equivalent's diagonal rule
PORTRAIT_ORIENTATION = 6  # a phone's stored landscape image shown upright (rear camera, held upright)
# EXIF's FocalLengthIn35mmFilm is a SHORT (0-65535 mm): a pinhole within 4-2400 mm, from a 9 mm fisheye-like
# ultra-wide (a 134-degree diagonal) past the longest phone and bridge-camera zooms; beyond, the tag is junk.
MIN_FOCAL_35MM_MM = 4.0
MAX_FOCAL_35MM_MM = 2400.0
EXIF_FOCAL_35MM_FIELD = "exif.FocalLengthIn35mmFilm"
EXIF_PIXEL_SIZE_FIELD = "exif.PixelXDimension"
# A photo scaled as a whole keeps the camera's aspect to within rounding: its sides may differ from the EXIF size
# times one scale by this share of a side (and 2 px), else the photo is a crop of what the camera wrote.
UNIFORM_SCALE_TOLERANCE = 0.002


def exif_scale(exif: PhotoExif, size: tuple[int, int]) -> float | None:
    """The photo's size (upright width, height) over the size its EXIF says the camera wrote (PixelXDimension,
    PixelYDimension, in either orientation: editors turn a photo upright and keep the camera's numbers); 1.0 when
    the EXIF says nothing; None when no one scale gives both sides, a crop (or a pad) of the camera's image."""
    if exif.pixel_size is None:
        return 1.0
    width, height = size
    for exif_w, exif_h in (exif.pixel_size, exif.pixel_size[::-1]):
        scale = width / exif_w
        if abs(exif_h * scale - height) <= max(2.0, UNIFORM_SCALE_TOLERANCE * height):
            return scale
    return None


def _refuse_crop(exif: PhotoExif, size: tuple[int, int], guess: str, ask: str) -> None:
    """A guess from EXIF (a profile the make names, the 35 mm rule) assumes the camera's whole image, centred on
    the optical axis: a crop's principal point is anywhere in the part cut away, so it is refused, not guessed."""
    if exif_scale(exif, size) is None:
        assert exif.pixel_size is not None
        raise FrameError(
            f"the photo is {size[0]}x{size[1]} pixels but its EXIF says the camera wrote "
            f"{exif.pixel_size[0]}x{exif.pixel_size[1]} (PixelXDimension, PixelYDimension): a crop, whose "
            f"principal point is unknown, so {guess} cannot be used: pass {ask}, or the photo as the camera wrote it",
            field=EXIF_PIXEL_SIZE_FIELD,
        )


@dataclass(frozen=True)
class PhotoCamera:
    """The intrinsics chosen for a photo, where they came from and how sure they are."""

    intrinsics: CameraIntrinsics
    source: CameraSource
    detail: str  # for people: which profile, which EXIF values
    focal_sigma_rel: float | None  # None: as given, unknown
    profile: str | None = None

    def used(self) -> CameraUsed:
        return camera_used(self.intrinsics, self.source, self.focal_sigma_rel, self.detail, self.profile)


def camera_used(
    camera: CameraIntrinsics, source: CameraSource, sigma: float | None, detail: str, profile: str | None = None
) -> CameraUsed:
    """The contract's statement of a fix's intrinsics (LocateResult.camera_used)."""
    return CameraUsed(
        fx=camera.fx,
        fy=camera.fy,
        cx=camera.cx,
        cy=camera.cy,
        source=source,
        profile=profile,
        focal_sigma_rel=sigma,
        detail=detail,
    )


def profile_sigma(profile: DeviceProfile) -> float:
    """A profile's relative focal uncertainty: calibrated or datasheet (see FOCAL_SIGMA_*)."""
    return FOCAL_SIGMA_CALIBRATED if profile.intrinsics is not None else FOCAL_SIGMA_DATASHEET


def frame_camera_used(meta: FrameMeta, camera: CameraIntrinsics, profiles: ProfileTable | None) -> CameraUsed:
    """`camera_used` of a recorded frame: its own intrinsics (uncertainty unknown) or the profile it names."""
    ref = meta.camera
    if not isinstance(ref, ProfileRef):
        return camera_used(camera, CameraSource.frame, None, "the frame's intrinsics")
    profile = (device_profiles() if profiles is None else profiles)[ref.profile]  # resolve_camera found it
    kind = "calibrated" if profile.intrinsics is not None else "datasheet"
    detail = f"{kind} profile '{profile.id}' named by the frame"
    return camera_used(camera, CameraSource.profile, profile_sigma(profile), detail, profile.id)


def _words(text: str) -> list[str]:
    return re.findall(r"[a-z0-9]+", text.lower())


def _profile_device(profile: DeviceProfile) -> list[str]:
    """The words of a profile's name before its camera ('Xiaomi Mi 8 rear camera' -> xiaomi, mi, 8)."""
    words = _words(profile.name)
    ends = [index for index, word in enumerate(words) if word in (profile.facing, "camera")]
    return words[: ends[0]] if ends else words


def profile_for_exif(exif: PhotoExif, profiles: ProfileTable) -> DeviceProfile | None:
    """The profile whose device is the photo's make and model, word for word (for example 'Xiaomi' 'MI 8' ->
    'Xiaomi Mi 8 rear camera', not 'Xiaomi Mi 8 Lite ...'); of a phone's several cameras, the one whose focal
    length is nearest the EXIF one (and within EXIF_LENS_MATCH of it: none when the photo's lens is not in the
    table), else the rear; a calibrated profile before a datasheet one of the same camera."""
    if not exif.model:
        return None
    make, model = _words(exif.make or ""), _words(exif.model)
    names = (model, make + model) if model[: len(make)] != make else (model,)
    matches = [p for p in profiles.values() if _profile_device(p) in names]
    if not matches:
        return None
    focal_mm = exif.focal_length_mm
    if focal_mm is not None:
        # a lens of the phone that the table lacks (a telephoto, an ultra-wide) is no profile's: the nearest
        # profile would be another lens, a pinhole tens of per cent off with a profile's small uncertainty
        matches = [p for p in matches if abs(p.focal_length_m * 1000 / focal_mm - 1) <= EXIF_LENS_MATCH]
        if not matches:
            return None
    return min(
        matches,
        key=lambda p: (
            0.0 if focal_mm is None else round(abs(p.focal_length_m * 1000 - focal_mm), 1),
            focal_mm is None and p.facing != "rear",
            p.intrinsics is None,
            p.id,
        ),
    )


def turn_intrinsics(camera: CameraIntrinsics, width: int, height: int, orientation: int) -> CameraIntrinsics:
    """`camera` of a `width` x `height` image, for that image turned by EXIF `orientation`'s rotation (1, 3, 6, 8).

    Orientation 6 turns the image a quarter clockwise: pixel (u, v) goes to (H-1-v, u), the camera's axes
    x' = -y, y' = x, so fx' = fy, cx' = H-1-cy, fy' = fx, cy' = cx; Brown-Conrady's tangential terms
    (2 p1 x y + p2 (r^2 + 2 x^2), p1 (r^2 + 2 y^2) + 2 p2 x y) become p1' = p2, p2' = -p1 (radial terms
    do not change). Orientation 8 is the other quarter, (u, v) -> (v, W-1-u): p1' = -p2, p2' = p1;
    orientation 3 the half turn: both principal point coordinates mirror and p1, p2 change sign.
    """
    fx, fy, cx, cy = camera.fx, camera.fy, camera.cx, camera.cy
    k = list(camera.distortion)
    p1, p2 = (k + [0.0, 0.0, 0.0, 0.0])[2:4]
    if orientation == 6:
        fx, fy, cx, cy, p1, p2 = fy, fx, height - 1 - cy, cx, p2, -p1
    elif orientation == 8:
        fx, fy, cx, cy, p1, p2 = fy, fx, cy, width - 1 - cx, -p2, p1
    elif orientation == 3:
        cx, cy, p1, p2 = width - 1 - cx, height - 1 - cy, -p1, -p2
    else:
        return camera
    if len(k) > 2:
        k[2:4] = [p1, p2][: len(k) - 2]
    return camera.model_copy(update={"fx": fx, "fy": fy, "cx": cx, "cy": cy, "distortion": k})


def _profile_turn(profile: DeviceProfile, upright: tuple[int, int], orientation: int) -> int:
    """The quarter turn (an EXIF orientation, 6 or 8; 1: none) from the profile's image to the upright photo.

    A profile of the upright photo's shape is taken as it is. One of the transposed shape was calibrated on the
    sensor's stored rows: it takes the photo's own quarter turn, or, for a photo its software turned upright
    already (no quarter in its EXIF), the quarter clockwise of a phone's rear camera held upright.
    """
    if upright[0] == upright[1] or (upright[0] > upright[1]) == (profile.width > profile.height):
        return 1
    return orientation if orientation in (6, 8) else PORTRAIT_ORIENTATION


def _profile_photo_camera(
    profile: DeviceProfile, size: tuple[int, int], exif: PhotoExif, source: CameraSource
) -> PhotoCamera:
    turn = _profile_turn(profile, size, exif.orientation)
    width, height = (size[1], size[0]) if turn in (6, 8) else size  # the photo in the profile's orientation
    intrinsics = turn_intrinsics(scaled_profile(profile, width, height, "photo", field="profile"), width, height, turn)
    turned = f", turned as EXIF orientation {turn}" if turn != 1 else ""
    kind = "calibrated" if profile.intrinsics is not None else "datasheet"
    detail = f"{kind} profile '{profile.id}'{turned}"
    return PhotoCamera(intrinsics, source, detail, profile_sigma(profile), profile.id)


def photo_camera(
    exif: PhotoExif,
    size: tuple[int, int],
    profiles: ProfileTable,
    camera: CameraIntrinsics | None = None,
    profile: DeviceProfile | None = None,
    ask: tuple[str, str] = ("--profile NAME|FILE", "--camera fx,fy,cx,cy"),
) -> PhotoCamera:
    """The intrinsics of a photo of `size` (upright width, height): `camera` as given (upright pixels) >
    `profile` > the profile EXIF make and model name > EXIF's 35 mm equivalent focal length (diagonal rule,
    principal point at the centre); FrameError asking for `ask` (the command's or the query's way to give a
    profile, then intrinsics) when there is nothing to go on."""
    width, height = size
    if camera is not None:
        return PhotoCamera(camera, CameraSource.camera, "given intrinsics", None)
    if profile is not None:  # what the user asked for, even on a crop: only said
        chosen = _profile_photo_camera(profile, size, exif, CameraSource.profile)
        return replace(chosen, detail=f"{chosen.detail}{_cropped(exif, size)}")
    matched = profile_for_exif(exif, profiles)
    if matched is not None:
        _refuse_crop(exif, size, f"the profile its EXIF names ('{matched.id}')", f"{ask[1]}")
        chosen = _profile_photo_camera(matched, size, exif, CameraSource.exif_profile)
        return replace(chosen, detail=f"EXIF '{exif.make} {exif.model}' -> {chosen.detail}{_scaled(exif, size)}")
    if exif.focal_35mm_mm is not None:
        _refuse_crop(exif, size, "its EXIF 35 mm equivalent focal length", ask[1])
        detail = (
            f"EXIF 35 mm equivalent focal length {exif.focal_35mm_mm:g} mm, principal point at the centre"
            f"{_scaled(exif, size)}"
        )
        return PhotoCamera(
            _exif_35mm_camera(exif.focal_35mm_mm, size, ask), CameraSource.exif_35mm, detail, FOCAL_SIGMA_EXIF_35MM
        )
    seen = f"EXIF make/model '{exif.make} {exif.model}' matches no profile" if exif.model else "no EXIF camera"
    fields = exif.fields()
    has = f"its EXIF has {', '.join(fields)}" if fields else "its EXIF has none of Make, Model, FocalLength"
    raise FrameError(
        f"the photo's camera is unknown ({seen}, no 35 mm equivalent focal length; {has}): pass {ask[0]} "
        f"(known: {', '.join(sorted(profiles))}) or {ask[1]}",
        field="camera",
    )


def _cropped(exif: PhotoExif, size: tuple[int, int]) -> str:
    """The detail's note of a photo whose EXIF size says it is cropped (a given profile assumes the whole image)."""
    if exif_scale(exif, size) is not None:
        return ""
    assert exif.pixel_size is not None
    return (
        f"; the photo looks cropped from {exif.pixel_size[0]}x{exif.pixel_size[1]} (its EXIF PixelXDimension, "
        "PixelYDimension): the profile's principal point may be off"
    )


def _scaled(exif: PhotoExif, size: tuple[int, int]) -> str:
    """The detail's note of a photo scaled as a whole from the size its EXIF gives (the guess scales with it)."""
    scale = exif_scale(exif, size)
    if exif.pixel_size is None or scale is None or abs(scale - 1) < 1e-3:
        return ""
    return f" (photo scaled {scale:.4g} x from the EXIF size {exif.pixel_size[0]}x{exif.pixel_size[1]})"


def _exif_35mm_camera(focal_35mm_mm: float, size: tuple[int, int], ask: tuple[str, str]) -> CameraIntrinsics:
    """The pinhole of EXIF's 35 mm equivalent focal length (diagonal rule, principal point at the centre), or a
    FrameError naming the EXIF field when it is no lens's (65535 mm) or gives no pinhole within the contract on
    this photo (1 mm on 16 x 16 pixels is a focal length of half a pixel)."""
    width, height = size
    ask_for = f"pass {ask[0]} or {ask[1]}"
    if not MIN_FOCAL_35MM_MM <= focal_35mm_mm <= MAX_FOCAL_35MM_MM:
        raise FrameError(
            f"the photo's EXIF 35 mm equivalent focal length {focal_35mm_mm:g} mm is no camera's (a lens is "
            f"{MIN_FOCAL_35MM_MM:g}-{MAX_FOCAL_35MM_MM:g} mm): {ask_for}",
            field=EXIF_FOCAL_35MM_FIELD,
        )
    focal_px = focal_35mm_mm / FULL_FRAME_DIAGONAL_MM * math.hypot(width, height)
    try:
        return CameraIntrinsics(fx=focal_px, fy=focal_px, cx=(width - 1) / 2, cy=(height - 1) / 2)
    except ValidationError as error:
        problem = error.errors()[0]
        raise FrameError(
            f"the photo's EXIF 35 mm equivalent focal length {focal_35mm_mm:g} mm on {width}x{height} pixels is a "
            f"focal length of {focal_px:.4g} px, out of the contract's range ({problem['msg']}): {ask_for}",
            field=EXIF_FOCAL_35MM_FIELD,
        ) from None


def resolve_profile_args(values: Iterable[str]) -> tuple[dict[str, DeviceProfile], DeviceProfile | None]:
    """`--profile NAME|FILE` as every command reads it: a path that exists is a profile file (registered, so a
    frame's camera.profile may name it), anything else a known id. Returns the table (bundled and files) and the
    last profile given (the one a photo uses), or ValueError naming the bad value."""
    values = list(values)
    given = []
    for value in values:
        path = Path(value)
        if not path.is_file():
            continue
        try:
            given.append(DeviceProfile.model_validate_json(path.read_bytes()))
        except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError: named by field
            raise ValueError(f"cannot read the device profile {describe_file_error(path, error)}") from None
    table = profile_table(given)
    chosen = None
    for value in values:
        if Path(value).is_file():
            chosen = given.pop(0)
        elif value in table:
            chosen = table[value]
        else:
            known = ", ".join(sorted(table))
            raise ValueError(f"--profile '{value}' is neither a file nor a known profile; known: {known}")
    return table, chosen


def parse_camera_arg(text: str) -> CameraIntrinsics:
    """`--camera fx,fy,cx,cy[,k1,k2,p1,p2,k3]` (pixels of the upright photo); ValueError names the fault."""
    try:
        numbers = [float(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"--camera '{text}' is not comma-separated numbers fx,fy,cx,cy[,k1,k2,p1,p2,k3]") from None
    if len(numbers) not in (4, 5, 6, 7, 8, 9):
        raise ValueError(f"--camera takes 4 to 9 numbers (fx,fy,cx,cy[,k1,k2,p1,p2,k3]), got {len(numbers)}")
    fx, fy, cx, cy, *distortion = numbers
    try:
        return CameraIntrinsics(fx=fx, fy=fy, cx=cx, cy=cy, distortion=distortion)
    except ValidationError as error:
        problem = error.errors()[0]
        raise ValueError(f"--camera: {'.'.join(map(str, problem['loc']))}: {problem['msg']}") from None
