"""Pydantic models of the Lumipose contract (`docs/contract.md`).

These models are the single source of truth: the JSON Schemas in `json/` are exported
from them (`python -m shared_schemas.export`), and every other language tests against
the golden examples in `examples/`.

Conventions that bind everywhere:
- World (map) frame: metres, right-handed, X east, Y north, Z up.
- Camera frame: OpenCV's (x right, y down, z along the optical axis).
- Pixel coordinates: OpenCV's, pixel centres at integers.
- `rotation_wc` maps camera-frame vectors into the world frame.
"""

from __future__ import annotations

import math
from enum import StrEnum
from typing import Annotated, Final, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_core import InitErrorDetails, PydanticCustomError

Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Mat3 = Annotated[list[Vec3], Field(min_length=3, max_length=3)]
Point2 = Annotated[list[float], Field(min_length=2, max_length=2)]

FRAME_SCHEMA: Final = "lumipose.frame/1"
MAP_SCHEMA: Final = "lumipose.map/1"
RESULT_SCHEMA: Final = "lumipose.result/1"

# The physical range of every number a client or a map gives (docs/contract.md, "range" columns;
# the Android core mirrors them in io.lumipose.client.contract.ContractRanges and tests that they
# equal the exported schemas). Generous, so that no real camera, phone or room is refused, but
# finite, so that no number that passes can overflow or degenerate the pipeline's arithmetic.
MAX_SIDE_PX: Final = 100_000  # frame width/height: a 200 MP phone sensor is 16 320 x 12 240; 6x room
MAX_ROW_STRIDE: Final = 2 * MAX_SIDE_PX  # bytes per luma row: the widest frame with as much padding again
MIN_FOCAL_PX: Final = 1.0  # fx, fy: an ultra-wide lens on a 4-pixel-wide frame; 0 or 1e-300 makes K singular
MAX_FOCAL_PX: Final = 1e6  # a 0.5-degree field of view across 8000 px (a 10x periscope lens is ~65 000 px)
# cx, cy: anywhere within the full frame's size beyond either edge (FrameMeta checks it against the
# frame); real principal points are within a few percent of the centre.
MIN_PRINCIPAL_PX: Final = -float(MAX_SIDE_PX)
MAX_PRINCIPAL_PX: Final = 2.0 * MAX_SIDE_PX
# OpenCV distortion coefficients (k1, k2, p1, p2, k3, k4, k5, k6): a phone lens has |k| < 1 with the
# polynomial model; rational-model fits of wide lenses reach tens to hundreds where numerator and
# denominator cancel; p1, p2 are ~1e-3. 1000 bounds them all and keeps the r^6 terms far from overflow.
MAX_DISTORTION: Final = 1e3
MIN_PIXEL_SIZE_M: Final = 1e-9  # phone pixels are 0.56-2.4 um; room for a frame scaled up 500x from native
MAX_PIXEL_SIZE_M: Final = 1e-2  # the pitch of a frame of a few pixels scaled down from a large sensor
MIN_FOCAL_LENGTH_M: Final = 1e-4  # phone lenses are 1.5-20 mm; 0.1 mm is below a medical endoscope's
MAX_FOCAL_LENGTH_M: Final = 1.0  # a 1 m telephoto lens
MIN_EXPOSURE_S: Final = 1e-9  # Camera2 counts exposure in whole nanoseconds
MAX_EXPOSURE_S: Final = 3600.0  # phones stop at ~30 s; an hour leaves room for any camera
MIN_ISO: Final = 1.0  # sensors start at ISO 50-100
MAX_ISO: Final = 1e7  # the highest-ISO video camera is ~4.5 million
MAX_SKEW_S: Final = 1.0  # a phone reads a frame out in 5-40 ms; no sensor takes a second
MAX_TIMESTAMP_NS: Final = 2**63  # exclusive: Camera2's SENSOR_TIMESTAMP is a signed 64-bit count, >= 0
MAX_ANGLE_DEG: Final = 360.0  # headings and yaws: one turn either way covers (-180, 180] and [0, 360)
MAX_GRAVITY: Final = 100.0  # per component: TYPE_GRAVITY gives 9.81 m/s^2, a unit vector 1; 10 g is no gravity
MIN_GRAVITY_NORM: Final = 1e-6  # the zero vector (or one too short to have a direction) is refused
MAX_COORDINATE_M: Final = 1e7  # map coordinates: a room is metres, projected coordinates (UTM) reach 1e7 m
MAX_ROTATION_ENTRY: Final = 1.001  # entries of a rotation matrix are within [-1, 1]; room for rounding
MIN_SIDE_M: Final = 0.005  # a panel of 5 mm is a single LED; smaller cannot be seen as a square
MAX_SIDE_M: Final = 10.0  # a 10 m luminous ceiling
MIN_REQUIRED_SIGMA_M: Final = 1e-4  # a map may ask for a tenth of a millimetre, not for nothing
MAX_GRAVITY_SIGMA_DEG: Final = 90.0  # a tilt error beyond 90 degrees says nothing
# A result's free text: sentences for people, cut (ending in "...") where longer; with them a result's JSON
# stays within a few KB (the X-Lumipose-Result header of ?annotate=1 travels through proxies' 4-16 KB buffers)
MAX_MESSAGE_CHARS: Final = 1000  # `message`, `camera_used.detail`; the longest the service writes is ~400
MAX_WARNING_CHARS: Final = 300  # each of `warnings`
MAX_WARNINGS: Final = 8  # the service writes at most 3

