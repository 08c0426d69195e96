"""The contract of camera calibration: the ChArUco board, the corners found on a photo, the report.

`lumipose calibrate board` writes a `BoardSpec` beside the printable board; `POST
/v1/calibrations/views` finds a `BoardView` on one photo (the app keeps these small records
instead of re-sending photos); `lumipose calibrate camera` and `POST /v1/calibrations` turn
views into a `CalibrationReport` whose `profile` is a calibrated `DeviceProfile`.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Final, Literal

from pydantic import (
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    ValidationInfo,
    field_validator,
    model_serializer,
    model_validator,
)

from shared_schemas.models import MAX_SIDE_PX, DeviceProfile, Strict

BOARD_SCHEMA: Final = "lumipose.board/1"
CALIBRATION_SCHEMA: Final = "lumipose.calibration/1"
MAX_BOARD_SQUARES: Final = 64  # per side: a board of 64 x 64 squares needs 2048 markers (DICT_*_1000 holds 1000)
MAX_VIEWS: Final = 200  # photos in one calibration: OpenCV's fit is cubic in them; 20-40 is plenty
MAX_VIEW_NAME: Final = 256  # characters of a view's name (a photo's file name)
MIN_SQUARE_M: Final = 1e-3
MAX_SQUARE_M: Final = 1.0


class ArucoDictionary(StrEnum):
    """OpenCV's predefined ArUco dictionaries a board may use (cv2.aruco.DICT_*, every one of OpenCV 4.6 and later)."""

    dict_4x4_50 = "DICT_4X4_50"
    dict_4x4_100 = "DICT_4X4_100"
    dict_4x4_250 = "DICT_4X4_250"
    dict_4x4_1000 = "DICT_4X4_1000"
    dict_5x5_50 = "DICT_5X5_50"
    dict_5x5_100 = "DICT_5X5_100"
    dict_5x5_250 = "DICT_5X5_250"
    dict_5x5_1000 = "DICT_5X5_1000"
    dict_6x6_50 = "DICT_6X6_50"
    dict_6x6_100 = "DICT_6X6_100"
    dict_6x6_250 = "DICT_6X6_250"
    dict_6x6_1000 = "DICT_6X6_1000"
    dict_7x7_50 = "DICT_7X7_50"
    dict_7x7_100 = "DICT_7X7_100"
    dict_7x7_250 = "DICT_7X7_250"
    dict_7x7_1000 = "DICT_7X7_1000"
    dict_aruco_original = "DICT_ARUCO_ORIGINAL"
    dict_apriltag_16h5 = "DICT_APRILTAG_16h5"
    dict_apriltag_25h9 = "DICT_APRILTAG_25h9"
    dict_apriltag_36h10 = "DICT_APRILTAG_36h10"
    dict_apriltag_36h11 = "DICT_APRILTAG_36h11"
    dict_aruco_mip_36h12 = "DICT_ARUCO_MIP_36h12"

    @property
    def size(self) -> int:
        """Markers in the dictionary."""
        return _DICTIONARY_SIZES[self.value]


# the AprilTag and original ArUco families' sizes are not in their names
_DICTIONARY_SIZES: Final = {
    "DICT_4X4_50": 50,
    "DICT_4X4_100": 100,
    "DICT_4X4_250": 250,
    "DICT_4X4_1000": 1000,
    "DICT_5X5_50": 50,
    "DICT_5X5_100": 100,
    "DICT_5X5_250": 250,
    "DICT_5X5_1000": 1000,
    "DICT_6X6_50": 50,
    "DICT_6X6_100": 100,
    "DICT_6X6_250": 250,
    "DICT_6X6_1000": 1000,
    "DICT_7X7_50": 50,
    "DICT_7X7_100": 100,
    "DICT_7X7_250": 250,
    "DICT_7X7_1000": 1000,
    "DICT_ARUCO_ORIGINAL": 1024,
    "DICT_APRILTAG_16h5": 30,
    "DICT_APRILTAG_25h9": 35,
    "DICT_APRILTAG_36h10": 2320,
    "DICT_APRILTAG_36h11": 587,
    "DICT_ARUCO_MIP_36h12": 250,
}


class BoardKind(StrEnum):
    """What is printed: OpenCV's ChArUco board (markers in the white squares) or a plain chessboard."""

    charuco = "charuco"
    chessboard = "chessboard"


