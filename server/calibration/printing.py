"""The printable board: OpenCV's ChArUco image or a plain chessboard at true scale, as a PDF page or a PNG.

Squares are whole pixels at the chosen resolution, so the sizes written into the spec are the
printed ones exactly (the requested sizes rounded to the pixel grid: at 600 dpi, to 0.04 mm).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from server.calibration.board import charuco_board
from shared_schemas.calibration import BoardKind, BoardSpec

MM_PER_INCH = 25.4
PAGE_MARGIN_MM = 10.0  # white around the board: the outer squares' corners need paper around them
MAX_BOARD_PIXELS = 200_000_000


def printed_spec(spec: BoardSpec, dpi: float) -> BoardSpec:
    """The spec with its square and marker sizes rounded to whole pixels at `dpi` (what is printed)."""
    metres_per_px = MM_PER_INCH / 1000 / dpi
    square_px = max(1, round(spec.square_m / metres_per_px))
    if spec.marker_m is None:  # a chessboard
        return spec.model_copy(update={"square_m": square_px * metres_per_px})
    marker_px = max(1, round(spec.marker_m / metres_per_px))
    if marker_px >= square_px:
        raise ValueError(f"at {dpi:g} dpi the marker ({marker_px} px) is not smaller than the square ({square_px} px)")
    return spec.model_copy(update={"square_m": square_px * metres_per_px, "marker_m": marker_px * metres_per_px})


def spec_json(spec: BoardSpec) -> str:
    """The spec as board.json: the fields added for other boards (issue 29) only when not at their default, so
    the project's own board is written as before and readers of that format (the Android app) still take it."""
    added = {"kind": BoardKind.charuco, "marker_m": None, "legacy": False, "first_marker_id": 0, "inverted": False}
    at_default = {name for name, default in added.items() if getattr(spec, name) == default}
    return spec.model_dump_json(by_alias=True, indent=2, exclude=at_default)


def board_image(spec: BoardSpec, dpi: float) -> np.ndarray:
    """The board with a white margin (rows, cols) uint8 at `dpi`; `spec` should be `printed_spec`'s."""
    metres_per_px = MM_PER_INCH / 1000 / dpi
    square_px = round(spec.square_m / metres_per_px)
    margin_px = round(PAGE_MARGIN_MM / MM_PER_INCH * dpi)
    width, height = spec.squares_x * square_px, spec.squares_y * square_px
    if (width + 2 * margin_px) * (height + 2 * margin_px) > MAX_BOARD_PIXELS:
        raise ValueError(f"a {width} x {height} px board at {dpi:g} dpi is too large; lower --dpi")
    board: np.ndarray
    if spec.kind == BoardKind.chessboard:  # the top-left square black, as on a ChArUco board
        rows, cols = np.indices((spec.squares_y, spec.squares_x))
        squares = np.where((rows + cols) % 2, 255, 0).astype(np.uint8)
        board = np.repeat(np.repeat(squares, square_px, axis=0), square_px, axis=1)
    else:
        board = charuco_board(spec).generateImage((width, height), marginSize=0, borderBits=1)
    # an inverted print keeps its white margin: the outer corners need it as much
    return np.pad(255 - board if spec.inverted else board, margin_px, constant_values=255)


def write_board(spec: BoardSpec, path: Path, dpi: float) -> BoardSpec:
    """Write the board to `path` (.pdf: a page of the board's physical size; .png: with its dpi) and
    its printed spec beside it (`path` with .json); returns that spec."""
    suffix = path.suffix.lower()
    if suffix not in (".pdf", ".png"):
        raise ValueError(f"the board's file must end in .pdf or .png, not '{path.suffix}'")
    if not 50 <= dpi <= 2400:
        raise ValueError(f"--dpi must be within 50 and 2400, got {dpi:g}")
    printed = printed_spec(spec, dpi)
    image = Image.fromarray(board_image(printed, dpi))
    if suffix == ".pdf":
        image.save(path, "PDF", resolution=dpi)
    else:
        image.save(path, "PNG", dpi=(dpi, dpi))
    path.with_suffix(".json").write_text(spec_json(printed) + "\n")
    return printed