Distortion = list[Annotated[float, Field(ge=-MAX_DISTORTION, le=MAX_DISTORTION)]]
GreyLevel = Annotated[float, Field(ge=0, le=255)]  # DN of an 8-bit luma plane
Coordinate = Annotated[float, Field(ge=-MAX_COORDINATE_M, le=MAX_COORDINATE_M)]
PositionM = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
RotationEntry = Annotated[float, Field(ge=-MAX_ROTATION_ENTRY, le=MAX_ROTATION_ENTRY)]
RotationRow = Annotated[list[RotationEntry], Field(min_length=3, max_length=3)]
Rotation = Annotated[list[RotationRow], Field(min_length=3, max_length=3)]
GravityComponent = Annotated[float, Field(ge=-MAX_GRAVITY, le=MAX_GRAVITY)]
GravityVec = Annotated[list[GravityComponent], Field(min_length=3, max_length=3)]
MAX_ANGULAR_RATE_DPS: Final = 4000.0  # phone gyroscopes read up to 2000 deg/s
AngularRate = Annotated[float, Field(ge=-MAX_ANGULAR_RATE_DPS, le=MAX_ANGULAR_RATE_DPS)]


def _require_finite(name: str, values: list[float]) -> None:
    for value in values:
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite numbers, got {value}")


def _field_error(loc: tuple[str | int, ...], message: str, value: object) -> ValidationError:
    """A validation error located at `loc` (a model validator's own errors have no field)."""
    error = PydanticCustomError("value_error", message)
    return ValidationError.from_exception_data("FrameMeta", [InitErrorDetails(type=error, loc=loc, input=value)])


def _check_distortion(value: list[float]) -> list[float]:
    if len(value) not in (0, 4, 5, 8):
        raise ValueError(f"distortion must have 0, 4, 5 or 8 OpenCV coefficients, got {len(value)}")
    _require_finite("distortion", value)
    return value


class Strict(BaseModel):
    """Base for models whose unknown fields are errors (typos must not pass silently)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class Open(BaseModel):
    """Base for models that keep unknown fields (the contract allows extra fields)."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False)


class CameraIntrinsics(Open):
    """Pinhole intrinsics in pixels for one frame size, plus OpenCV distortion.

    `distortion` is OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6]]); empty means none.
    """

    fx: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along x, pixels")
    fy: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along y, pixels")
    cx: float = Field(
        ge=MIN_PRINCIPAL_PX,
        le=MAX_PRINCIPAL_PX,
        description="principal point x, pixels of the full frame (pixel centres at integers); "
        "within [-width, 2 width] of the full frame",
    )
    cy: float = Field(
        ge=MIN_PRINCIPAL_PX,
        le=MAX_PRINCIPAL_PX,
        description="principal point y, pixels of the full frame; within [-height, 2 height] of the full frame",
    )
    distortion: Distortion = Field(default_factory=list)
    pixel_size_m: float | None = Field(default=None, ge=MIN_PIXEL_SIZE_M, le=MAX_PIXEL_SIZE_M)
    focal_length_m: float | None = Field(default=None, ge=MIN_FOCAL_LENGTH_M, le=MAX_FOCAL_LENGTH_M)
    device: str | None = None

    @field_validator("fx", "fy", "cx", "cy")
    @classmethod
    def _finite(cls, value: float, info) -> float:
        _require_finite(info.field_name, [value])
        return value

    @field_validator("distortion")
    @classmethod
    def _distortion_shape(cls, value: list[float]) -> list[float]:
        return _check_distortion(value)