class BoardSpec(Strict):
    """A calibration board: a chessboard of `squares_x` x `squares_y` squares, with an ArUco marker in each
    white square (`kind` charuco, the default) or none (`kind` chessboard).

    Sizes are as printed (measure them: a printer may scale). A ChArUco board's top-left square is black
    (OpenCV >= 4.6) unless `legacy`; its markers are `first_marker_id`, `first_marker_id` + 1, ... row by
    row. A chessboard of OpenCV's "9 x 6" (inner corners) pattern has 10 x 7 squares.
    """

    schema_: Literal["lumipose.board/1"] = Field(default=BOARD_SCHEMA, alias="schema")
    kind: BoardKind = BoardKind.charuco
    squares_x: int = Field(ge=3, le=MAX_BOARD_SQUARES, description="squares along the board's width")
    squares_y: int = Field(ge=3, le=MAX_BOARD_SQUARES, description="squares along the board's height")
    square_m: float = Field(ge=MIN_SQUARE_M, le=MAX_SQUARE_M, description="side of one square, metres")
    marker_m: float | None = Field(
        default=None,
        ge=MIN_SQUARE_M / 2,
        le=MAX_SQUARE_M,
        description="side of one marker, metres (a ChArUco board's; a chessboard has none)",
    )
    dictionary: ArucoDictionary = Field(
        default=ArucoDictionary.dict_5x5_100,
        description="the markers' dictionary (a ChArUco board's; a chessboard has none)",
    )
    # OpenCV before 4.6 drew boards of an even number of rows with the top-left square white
    legacy: bool = Field(default=False, description="OpenCV's layout before 4.6 (CharucoBoard.setLegacyPattern)")
    first_marker_id: int = Field(default=0, ge=0, description="the id of the top-left marker")
    inverted: bool = Field(default=False, description="printed inverted: white markers on black squares")

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)

    @model_validator(mode="after")
    def _fits(self) -> BoardSpec:
        if self.kind == BoardKind.chessboard:
            given_dictionary = "dictionary" in self.model_fields_set
            if self.marker_m is not None or self.legacy or self.first_marker_id or given_dictionary:
                raise ValueError(
                    "a chessboard has no markers: marker_m, legacy, first_marker_id and dictionary are ChArUco's"
                )
            return self
        if self.marker_m is None:
            raise ValueError("a ChArUco board needs marker_m (the side of one marker)")
        if self.marker_m >= self.square_m:
            raise ValueError(f"marker_m ({self.marker_m}) must be smaller than square_m ({self.square_m})")
        markers, size = self.squares_x * self.squares_y // 2, self.dictionary.size
        if self.first_marker_id + markers > size:
            raise ValueError(
                f"a {self.squares_x} x {self.squares_y} board needs {markers} markers"
                + (f" from id {self.first_marker_id}" if self.first_marker_id else "")
                + f"; {self.dictionary.value} has {size} (ids 0 to {size - 1})"
            )
        return self

    @model_serializer(mode="wrap")
    def _without_unused(self, handler: SerializerFunctionWrapHandler) -> dict:
        """A chessboard's spec without its (unused, default) dictionary: as written, it is read back."""
        data = handler(self)
        if self.kind == BoardKind.chessboard:
            data.pop("dictionary", None)
        return data

    @property
    def inner_corners(self) -> int:
        """Corners where four squares meet (a ChArUco board's corners, a chessboard's inner corners)."""
        return (self.squares_x - 1) * (self.squares_y - 1)


CornerId = Annotated[int, Field(ge=0, lt=MAX_BOARD_SQUARES * MAX_BOARD_SQUARES)]
# An image point: pixel centres at integers, so the image spans [-0.5, side - 0.5] (the view's own width and
# height bound it further, checked by BoardView).
CornerPoint = Annotated[list[Annotated[float, Field(ge=-0.5, le=MAX_SIDE_PX)]], Field(min_length=2, max_length=2)]


