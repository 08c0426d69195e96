"""The printable board at true scale: a PDF page of A4 or US Letter drawn as vectors, or a PNG for a screen.

A PDF board's squares and markers are filled rectangles, their sizes whole 0.01 mm (as the spec says them), on a
page exactly the paper's size, with a 100 mm check bar and the board's spec in words below it: what a ruler and
the next person need. A PNG's squares are whole pixels at the chosen resolution, so the sizes written into the
spec are the drawn ones exactly (the requested sizes rounded to the pixel grid: at 600 dpi, to 0.04 mm).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from server.calibration.board import charuco_board
from shared_schemas.calibration import BoardKind, BoardSpec

MM_PER_INCH = 25.4
PT_PER_MM = 72 / MM_PER_INCH
PAPERS_MM = {"a4": (210.0, 297.0), "letter": (215.9, 279.4)}  # portrait width x height
PAGE_MARGIN_MM = 5.0  # most printers leave 3-5 mm of the edge unprinted
# below the board, after 2 mm of paper: the check bar, and two lines of words beside it or, when they would be
# smaller than MIN_FONT_PT there, under it
BAND_BESIDE_MM, BAND_UNDER_MM = 8.0, 13.0
CHECK_BAR_MM = 100.0
CHECK_BAR_HEIGHT_MM = 1.5
SCREEN_MARGIN_MM = 10.0  # white around a PNG board: the outer squares' corners need paper around them
MAX_BOARD_PIXELS = 200_000_000
MAX_FONT_PT, MIN_FONT_PT = 6.5, 5.0

Rect = tuple[float, float, float, float]  # x, y, width, height in metres from the board's top-left, y down


@dataclass(frozen=True)
class PageLayout:
    """Where the board sits on its page, in mm from the page's top-left corner."""

    paper: str
    width_mm: float
    height_mm: float
    board_left_mm: float
    board_top_mm: float
    words_beside: bool  # the words beside the check bar, or under it
    font_pt: float

    @property
    def landscape(self) -> bool:
        return self.width_mm > self.height_mm


def exact_spec(spec: BoardSpec) -> BoardSpec:
    """The spec with its square and marker sizes rounded to 0.01 mm: what a vector page prints exactly."""
    square_m = round(spec.square_m * 1e5) / 1e5
    if spec.marker_m is None:
        return spec.model_copy(update={"square_m": square_m})
    marker_m = round(spec.marker_m * 1e5) / 1e5
    if marker_m >= square_m:
        raise ValueError(f"to 0.01 mm the marker ({marker_m * 1000:.2f} mm) is not smaller than the square")
    return spec.model_copy(update={"square_m": square_m, "marker_m": marker_m})


def printed_spec(spec: BoardSpec, dpi: float) -> BoardSpec:
    """The spec with its square and marker sizes rounded to whole pixels at `dpi` (what a PNG draws)."""
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


def page_layout(spec: BoardSpec, paper: str, lines: list[str]) -> PageLayout:
    """The board and its band on `paper` ("a4", "letter"): landscape or portrait, whichever the board's shape
    asks for and fits; centred; `lines` beside the check bar or under it. Raises ValueError when it fits
    neither way."""
    from reportlab.pdfbase.pdfmetrics import stringWidth

    board_w, board_h = spec.squares_x * spec.square_m * 1000, spec.squares_y * spec.square_m * 1000
    widest_pt = max(stringWidth(line, "Helvetica", 1.0) for line in lines)  # at 1 pt
    short, long = PAPERS_MM[paper]
    turns = [(long, short), (short, long)]
    for width, height in turns if board_w >= board_h else turns[::-1]:
        for beside, band in ((True, BAND_BESIDE_MM), (False, BAND_UNDER_MM)):
            spare_w, spare_h = width - board_w - 2 * PAGE_MARGIN_MM, height - board_h - band - 2 * PAGE_MARGIN_MM
            left = PAGE_MARGIN_MM + spare_w / 2
            # beside the bar the words start after it; under it they take the page's width (a small board's
            # own width would shrink them below MIN_FONT_PT)
            room_mm = width - PAGE_MARGIN_MM - left - CHECK_BAR_MM - 4.0 if beside else width - 2 * PAGE_MARGIN_MM
            font_pt = min(MAX_FONT_PT, room_mm * PT_PER_MM / widest_pt)
            if spare_w >= 0 and spare_h >= 0 and font_pt >= MIN_FONT_PT:
                return PageLayout(paper, width, height, left, PAGE_MARGIN_MM + spare_h / 2, beside, font_pt)
    raise ValueError(
        f"a {board_w:.1f} x {board_h:.1f} mm board does not fit on {paper_name(paper)} ({short:g} x {long:g} mm) "
        f"with {PAGE_MARGIN_MM:g} mm margins and the {BAND_BESIDE_MM:g} mm for its check bar: give smaller squares "
        "(--square-mm) or fewer (--squares)"
    )