class ProfileRef(Strict):
    """A camera given by the name of a device profile, scaled to the frame size."""

    profile: str = Field(description="device profile id, for example 'xiaomi-mi8-front'")


class Facing(StrEnum):
    front = "front"
    rear = "rear"


class MeasuredPinhole(Strict):
    """A camera's pinhole as a calibration measured it (`lumipose calibrate camera`), at the profile's size."""

    fx: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along x, pixels")
    fy: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along y, pixels")
    cx: float = Field(ge=MIN_PRINCIPAL_PX, le=MAX_PRINCIPAL_PX, description="principal point x, pixels")
    cy: float = Field(ge=MIN_PRINCIPAL_PX, le=MAX_PRINCIPAL_PX, description="principal point y, pixels")
    rms_px: float | None = Field(default=None, ge=0, description="the calibration's reprojection RMS")
    views: int | None = Field(default=None, ge=1, description="board photos the calibration used")


class DeviceProfile(Strict):
    """A phone camera as its maker describes it, at its native output size, or as a calibration measured it.

    With `intrinsics` (a calibrated profile: `width` x `height` are then the calibration photos' size)
    the pinhole comes from them; without, from `focal_length_m` / `pixel_size_m` with the principal
    point at the image centre. `distortion` is the calibration's or the maker's.
    """

    id: str
    name: str
    sensor: str
    facing: Facing
    pixel_size_m: float = Field(ge=MIN_PIXEL_SIZE_M, le=MAX_PIXEL_SIZE_M)
    focal_length_m: float = Field(ge=MIN_FOCAL_LENGTH_M, le=MAX_FOCAL_LENGTH_M)
    width: int = Field(ge=1, le=MAX_SIDE_PX, description="native output width, pixels")
    height: int = Field(ge=1, le=MAX_SIDE_PX, description="native output height, pixels")
    distortion: Distortion = Field(default_factory=list)
    gravity_sigma_deg: float = Field(
        default=0.1, ge=0, le=MAX_GRAVITY_SIGMA_DEG, description="1-sigma tilt error of the gravity sensor at rest"
    )
    intrinsics: MeasuredPinhole | None = Field(
        default=None, description="the measured pinhole at width x height; absent: the datasheet's"
    )

    @field_validator("distortion")
    @classmethod
    def _distortion_shape(cls, value: list[float]) -> list[float]:
        return _check_distortion(value)


class FrameFormat(StrEnum):
    y8 = "Y8"
    nv21 = "NV21"
    i420 = "I420"
    png = "PNG"


class FrameKind(StrEnum):
    """What a frame is for (docs/vlc.md, capture protocol)."""

    pose = "pose"  # normal exposure (~10 ms): the panel's outline; any LED code is averaged away
    id = "id"  # short exposure (<= 1/8000 s) beside a pose frame: the rolling shutter shows the code as stripes


class ToneCurve(StrEnum):
    """The tone curve the phone applied to the frame (Camera2 TONEMAP_MODE)."""

    linear = "linear"  # the linear contrast curve the app asked for: the response the clipped-edge model assumes
    srgb = "srgb"  # the sRGB preset curve (TONEMAP_MODE_PRESET_CURVE / TONEMAP_PRESET_CURVE_SRGB): the server undoes it
    device = "device"  # the device's own tone curve (the app's request was not applied or not possible)


class GroundTruth(Open):
    position_m: PositionM = Field(description="camera optical centre, map frame")
    rotation_wc: Rotation = Field(description="camera-to-world rotation")


