"""The board of a `BoardSpec` (ChArUco or plain chessboard), and its corners found on one photo (a `BoardView`).

Board frame: x along the board's width, y down its height, origin at its top-left corner,
metres; corner id i sits at ((i mod (squares_x - 1)) + 1, (i div (squares_x - 1)) + 1) squares,
on either kind. Image points are pixels with pixel centres at integers (OpenCV's convention).

Boards users already own are found as they come: printed inverted (white markers on black) or
photographed by a front camera that mirrors its photos. When the board is not found on the photo
as it is, `find_board` tries it inverted, mirrored, and both, and says which one worked; the corners
of a mirrored photo are those of the photo un-mirrored (flipped left-right back), the image the lens
really made, so a calibration of them is the real camera's.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from shared_schemas.calibration import BoardKind, BoardSpec, BoardView


@dataclass(frozen=True)
class BoardRules:
    # a view with fewer corners adds six pose unknowns for little: a handful of corners can be near collinear
    min_corners: int = 8
    # a corner further than this share of a square from where its neighbours (two squares around, through
    # a homography) put it was misread or belongs to another layout: lens distortion bends a 5 x 5 squares
    # patch by a few pixels at most (smaller misreads are the fit's outliers, `server.calibration.fit`)
    max_misfit_square: float = 0.1
    # more misfits than this share means the markers were read on another layout (a spec that does not match)
    max_misfit_share: float = 0.25
    patch_squares: int = 2  # the neighbours' reach, in squares
    # the saddle fit's window half-width and pre-blur, as shares of the white gap between a corner and the
    # nearest marker at the view's finest scale: window + 2 sigma stays inside the gap, so no marker edge
    # enters the fit (what biased cornerSubPix by 0.1-0.3 px on tilted views)
    window_share: float = 0.4
    min_window_px: int = 2
    max_window_px: int = 20
    saddle_iterations: int = 10
    # the saddle fit has converged when its step is below this, far below the corners' noise (~0.02 px), or
    # below 4 float32 steps at the corner's coordinates if that is more: getRectSubPix takes the window's centre
    # in float32 (2.4e-4 px apart beyond x or y = 2048, 4.9e-4 beyond 4096), so a smaller step is never taken
    # there and the fit dithers; a 1e-4 px tolerance dropped most corners in the lower half of a full-size
    # portrait photo (docs/calibration.md)
    saddle_tolerance_px: float = 1e-3
    # corners whose markers are cut by the frame's border are not detected, yet the corner itself may be
    # whole: predicted from their found neighbours (a local homography) and refined, one ring per round,
    # they bring the corners of the image into the fit, where the distortion is largest
    grow_rounds: int = 4
    min_neighbours: int = 6


def charuco_board(spec: BoardSpec) -> cv2.aruco.CharucoBoard:
    """OpenCV's ChArUco board for the spec (its layout, dictionary and marker ids); raises ValueError for a
    chessboard spec."""
    if spec.kind != BoardKind.charuco or spec.marker_m is None:
        raise ValueError("a chessboard has no ChArUco board")
    return _board(
        spec.squares_x,
        spec.squares_y,
        spec.square_m,
        spec.marker_m,
        spec.dictionary.value,
        spec.legacy,
        spec.first_marker_id,
    )


@functools.cache  # the models are not hashable; their values are
def _board(
    squares_x: int, squares_y: int, square_m: float, marker_m: float, dictionary: str, legacy: bool, first_id: int
) -> cv2.aruco.CharucoBoard:
    aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    ids = np.arange(first_id, first_id + squares_x * squares_y // 2, dtype=np.int32)
    board = cv2.aruco.CharucoBoard((squares_x, squares_y), square_m, marker_m, aruco, ids)
    board.setLegacyPattern(legacy)
    return board


def corner_points_m(spec: BoardSpec, corner_ids: list[int] | np.ndarray) -> np.ndarray:
    """Board-frame points (N, 3) of corner ids; raises ValueError for an id the board lacks."""
    ids = np.asarray(corner_ids, dtype=int)
    if ids.size and (ids.min() < 0 or ids.max() >= spec.inner_corners):
        raise ValueError(
            f"corner id {int(ids.max())} is not on a {spec.squares_x} x {spec.squares_y} board "
            f"({spec.inner_corners} corners)"
        )
    # OpenCV's CharucoBoard.getChessboardCorners, for either kind of board
    return np.column_stack([(_grid_cells(spec, ids) + 1) * spec.square_m, np.zeros(len(ids))])


def describe_board(spec: BoardSpec) -> str:
    """A spec in words: "7 x 5 DICT_4X4_50 board (squares 40.00 mm, markers 28.00 mm)",
    "10 x 7 chessboard (9 x 6 inner corners, squares 25.40 mm)"; a size off the 0.01 mm grid (a PNG's whole
    pixels) with 3 decimals."""
    square = f"squares {format_mm(spec.square_m)}"
    if spec.kind == BoardKind.chessboard or spec.marker_m is None:
        name = f"{spec.squares_x} x {spec.squares_y} chessboard"
        details = [f"{spec.squares_x - 1} x {spec.squares_y - 1} inner corners", square]
    else:
        name = f"{spec.squares_x} x {spec.squares_y} {spec.dictionary.value} board"
        details = [square, f"markers {format_mm(spec.marker_m)}"]
        details += ["legacy layout"] * spec.legacy + [f"first marker {spec.first_marker_id}"] * bool(
            spec.first_marker_id
        )
    return f"{name} ({', '.join(details + ['inverted'] * spec.inverted)})"


def format_mm(metres: float) -> str:
    """A printed size in mm: "24.00 mm" when it is a whole 0.01 mm, as a PDF board's are, else "24.003 mm"."""
    mm = metres * 1000
    return f"{mm:.2f} mm" if abs(mm - round(mm, 2)) < 1e-6 else f"{mm:.3f} mm"