def paper_name(paper: str) -> str:
    return {"a4": "A4", "letter": "US Letter"}[paper]


def board_rects(spec: BoardSpec) -> list[Rect]:
    """The board's black rectangles as OpenCV draws it (`CharucoBoard.generateImage`, tested equal): the black
    squares, then each marker's black cells, a row's neighbouring cells one rectangle. White on black when the
    spec is inverted."""
    square = spec.square_m
    if spec.kind == BoardKind.chessboard:  # the top-left square black, as on a ChArUco board
        return [
            (col * square, row * square, square, square)
            for row in range(spec.squares_y)
            for col in range(spec.squares_x)
            if (row + col) % 2 == 0
        ]
    assert spec.marker_m is not None  # a ChArUco spec has its marker size (BoardSpec checks it)
    board = charuco_board(spec)
    dictionary = board.getDictionary()
    ids, corners = np.asarray(board.getIds()).ravel(), board.getObjPoints()
    markers = [(int(marker), np.asarray(points)[0, :2]) for marker, points in zip(ids, corners, strict=True)]
    # a marker sits in a white square; each square without one is black
    white = {(int(top_left[1] // square), int(top_left[0] // square)) for _, top_left in markers}
    rects = [
        (col * square, row * square, square, square)
        for row in range(spec.squares_y)
        for col in range(spec.squares_x)
        if (row, col) not in white
    ]
    cells = dictionary.markerSize + 2  # with its one-cell black border
    cell = spec.marker_m / cells
    offset = (square - spec.marker_m) / 2
    for marker, top_left in markers:
        # generateImageMarker at one pixel per cell: the marker's cells, rows from its top (its corner 0)
        bits = cv2.aruco.generateImageMarker(dictionary, marker, cells, borderBits=1) == 0
        left = (top_left[0] // square) * square + offset
        top = (top_left[1] // square) * square + offset
        for row, start, length in _runs(bits):
            rects.append((left + start * cell, top + row * cell, length * cell, cell))
    return rects


def _runs(bits: np.ndarray) -> Iterator[tuple[int, int, int]]:
    """(row, first column, length) of each run of True along the rows of a 2-D bool array."""
    for row, line in enumerate(bits):
        padded = np.concatenate(([False], line, [False])).astype(np.int8)
        edges = np.flatnonzero(np.diff(padded))
        for start, end in zip(edges[::2], edges[1::2], strict=True):
            yield row, int(start), int(end - start)


def board_label(spec: BoardSpec) -> str:
    """The board's spec in words, for its page: every field a spec needs."""
    size = f"{spec.squares_x} x {spec.squares_y} squares of {spec.square_m * 1000:.2f} mm"
    if spec.kind == BoardKind.chessboard or spec.marker_m is None:
        words = [f"chessboard, {size} ({spec.squares_x - 1} x {spec.squares_y - 1} inner corners)"]
    else:
        layout = "legacy layout (OpenCV before 4.6)" if spec.legacy else "OpenCV 4.6+ layout"
        words = [
            f"ChArUco board, {size}, markers {spec.marker_m * 1000:.2f} mm, {spec.dictionary.value}",
            f"first marker id {spec.first_marker_id}",
            layout,
        ]
    return ", ".join(words + ["printed inverted"] * spec.inverted)


def board_command(spec: BoardSpec, out: str, paper: str) -> str:
    """The `lumipose calibrate board` command that makes this board's page again."""
    words = ["lumipose calibrate board", f"--out {out}", f"--paper {paper}"]
    if spec.kind == BoardKind.chessboard:
        words.append("--kind chessboard")
    words += [f"--squares {spec.squares_x}x{spec.squares_y}", f"--square-mm {spec.square_m * 1000:g}"]
    if spec.kind == BoardKind.charuco and spec.marker_m is not None:
        words += [f"--marker-mm {spec.marker_m * 1000:g}", f"--dictionary {spec.dictionary.value}"]
        words += ["--legacy"] * spec.legacy + [f"--first-marker {spec.first_marker_id}"] * bool(spec.first_marker_id)
    return " ".join(words + ["--inverted"] * spec.inverted)


def write_pdf(spec: BoardSpec, path: Path, paper: str) -> PageLayout:
    """The board on one page of `paper` (vectors: filled rectangles), the check bar and the spec below it."""
    from reportlab.pdfgen.canvas import Canvas

    label = board_label(spec)
    lines = [f"check bar: {CHECK_BAR_MM:g} mm (print at 100 %, no 'fit to page'). {label}"]
    lines.append(f"made by: {board_command(spec, path.name, paper)}")
    layout = page_layout(spec, paper, lines)
    page_h = layout.height_mm * PT_PER_MM

    def at(x_mm: float, top_mm: float, w_mm: float, h_mm: float) -> tuple[float, float, float, float]:
        """A rectangle from the page's top-left in mm, in PDF points from its bottom-left."""
        return x_mm * PT_PER_MM, page_h - (top_mm + h_mm) * PT_PER_MM, w_mm * PT_PER_MM, h_mm * PT_PER_MM

    def baseline(top_mm: float) -> float:
        return page_h - top_mm * PT_PER_MM

    canvas = Canvas(str(path), pagesize=(layout.width_mm * PT_PER_MM, page_h), invariant=1, pageCompression=1)
    canvas.setTitle(f"calibration board: {label}")
    canvas.setCreator("lumipose calibrate board")
    left, top = layout.board_left_mm, layout.board_top_mm
    board_w, board_h = spec.squares_x * spec.square_m * 1000, spec.squares_y * spec.square_m * 1000
    if spec.inverted:
        canvas.setFillGray(0)
        canvas.rect(*at(left, top, board_w, board_h), stroke=0, fill=1)
        canvas.setFillGray(1)
    # one path of every cell: one fill of their union, no hairline seams between neighbouring cells
    cells = canvas.beginPath()
    for x, y, w, h in board_rects(spec):
        cells.rect(*at(left + x * 1000, top + y * 1000, w * 1000, h * 1000))
    canvas.drawPath(cells, stroke=0, fill=1)
    canvas.setFillGray(0)
    bar_top = top + board_h + 2.0
    canvas.rect(*at(left, bar_top, CHECK_BAR_MM, CHECK_BAR_HEIGHT_MM), stroke=0, fill=1)
    canvas.setFont("Helvetica", layout.font_pt)
    under_bar = bar_top + CHECK_BAR_HEIGHT_MM + 2.6
    canvas.drawString(left * PT_PER_MM, baseline(under_bar), "0")
    canvas.drawRightString((left + CHECK_BAR_MM) * PT_PER_MM, baseline(under_bar), f"{CHECK_BAR_MM:g} mm")
    text_left, text_top = (
        (left + CHECK_BAR_MM + 4.0, bar_top + 1.6) if layout.words_beside else (PAGE_MARGIN_MM, under_bar + 3)
    )
    for k, line in enumerate(lines):
        canvas.drawString(text_left * PT_PER_MM, baseline(text_top + k * 2.8), line)
    canvas.showPage()
    canvas.save()
    return layout


def board_image(spec: BoardSpec, dpi: float) -> np.ndarray:
    """The board with a white margin (rows, cols) uint8 at `dpi`; `spec` should be `printed_spec`'s."""
    metres_per_px = MM_PER_INCH / 1000 / dpi
    square_px = round(spec.square_m / metres_per_px)
    margin_px = round(SCREEN_MARGIN_MM / MM_PER_INCH * dpi)
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


def write_board(spec: BoardSpec, path: Path, dpi: float, paper: str = "a4") -> tuple[BoardSpec, PageLayout | None]:
    """Write the board to `path` (.pdf: a page of `paper`; .png: its pixels at `dpi`) and its printed spec
    beside it (`path` with .json); returns that spec and the PDF's page."""
    suffix = path.suffix.lower()
    if suffix not in (".pdf", ".png"):
        raise ValueError(f"the board's file must end in .pdf or .png, not '{path.suffix}'")
    if paper not in PAPERS_MM:
        raise ValueError(f"--paper must be one of {', '.join(PAPERS_MM)}, got '{paper}'")
    layout = None
    if suffix == ".pdf":
        printed = exact_spec(spec)
        layout = write_pdf(printed, path, paper)
    else:
        if not 50 <= dpi <= 2400:
            raise ValueError(f"--dpi must be within 50 and 2400, got {dpi:g}")
        printed = printed_spec(spec, dpi)
        Image.fromarray(board_image(printed, dpi)).save(path, "PNG", dpi=(dpi, dpi))
    path.with_suffix(".json").write_text(spec_json(printed) + "\n")
    return printed, layout