class Crop(Strict):
    """The frame's pixels are a window of a larger sensor frame (a client may send only the
    beacon's region: a 20 MB frame then travels as 0.3-3 MB).

    The camera (intrinsics, or a profile scaled to `full_width` x `full_height`) describes the
    full frame; results (`corners_px`, `center_px`) are in the window's own pixels.
    """

    x: int = Field(ge=0, le=MAX_SIDE_PX, description="column of the window's first pixel in the full frame")
    y: int = Field(ge=0, le=MAX_SIDE_PX, description="row of the window's first pixel in the full frame")
    full_width: int = Field(ge=1, le=MAX_SIDE_PX)
    full_height: int = Field(ge=1, le=MAX_SIDE_PX)
    levels_dn: Annotated[list[GreyLevel], Field(min_length=2, max_length=2)] | None = Field(
        default=None,
        description="background and plateau grey levels of the FULL frame by the coarse rule (docs/contract.md, "
        "'Windows'); a tight window's own histogram is mostly panel. Without them the server measures the window",
    )

    @field_validator("levels_dn")
    @classmethod
    def _levels_in_range(cls, value: list[float] | None) -> list[float] | None:
        if value is not None:
            _require_finite("crop.levels_dn", value)
            background, plateau = value
            if background > plateau:
                raise ValueError(f"levels_dn must be [background, plateau], background <= plateau; got {value}")
        return value


class FrameMeta(Open):
    """The JSON that travels with every frame (a fixture's NAME.json, an upload's header)."""

    schema_: Literal["lumipose.frame/1"] = Field(default=FRAME_SCHEMA, alias="schema")
    format: FrameFormat = FrameFormat.y8
    width: int = Field(ge=1, le=MAX_SIDE_PX)
    height: int = Field(ge=1, le=MAX_SIDE_PX)
    row_stride: int | None = Field(default=None, ge=1, le=MAX_ROW_STRIDE, description="bytes per row; default width")
    camera: CameraIntrinsics | ProfileRef
    exposure_s: float | None = Field(default=None, ge=MIN_EXPOSURE_S, le=MAX_EXPOSURE_S)
    iso: float | None = Field(default=None, ge=MIN_ISO, le=MAX_ISO)
    rolling_shutter_skew_s: float | None = Field(default=None, ge=0, le=MAX_SKEW_S)
    timestamp_ns: int | None = Field(default=None, ge=0, lt=MAX_TIMESTAMP_NS)
    heading_deg: float | None = Field(default=None, ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)
    compass_bearing_deg: float | None = Field(
        default=None,
        ge=-MAX_ANGLE_DEG,
        le=MAX_ANGLE_DEG,
        description="the compass bearing (deg clockwise from north) of the image's +x direction laid level: "
        "the direction whose map yaw is heading_deg; a survey measures the map's bearing_deg from it",
    )
    gravity_camera: GravityVec | None = None
    angular_velocity_camera_dps: Annotated[list[AngularRate], Field(min_length=3, max_length=3)] | None = Field(
        default=None,
        description="the gyroscope's rotation rate in the camera frame, deg/s, over the frame's readout: "
        "the server undoes the rolling shutter's skew of pose frames with it",
    )
    ground_truth: GroundTruth | None = None
    crop: Crop | None = Field(default=None, description="present when the pixels are a window of a larger frame")
    tone_curve: ToneCurve | None = Field(
        default=None,
        description="'linear' when the phone applied the linear contrast curve it asked for, 'srgb' when it applied "
        "the sRGB preset curve (the server undoes it before measuring), 'device' when the device's own tone curve was "
        "used (named in the warnings, widens the uncertainty); absent means unknown",
    )
    frame_kind: FrameKind = Field(
        default=FrameKind.pose,
        description="'id' marks a short-exposure VLC frame (exposure_s <= 2e-4, needs rolling_shutter_skew_s "
        "and timestamp_ns); its beacon IDs are read from the stripes and combined with the device's other ID frames",
    )

    model_config = ConfigDict(extra="allow", populate_by_name=True, allow_inf_nan=False)

    @field_validator("heading_deg")
    @classmethod
    def _heading_finite(cls, value: float | None) -> float | None:
        if value is not None:
            _require_finite("heading_deg", [value])
        return value

    @field_validator("gravity_camera")
    @classmethod
    def _gravity_unit(cls, value: list[float] | None) -> list[float] | None:
        if value is None:
            return None
        _require_finite("gravity_camera", value)
        norm = math.hypot(*value)
        if norm < MIN_GRAVITY_NORM:
            raise ValueError(f"gravity_camera must not be the zero vector (its length is {norm:.3g})")
        return [v / norm for v in value]

    @field_validator("row_stride")
    @classmethod
    def _stride_fits(cls, value: int | None, info) -> int | None:
        width = info.data.get("width")
        if value is not None and width is not None and value < width:
            raise ValueError(f"row_stride {value} is smaller than width {width}")
        return value

    @model_validator(mode="after")
    def _crop_inside(self) -> FrameMeta:
        crop = self.crop
        if crop is not None and (crop.x + self.width > crop.full_width or crop.y + self.height > crop.full_height):
            raise _field_error(
                ("crop",),
                f"crop window {self.width}x{self.height} at ({crop.x}, {crop.y}) does not fit in the "
                f"full frame {crop.full_width}x{crop.full_height}",
                crop.model_dump(),
            )
        return self

    @model_validator(mode="after")
    def _principal_point_near_the_frame(self) -> FrameMeta:
        """cx, cy (of the full frame) within [-size, 2 size] of the full frame: real ones are near its centre."""
        if not isinstance(self.camera, CameraIntrinsics):
            return self
        for name, value, size in (("cx", self.camera.cx, self.full_size[0]), ("cy", self.camera.cy, self.full_size[1])):
            if not -size <= value <= 2 * size:
                raise _field_error(
                    ("camera", name),
                    f"principal point {name} = {value:g} px is outside [-{size}, {2 * size}], "
                    f"the full frame's {'width' if name == 'cx' else 'height'} {size} beyond either edge",
                    value,
                )
        return self

    @property
    def stride(self) -> int:
        return self.row_stride or self.width

    @property
    def full_size(self) -> tuple[int, int]:
        """(width, height) of the sensor frame the camera describes: the crop's full frame, or this one."""
        return (self.crop.full_width, self.crop.full_height) if self.crop else (self.width, self.height)

    @property
    def full_offset(self) -> tuple[int, int]:
        """(column, row) of this frame's first pixel in the full frame: the crop's, or (0, 0)."""
        return (self.crop.x, self.crop.y) if self.crop else (0, 0)

    def fraction_of_full_frame(self, x_px: float, y_px: float) -> tuple[float, float]:
        """A pixel of this frame as a fraction of the full frame's width and height, comparable
        between frames of other sizes or crops of the same camera."""
        (width, height), (column, row) = self.full_size, self.full_offset
        return (x_px + column) / width, (y_px + row) / height