def _grey(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] in (3, 4):
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    raise ValueError(f"an image must be grey (H, W) or colour (H, W, 3 or 4); got shape {image.shape}")


def _grid_cells(spec: BoardSpec, ids: np.ndarray) -> np.ndarray:
    """(column, row) of each corner id on the board's grid of inner corners."""
    return np.column_stack([ids % (spec.squares_x - 1), ids // (spec.squares_x - 1)])


def _within(spec: BoardSpec, corner_id: int, reach: int) -> list[int]:
    """Corner ids within `reach` squares of `corner_id` (Chebyshev distance on the grid), itself excluded."""
    cols, rows = spec.squares_x - 1, spec.squares_y - 1
    col, row = corner_id % cols, corner_id // cols
    return [
        r * cols + c
        for r in range(max(0, row - reach), min(rows, row + reach + 1))
        for c in range(max(0, col - reach), min(cols, col + reach + 1))
        if (r, c) != (row, col)
    ]


def _square_px(spec: BoardSpec, ids: np.ndarray, points: np.ndarray) -> float:
    """The smallest image distance (px) between two corners one square apart: the view's finest scale."""
    cols = spec.squares_x - 1
    where = {int(i): k for k, i in enumerate(ids)}
    steps = [
        np.linalg.norm(points[k] - points[where[i + step]])
        for i, k in where.items()
        for step in (1, cols)
        if (step == cols or (i + 1) % cols) and i + step in where
    ]
    return float(min(steps)) if steps else 0.0


def _saddle_window(gap_px: float, rules: BoardRules) -> tuple[int, float]:
    """The saddle fit's window half-width (px) and pre-blur sigma (px) for a view whose finest gap is `gap_px`."""
    radius = int(np.clip(round(rules.window_share * gap_px), rules.min_window_px, rules.max_window_px))
    return radius, max(1.0, (gap_px - radius) / 2)


def _saddle_points(
    smooth: np.ndarray, points: np.ndarray, radius: int, rules: BoardRules
) -> tuple[np.ndarray, np.ndarray]:
    """Corners refined to the saddle of the smoothed image, and which converged.

    A chessboard corner is point-symmetric (two straight edges crossing, opposite quadrants alike),
    and so is it after a Gaussian blur and under perspective (locally affine): the smoothed
    intensity's saddle point is the corner. A quadratic a x^2 + b x y + c y^2 + d x + e y + f
    fitted over the window gives the saddle; the window moves there and the fit repeats.
    `smooth` is the photo blurred by `_saddle_window`'s sigma.
    """
    side = 2 * radius + 1
    ys, xs = (axis.ravel() for axis in np.mgrid[-radius : radius + 1, -radius : radius + 1].astype(float))
    weight = np.exp(-(xs**2 + ys**2) / (2 * (radius / 1.5) ** 2))  # the window's centre counts most
    solver = np.linalg.pinv(np.column_stack([xs * xs, xs * ys, ys * ys, xs, ys, np.ones_like(xs)]) * weight[:, None])
    refined, converged = points.astype(float).copy(), np.zeros(len(points), bool)
    for k, start in enumerate(points):
        centre = start.astype(float)
        tolerance = max(rules.saddle_tolerance_px, 4 * float(np.spacing(np.float32(np.abs(centre).max()))))
        for _ in range(rules.saddle_iterations):
            patch = cv2.getRectSubPix(smooth, (side, side), (float(centre[0]), float(centre[1])))
            a, b, c, d, e, _ = solver @ (patch.ravel().astype(float) * weight)
            hessian = np.array([[2 * a, b], [b, 2 * c]])
            if np.linalg.det(hessian) >= 0:  # not a saddle: no corner here
                break
            step = np.linalg.solve(hessian, [-d, -e])
            centre = centre + step
            if np.linalg.norm(centre - start) > radius:  # wandered off
                break
            if np.linalg.norm(step) < tolerance:
                refined[k], converged[k] = centre, True
                break
    return refined, converged


def _predicted(
    spec: BoardSpec, where: dict[int, int], points: np.ndarray, corner_id: int, reach: int
) -> np.ndarray | None:
    """Where the known corners (`where`: id -> index into `points`) within `reach` squares put `corner_id`,
    through their homography grid -> pixels; None with fewer than five of them."""
    others = [where[i] for i in _within(spec, corner_id, reach) if i in where]
    if len(others) < 5:
        return None
    ids = np.array([i for i in _within(spec, corner_id, reach) if i in where])
    cells = _grid_cells(spec, ids).astype(float)
    homography, _ = cv2.findHomography(cells, points[others], 0)
    if homography is None:
        return None
    cell = _grid_cells(spec, np.array([corner_id])).astype(float).reshape(1, 1, 2)
    return cv2.perspectiveTransform(cell, homography).ravel()


def _grow(
    smooth: np.ndarray,
    spec: BoardSpec,
    ids: np.ndarray,
    points: np.ndarray,
    radius: int,
    margin_px: float,
    rules: BoardRules,
) -> tuple[np.ndarray, np.ndarray]:
    """Add the corners next to the found ones that the detector missed (their markers cut by the border)."""
    height, width = smooth.shape
    for _ in range(rules.grow_rounds):
        where = {int(i): k for k, i in enumerate(ids)}
        candidates = sorted({n for i in where for n in _within(spec, i, 1)} - set(where))
        predicted_ids, predicted = [], []
        for i in candidates:
            if sum(n in where for n in _within(spec, i, rules.patch_squares)) < rules.min_neighbours:
                continue
            point = _predicted(spec, where, points, i, rules.patch_squares)
            if (
                point is not None
                and margin_px <= point[0] <= width - 1 - margin_px
                and (margin_px <= point[1] <= height - 1 - margin_px)
            ):
                predicted_ids.append(i)
                predicted.append(point)
        if not predicted:
            break
        refined, converged = _saddle_points(smooth, np.array(predicted), radius, rules)
        if not converged.any():
            break
        ids = np.concatenate([ids, np.array(predicted_ids)[converged]])
        points = np.vstack([points, refined[converged]])
    return ids, points


def _misfits(spec: BoardSpec, ids: np.ndarray, points: np.ndarray, rules: BoardRules) -> np.ndarray:
    """Corners (bool mask) that their neighbours' local homography misplaces; the worst is dropped first."""
    dropped = np.zeros(len(ids), bool)
    while True:
        where = {int(i): k for k, i in enumerate(ids) if not dropped[k]}
        errors = np.zeros(len(ids))
        for i, k in where.items():
            point = _predicted(spec, where, points, i, rules.patch_squares)
            if point is not None:  # with too few neighbours to judge, the corner stays
                errors[k] = np.linalg.norm(point - points[k])
        worst = int(np.argmax(errors))
        if errors[worst] <= rules.max_misfit_square * _square_px(spec, ids[~dropped], points[~dropped]):
            return dropped
        dropped[worst] = True


def _charuco_corners(grey: np.ndarray, spec: BoardSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """OpenCV's ChArUco corners (ids, (N, 2) px) on a photo of a board printed as OpenCV draws it."""
    corners, ids, _, _ = cv2.aruco.CharucoDetector(charuco_board(spec)).detectBoard(grey)
    if ids is None:
        return None
    return ids.ravel().astype(int), corners.reshape(-1, 2).astype(float)


def _chessboard_corners(grey: np.ndarray, spec: BoardSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """OpenCV's corners of a whole chessboard (every inner corner, row by row) on a photo, or None.

    findChessboardCornersSB (Duda and Frese's localized radon transform) finds boards that
    findChessboardCorners misses (docs/calibration.md); a chessboard must be seen whole, as
    nothing tells its corners apart.
    """
    pattern = (spec.squares_x - 1, spec.squares_y - 1)
    found, corners = cv2.findChessboardCornersSB(grey, pattern, flags=cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        return None
    return np.arange(spec.inner_corners), corners.reshape(-1, 2).astype(float)


def _gap_share(spec: BoardSpec) -> float:
    """The white gap around a corner as a share of a square: to the nearest marker, or half a square on a
    chessboard (beyond it the next corner's edges enter)."""
    if spec.kind == BoardKind.chessboard or spec.marker_m is None:
        return 0.5
    return (spec.square_m - spec.marker_m) / (2 * spec.square_m)


def refine_corners(
    grey: np.ndarray, spec: BoardSpec, ids: np.ndarray, detected: np.ndarray, rules: BoardRules = BoardRules()
) -> tuple[np.ndarray, np.ndarray] | None:
    """A detector's corners refined to the smoothed photo's saddle points, the missed ones next to them grown
    in and the misplaced ones left out: (ids, (N, 2) px), or None when too few are left or too many misfit
    (markers read on a board of another layout: a spec that does not match the photo)."""
    # the detector's corners (its own cornerSubPix) are off by 0.05 px typically and 0.2 px on tilted
    # views; the saddle fit halves the first and removes most of the second (rendered boards, docs/calibration.md)
    gap_px = _square_px(spec, ids, detected) * _gap_share(spec)
    radius, sigma = _saddle_window(gap_px, rules)
    smooth = cv2.GaussianBlur(grey.astype(np.float32), (0, 0), sigma)
    refined, converged = _saddle_points(smooth, detected, radius, rules)
    ids, refined = ids[converged], refined[converged]
    if len(ids) < rules.min_corners:
        return None
    # the window and its blur must lie inside the frame: a border replicated into it breaks the symmetry
    ids, refined = _grow(smooth, spec, ids, refined, radius, radius + 3 * sigma + 1, rules)
    misfits = _misfits(spec, ids, refined, rules)
    if misfits.mean() > rules.max_misfit_share or np.sum(~misfits) < rules.min_corners:
        return None
    return ids[~misfits], refined[~misfits]


def detect_corners(grey: np.ndarray, spec: BoardSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """OpenCV's own corners of the board (ids, (N, 2) px) on a grey photo as it is, before any refinement."""
    return (_chessboard_corners if spec.kind == BoardKind.chessboard else _charuco_corners)(grey, spec)


def attempts(spec: BoardSpec, first: tuple[bool, bool] | None = None) -> list[tuple[bool, bool]]:
    """The (inverted, mirrored) ways a photo is tried, in order: `first` (what worked on the photo before),
    then the photo as printed per the spec, inverted, mirrored, both. A chessboard is the same inverted
    (a shift by one square) and mirrored (a board seen from another side): tried as it is only."""
    if spec.kind == BoardKind.chessboard:
        return [(False, False)]
    ways = [(spec.inverted, False), (not spec.inverted, False), (spec.inverted, True), (not spec.inverted, True)]
    return sorted(ways, key=lambda way: way != first)


def find_board(
    image: np.ndarray,
    spec: BoardSpec,
    name: str,
    rules: BoardRules = BoardRules(),
    first: tuple[bool, bool] | None = None,
) -> BoardView | None:
    """The board's corners (sub-pixel) on a grey or colour photo (uint8); None when no board is found.

    Tried as `attempts` says; the view says whether the board was found `inverted` and on the photo
    `mirrored` (then its corners are those of the photo flipped left-right: the un-mirrored image).
    Corners their neighbours misplace are left out (`refine_corners`).
    """
    grey = _grey(np.asarray(image))
    if grey.dtype != np.uint8:
        raise ValueError(f"an image must be 8-bit; got {grey.dtype}")
    height, width = grey.shape
    for inverted, mirrored in attempts(spec, first):
        seen = cv2.flip(grey, 1) if mirrored else grey
        seen = cv2.bitwise_not(seen) if inverted else seen
        detected = detect_corners(seen, spec)
        if detected is None or len(detected[0]) < rules.min_corners:
            continue
        corners = refine_corners(seen, spec, *detected, rules)
        if corners is None:
            continue
        ids, points = corners
        return BoardView(
            name=name,
            width=width,
            height=height,
            corner_ids=ids.tolist(),
            corners_px=[[float(x), float(y)] for x, y in points],
            inverted=inverted,
            mirrored=mirrored,
        )
    return None
