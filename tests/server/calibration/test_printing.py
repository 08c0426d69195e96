"""The printed board read back from its PDF: the paper's page, vectors at the spec's sizes, the check bar, the spec
in words, and the page rasterized as a printer would found as the spec says (issue 31)."""

from pathlib import Path

import numpy as np
import pdfplumber
import pytest

from lumipose_cli.main import main
from server.calibration.board import charuco_board, find_board
from server.calibration.printing import board_rects
from shared_schemas.calibration import BoardSpec

PT_PER_MM = 72 / 25.4
PAPERS_PT = {"a4": (210 * PT_PER_MM, 297 * PT_PER_MM), "letter": (612.0, 792.0)}


def _board(tmp_path, capsys, *args):
    out = tmp_path / "board.pdf"
    assert main(["calibrate", "board", "--out", str(out), *args]) == 0
    return out, BoardSpec.model_validate_json((tmp_path / "board.json").read_text()), capsys.readouterr().out


@pytest.mark.parametrize("paper, turned", [("a4", "A4 landscape"), ("letter", "US Letter landscape")])
def test_the_page_is_the_papers_and_the_board_is_vectors_at_the_specs_sizes(tmp_path, capsys, paper, turned):
    out, spec, said = _board(tmp_path, capsys, "--paper", paper)
    assert (spec.square_m, spec.marker_m) == (0.024, 0.0144)  # exact, not whole pixels (24.003 mm before)
    assert f"squares 24.00 mm, markers 14.40 mm) on a" in said and f"({turned})" in said
    assert "measure the check bar (100 mm) and a square: if a square is not 24.00 mm" in said
    data = out.read_bytes()
    assert b"/DCTDecode" not in data and b"/XObject" not in data  # no picture of the board, lossy or not
    with pdfplumber.open(out) as pdf:
        (page,) = pdf.pages
        width, height = PAPERS_PT[paper]
        assert (page.width, page.height) == (pytest.approx(height, abs=1e-3), pytest.approx(width, abs=1e-3))
        mm = [
            (r["x0"] / PT_PER_MM, r["top"] / PT_PER_MM, r["width"] / PT_PER_MM, r["height"] / PT_PER_MM)
            for r in page.rects
        ]
        text, images, font_pt = page.extract_text(), page.images, min(char["size"] for char in page.chars)
    assert images == []
    squares = [r for r in mm if abs(r[2] - 24) < 0.01 and abs(r[3] - 24) < 0.01]
    assert len(squares) == 44  # 88 squares, half of them black
    assert max(abs(r[2] - 24) for r in squares) < 1e-4
    left, top = min(r[0] for r in squares), min(r[1] for r in squares)
    grid = np.array([((r[0] - left) / 24, (r[1] - top) / 24) for r in squares])
    assert np.abs(grid - grid.round()).max() < 1e-5  # each square on the 24.00 mm grid
    (bar,) = [r for r in mm if r[2] > 90]
    assert bar[2] == pytest.approx(100, abs=1e-4) and bar[1] > top + 8 * 24  # below the board
    assert f"ChArUco board, 11 x 8 squares of 24.00 mm, markers 14.40 mm, DICT_5X5_100, first marker id 0" in text
    assert "check bar: 100 mm" in text and font_pt >= 5  # readable: 1.8 mm capitals
    command = f"lumipose calibrate board --out board.pdf --paper {paper} --squares 11x8 --square-mm 24"
    assert f"made by: {command} --marker-mm 14.4 --dictionary DICT_5X5_100" in text