_SIZE_FIELDS: Final = ("side_m", "width_m", "height_m", "diameter_m")


class PanelShape(StrEnum):
    rounded_rectangle = "rounded_rectangle"  # squares too: side_m, or width_m and height_m
    circle = "circle"  # a round downlight: diameter_m; it shows no yaw (docs/contract.md, "Panel shapes")


class Beacon(Strict):
    """A luminous panel on the ceiling, facing down (-Z): a rounded rectangle (a square by
    default) or a circle, centred at `center_m`, its width along the beacon frame's x_B axis."""

    id: int = Field(ge=0, le=255, description="VLC code of the beacon")
    center_m: PositionM
    yaw_deg: float = Field(default=0.0, ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)
    shape: PanelShape = PanelShape.rounded_rectangle
    side_m: float | None = Field(
        default=None, ge=MIN_SIDE_M, le=MAX_SIDE_M, description="outer side of a rounded square"
    )
    width_m: float | None = Field(
        default=None, ge=MIN_SIDE_M, le=MAX_SIDE_M, description="rounded rectangle: outer size along x_B"
    )
    height_m: float | None = Field(
        default=None, ge=MIN_SIDE_M, le=MAX_SIDE_M, description="rounded rectangle: outer size along y_B"
    )
    diameter_m: float | None = Field(default=None, ge=MIN_SIDE_M, le=MAX_SIDE_M, description="circle: its diameter")
    corner_radius_m: float = Field(default=0.0, ge=0, le=MAX_SIDE_M / 2)

    @model_validator(mode="after")
    def _geometry(self) -> Beacon:
        _require_finite("center_m", self.center_m)
        _require_finite("yaw_deg", [self.yaw_deg])
        given = {name for name in _SIZE_FIELDS if getattr(self, name) is not None}
        if self.shape is PanelShape.circle:
            if given != {"diameter_m"}:
                raise ValueError(f"a circle has diameter_m and no other size, got {sorted(given)}")
            if self.corner_radius_m:
                raise ValueError("a circle has no corner_radius_m")
            return self
        if given not in ({"side_m"}, {"width_m", "height_m"}):
            raise ValueError(f"a rounded rectangle has side_m, or width_m and height_m, got {sorted(given)}")
        if self.corner_radius_m * 2 >= min(self.extent_m):
            raise ValueError("corner_radius_m must be less than half of the panel's shorter side")
        return self

    @property
    def extent_m(self) -> tuple[float, float]:
        """(width along x_B, height along y_B) of the panel's outline."""
        if self.diameter_m is not None:
            return self.diameter_m, self.diameter_m
        if self.side_m is not None:
            return self.side_m, self.side_m
        assert self.width_m is not None and self.height_m is not None  # the validator's
        return self.width_m, self.height_m

    @property
    def outline_radius_m(self) -> float:
        """The radius of the outline's corner arcs (a circle: all arc, half its diameter)."""
        return self.diameter_m / 2 if self.diameter_m is not None else self.corner_radius_m

    @property
    def size_m(self) -> float:
        """The panel's longer outer size (its side, its width or its diameter)."""
        return max(self.extent_m)

    @property
    def has_corners(self) -> bool:
        """A rounded rectangle has four corners (their order is the contract's); a circle none."""
        return self.shape is PanelShape.rounded_rectangle