class BoardView(Strict):
    """The board's corners found on one photo: ChArUco corner ids and their sub-pixel image points."""

    name: str = Field(max_length=MAX_VIEW_NAME, description="the photo's name, for the report")
    width: int = Field(ge=1, le=MAX_SIDE_PX)
    height: int = Field(ge=1, le=MAX_SIDE_PX)
    corner_ids: list[CornerId] = Field(max_length=MAX_BOARD_SQUARES * MAX_BOARD_SQUARES)
    corners_px: list[CornerPoint] = Field(
        max_length=MAX_BOARD_SQUARES * MAX_BOARD_SQUARES,
        description="image points, finite and within the photo: x in [-0.5, width - 0.5], y in [-0.5, height - 0.5]",
    )
    inverted: bool = Field(default=False, description="the board was found inverted: white markers on black")
    mirrored: bool = Field(
        default=False,
        description="the photo was mirrored (a front camera's): the corners are those of the photo flipped "
        "left-right back, the image the lens made",
    )

    @model_validator(mode="after")
    def _paired(self) -> BoardView:
        if len(self.corner_ids) != len(self.corners_px):
            raise ValueError(f"{len(self.corner_ids)} corner_ids but {len(self.corners_px)} corners_px")
        if len(set(self.corner_ids)) != len(self.corner_ids):
            raise ValueError("corner_ids must be unique")
        return self

    @field_validator("corners_px")
    @classmethod
    def _within_photo(cls, corners: list[list[float]], info: ValidationInfo) -> list[list[float]]:
        width, height = info.data.get("width"), info.data.get("height")
        if width is None or height is None:
            return corners  # refused already
        for index, (x, y) in enumerate(corners):
            if x > width - 0.5 or y > height - 0.5:
                raise ValueError(
                    f"point {index} ({x:g}, {y:g}) lies outside the {width} x {height} photo "
                    f"(x at most {width - 0.5:g}, y at most {height - 0.5:g})"
                )
        return corners


class CalibrationRequest(Strict):
    """`POST /v1/calibrations`: views found on the photos (all of one size) and the phone they came from."""

    board: BoardSpec
    views: list[BoardView] = Field(min_length=1, max_length=MAX_VIEWS)
    device: str | DeviceProfile = Field(
        description="the phone's datasheet profile (an id the service knows, or the profile itself): "
        "its name, sensor, facing and pixel size carry over to the calibrated profile"
    )
    profile_id: str | None = Field(
        default=None,
        pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$",
        description="id of the calibrated profile; default '<device id>-calibrated'",
    )


class ViewFit(Strict):
    """How one photo fitted the calibration."""

    name: str
    corners: int = Field(ge=0, description="ChArUco corners used")
    rms_px: float | None = Field(default=None, ge=0, description="reprojection RMS of its corners; null when unused")
    tilt_deg: float | None = Field(default=None, ge=0, description="angle between the board's normal and the axis")
    distance_m: float | None = Field(default=None, description="board centre to camera")
    note: str | None = Field(default=None, description="why the photo was left out, if it was")
    inverted: bool = Field(default=False, description="the board was found inverted (white markers on black)")
    mirrored: bool = Field(default=False, description="the photo was mirrored: un-mirrored before fitting")


class FittedCamera(Strict):
    """The fitted pinhole and distortion at the photos' size, given also when the set is refused."""

    trusted: bool = Field(
        description="the set passed every check (these are the profile's values); false: fitted, but the set was "
        "refused (`advice` says why): for a look, not for positioning"
    )
    width: int = Field(ge=1, le=MAX_SIDE_PX)
    height: int = Field(ge=1, le=MAX_SIDE_PX)
    fx: float = Field(description="px")
    fy: float = Field(description="px")
    cx: float = Field(description="px")
    cy: float = Field(description="px")
    distortion: list[float] = Field(min_length=5, max_length=5, description="k1, k2, p1, p2, k3 (OpenCV's)")


class CalibrationReport(Strict):
    """What a calibration measured, how well, and what to shoot next when it is not good enough."""

    schema_: Literal["lumipose.calibration/1"] = Field(default=CALIBRATION_SCHEMA, alias="schema")
    ok: bool = Field(description="the set passed every check; only then is `profile` given")
    profile: DeviceProfile | None = None
    fitted: FittedCamera | None = Field(
        default=None, description="what the fit gave, trusted or not; null when nothing could be fitted"
    )
    rms_px: float | None = Field(default=None, ge=0, description="reprojection RMS over all corners")
    sigmas: dict[str, float] = Field(
        default_factory=dict, description="1-sigma of each parameter (fx, fy, cx, cy px; k1, k2, p1, p2, k3)"
    )
    distortion_sigma_px: float | None = Field(
        default=None, ge=0, description="the largest 1-sigma of the distortion's image shift over the whole frame"
    )
    fixed_terms: list[Literal["k3", "p1", "p2"]] = Field(
        default_factory=list,
        description="distortion terms the views did not support (an F-test on the residuals), fixed at 0",
    )
    coverage: float = Field(
        ge=0, le=1, description="share of the image's cells (`coverage_cells`) holding 3 corners or more"
    )
    coverage_cells: list[list[int]] = Field(
        default_factory=list, description="corners seen per cell, rows of the image top to bottom"
    )
    max_tilt_deg: float | None = Field(default=None, ge=0, description="the most tilted view")
    views: list[ViewFit] = Field(default_factory=list)
    advice: list[str] = Field(default_factory=list, description="what to shoot next, when ok is false")
    message: str | None = None