@pytest.mark.parametrize(
    "args, shape",
    [
        ([], (1240, 1754)),  # A4 landscape at 150 dpi
        (
            [
                "--paper",
                "letter",
                "--squares",
                "6x8",
                "--square-mm",
                "25.4",
                "--dictionary",
                "DICT_4X4_50",
                "--legacy",
                "--first-marker",
                "5",
                "--inverted",
            ],
            (1650, 1275),
        ),  # Letter portrait
        (["--kind", "chessboard", "--squares", "10x7", "--square-mm", "25"], (1240, 1754)),
    ],
)
def test_the_page_rasterized_shows_the_spec_at_its_size(tmp_path, capsys, args, shape):
    out, spec, _ = _board(tmp_path, capsys, *args)
    dpi = 150
    with pdfplumber.open(out) as pdf:
        page = np.asarray(pdf.pages[0].to_image(resolution=dpi, antialias=True).original.convert("L"))
    assert np.abs(np.subtract(page.shape, shape)).max() <= 1  # the page rounded up to whole pixels
    view = find_board(page, spec, "page")  # cv2.aruco's CharucoDetector (findChessboardCornersSB for a chessboard)
    assert view is not None and len(view.corner_ids) == spec.inner_corners and not view.mirrored
    assert view.inverted == spec.inverted
    with pdfplumber.open(out) as pdf:  # the words beside the bar, or under it where they would be too small
        assert min(char["size"] for char in pdf.pages[0].chars) >= 5
    # the corners' spacing is the square's size on paper
    corners = np.asarray(view.corners_px)
    per_row = spec.squares_x - 1
    steps = np.linalg.norm(np.diff(corners.reshape(-1, per_row, 2), axis=1), axis=2)
    assert np.median(steps) == pytest.approx(spec.square_m / 0.0254 * dpi, rel=2e-3)


@pytest.mark.parametrize("legacy", [False, True])
def test_the_vector_cells_are_opencvs_board(legacy):
    # at 77 px a square and 7 px a marker cell, OpenCV's own image of the board has every edge on a pixel
    spec = BoardSpec(
        squares_x=5,
        squares_y=4,
        square_m=0.077,
        marker_m=0.049,
        dictionary="DICT_5X5_100",
        legacy=legacy,
        first_marker_id=3,
    )
    image = np.full((4 * 77, 5 * 77), 255, np.uint8)
    for x, y, w, h in board_rects(spec):
        image[round(y * 1000) : round((y + h) * 1000), round(x * 1000) : round((x + w) * 1000)] = 0
    assert np.array_equal(image, charuco_board(spec).generateImage((5 * 77, 4 * 77), marginSize=0, borderBits=1))


def test_a_board_too_large_for_the_paper_is_bad_input(tmp_path, capsys):
    out = tmp_path / "big.pdf"
    assert main(["calibrate", "board", "--out", str(out), "--square-mm", "30", "--paper", "letter"]) == 2
    assert "a 330.0 x 240.0 mm board does not fit on US Letter (215.9 x 279.4 mm)" in capsys.readouterr().err
    assert not out.exists() and not (tmp_path / "big.json").exists()


def test_the_docs_quote_what_calibrate_board_prints(tmp_path, capsys, monkeypatch):
    doc = (Path(__file__).parents[3] / "docs" / "calibration.md").read_text()
    quoted = [line.strip() for line in doc.split("```")[1].splitlines() if line.strip()]
    monkeypatch.chdir(tmp_path)
    assert main(["calibrate", "board", "--out", "board.pdf"]) == 0
    assert capsys.readouterr().out.splitlines() == quoted


@pytest.mark.parametrize("paper", ["a4", "letter"])
def test_a_small_boards_words_stay_readable(tmp_path, capsys, paper):
    # a 15 mm board centred on the page left its words the board's own width: 4.8 / 4.4 pt before
    args = ["--paper", paper, "--squares", "3x3", "--square-mm", "5", "--legacy", "--first-marker", "17", "--inverted"]
    out, _, _ = _board(tmp_path, capsys, *args)
    with pdfplumber.open(out) as pdf:
        (page,) = pdf.pages
        chars = page.chars
    assert min(char["size"] for char in chars) >= 5
    assert min(char["x0"] for char in chars) >= 5 * PT_PER_MM - 1e-6  # within the page's margins
    assert max(char["x1"] for char in chars) <= page.width - 5 * PT_PER_MM + 1e-6