class BeaconMap(Strict):
    schema_: Literal["lumipose.map/1"] = Field(default=MAP_SCHEMA, alias="schema")
    name: str
    beacons: list[Beacon] = Field(min_length=1)
    required_sigma_m: float = Field(
        default=0.01,
        ge=MIN_REQUIRED_SIGMA_M,
        le=MAX_SIDE_M,
        description="the 1-sigma 2-D position error every fix must reach, or it is refused (pose_uncertain)",
    )
    bearing_deg: float | None = Field(
        default=None,
        ge=-MAX_ANGLE_DEG,
        le=MAX_ANGLE_DEG,
        description="the compass bearing (deg clockwise from north) of the map's +X axis, as a survey measured it: "
        "a phone turns its compass reading into heading_deg with it",
    )

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)

    @model_validator(mode="after")
    def _unique_ids(self) -> BeaconMap:
        ids = [b.id for b in self.beacons]
        if len(ids) != len(set(ids)):
            raise ValueError(f"beacon ids must be unique, got {sorted(ids)}")
        return self

    def beacon(self, beacon_id: int) -> Beacon | None:
        return next((b for b in self.beacons if b.id == beacon_id), None)


class FailureReason(StrEnum):
    no_beacon = "no_beacon"
    beacon_cut_off = "beacon_cut_off"
    not_a_square = "not_a_square"
    not_four_sides = "not_four_sides"
    pose_failed = "pose_failed"
    pose_ambiguous = "pose_ambiguous"
    pose_uncertain = "pose_uncertain"  # the frame fixes the position only to worse than the map's required_sigma_m
    # the fitted panel does not explain what the frame shows, beyond the noise the fit measured (a wrong
    # map, a blob that is not a panel of the map): docs/reliability.md, "A fix answers to its own evidence"
    shape_mismatch = "shape_mismatch"
    unknown_beacon = "unknown_beacon"
    id_frame = "id_frame"  # an ID frame kept for the device's next capture: no fix of its own (docs/vlc.md)
    numerical_failure = "numerical_failure"  # the arithmetic failed on the frame's or map's numbers (logged)


class OrientationRule(StrEnum):
    heading = "heading"
    yaw_within_45deg = "yaw_within_45deg"
    yaw_within_90deg = "yaw_within_90deg"  # a rectangle: its aspect settles two of the square's four orientations


class BeaconIdSource(StrEnum):
    single_beacon_map = "single_beacon_map"
    vlc = "vlc"
    track = "track"  # carried by the device's track: the map beacon nearest the predicted view


class VlcReading(Strict):
    """The beacon ID read from rolling-shutter stripes (docs/vlc.md)."""

    beacon_id: int | None = Field(
        default=None,
        ge=0,
        le=255,
        description="the best hypothesis's ID: a map ID, or, when 'none of the map's' wins, the code the stripes "
        "read as (not in the map: never confident, never names a panel); null when no stripes were read",
    )
    confidence: float = Field(
        ge=0,
        le=1,
        description="posterior probability of beacon_id's hypothesis among the map's IDs and 'none of them' "
        "(for an ID not in the map: of 'none'); without a map, among all 256 IDs",
    )
    confident: bool = Field(description="a map ID's confidence reached the decoder's threshold; only then is it used")
    frames: int = Field(ge=0, description="ID frames combined")
    chips_seen: float = Field(ge=0, description="message chips covered by those frames (a message is 21)")
    candidates: int = Field(
        ge=1, description="hypotheses weighed: the map's IDs plus 'none of them' (256 IDs without a map)"
    )


class CameraSource(StrEnum):
    frame = "frame"  # the frame JSON's own intrinsics
    camera = "camera"  # intrinsics given with the request (--camera, the camera query parameter)
    profile = "profile"  # a device profile named by the frame, --profile or the profile query parameter
    exif_profile = "exif_profile"  # the profile whose name is the photo's EXIF make and model
    exif_35mm = "exif_35mm"  # the photo's EXIF 35 mm equivalent focal length, principal point at the centre


class CameraUsed(Strict):
    """The intrinsics a fix was computed with, where they came from and how sure they are."""

    fx: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along x, pixels of the frame")
    fy: float = Field(ge=MIN_FOCAL_PX, le=MAX_FOCAL_PX, description="focal length along y, pixels of the frame")
    cx: float = Field(ge=MIN_PRINCIPAL_PX, le=MAX_PRINCIPAL_PX, description="principal point x, pixels")
    cy: float = Field(ge=MIN_PRINCIPAL_PX, le=MAX_PRINCIPAL_PX, description="principal point y, pixels")
    source: CameraSource
    profile: str | None = Field(
        default=None, max_length=64, description="the device profile's id (a profile's name), when one was used"
    )
    focal_sigma_rel: float | None = Field(
        default=None, ge=0, le=1, description="relative 1-sigma error of fx, fy; null: unknown (given intrinsics)"
    )
    detail: str = Field(
        max_length=MAX_MESSAGE_CHARS, description="for people: which profile, which EXIF values, any turn"
    )


class TrackState(Strict):
    """A device's motion-filtered track at this frame; the fix itself stays in position_m."""

    filtered_position_m: Vec3
    velocity_mps: Vec3
    outlier: bool = Field(description="the raw fix was rejected by the filter's gate")
    beacon_id_carried: bool = Field(default=False, description="the beacon ID came from the track, not this frame")


class LocateResult(Strict):
    """What the pipeline says about one frame. On failure only `reason` and `message` bind."""

    schema_: Literal["lumipose.result/1"] = Field(default=RESULT_SCHEMA, alias="schema")
    ok: bool
    position_m: Vec3 | None = Field(default=None, description="camera optical centre, map frame")
    rotation_wc: Mat3 | None = None
    yaw_pitch_roll_deg: Vec3 | None = Field(
        default=None, description="R_wc = Rz(yaw) Ry(pitch) Rx(roll); all zero = looking up"
    )
    beacon_id: int | None = None
    beacon_id_source: BeaconIdSource | None = None
    orientation_rule: OrientationRule | None = None
    corners_px: list[Point2] | None = Field(default=None, description="4 corners in the beacon model's corner order")
    center_px: Point2 | None = None
    reprojection_error_px: float | None = None
    ambiguity_ratio: float | None = Field(
        default=None, description="reprojection error of the best over the alternative pose"
    )
    gravity_used: bool = False
    position_sigma_m: Vec3 | None = Field(
        default=None, description="1-sigma uncertainty of position_m along the map's X, Y, Z (m), from the fit"
    )
    position_covariance_m2: Mat3 | None = Field(
        default=None, description="covariance of position_m in the map frame (m^2); its XY block gives the 2D ellipse"
    )
    reason: FailureReason | None = None
    message: str | None = Field(default=None, max_length=MAX_MESSAGE_CHARS)
    warnings: list[Annotated[str, Field(max_length=MAX_WARNING_CHARS)]] = Field(
        default_factory=list, max_length=MAX_WARNINGS
    )
    timing_ms: dict[str, float] = Field(default_factory=dict)
    vlc: VlcReading | None = Field(default=None, description="the ID read by VLC for this fix, when one was read")
    camera_used: CameraUsed | None = Field(default=None, description="the intrinsics of this result and how sure")
    beacons_in_view: int | None = Field(default=None, ge=0, description="beacon-shaped blobs seen in the frame")
    track: TrackState | None = None

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)


class ErrorBody(Strict):
    """A request that cannot be read at all (HTTP 4xx, CLI exit 2)."""

    error: str = Field(description="machine-readable code, for example 'bad_frame'")
    field: str | None = Field(default=None, description="the offending field, if one")
    message: str
