"""`lumipose bench boards`: the boards users already own, on real photos no one here made (issue 29).

Two public sets, shipped under tests/fixtures/calibration/ (sources, commits, licences in their READMEs):
- OpenCV's chessboard photos `samples/data/left01..14.jpg` (9 x 6 inner corners, 640 x 480): the
  calibration against OpenCV's published one (`samples/data/left_intrinsics.yml`), and the calibration
  RMS of each corner finder: OpenCV's findChessboardCornersSB, findChessboardCorners + cornerSubPix
  (OpenCV's tutorial: 11 x 11 window), and each of the two refined by our saddle fit;
- caliscope's webcam frames of an inverted 4 x 5 DICT_4X4_1000 ChArUco board (one camera mirrored):
  how each was found, the report's verdict, and the calibration RMS of OpenCV's CharucoDetector
  corners against ours. `--videos DIR` reads every frame of caliscope's `cam_*.mp4` there instead.

The calibration RMS (OpenCV's calibrateCamera on one detector's corners) measures the corners' noise
and bias together: the same photos and the same model, only the corners differ.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from server.calibration.board import corner_points_m, detect_corners, find_board, refine_corners
from server.calibration.report import calibrate
from shared_schemas import device_profiles
from shared_schemas.calibration import BoardSpec, BoardView

FIXTURES = Path(__file__).parents[1] / "tests" / "fixtures" / "calibration"
CHESSBOARD = BoardSpec(kind="chessboard", squares_x=10, squares_y=7, square_m=0.025)
# OpenCV's samples/data/left_intrinsics.yml (tests/fixtures/calibration/opencv_left/README.md)
PUBLISHED = {"fx": 535.9157, "fy": 535.9157, "cx": 342.2832, "cy": 235.5708, "k1": -0.266373, "rms_px": 0.3926}
# caliscope's tests/sessions/prerecorded_calibration/charuco.toml: 5.4 cm squares, markers 0.75 of them
CALISCOPE = BoardSpec(squares_x=4, squares_y=5, square_m=0.054, marker_m=0.0405, dictionary="DICT_4X4_1000")
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)

Corners = tuple[np.ndarray, np.ndarray]  # corner ids, (N, 2) px


def calibration_rms_px(spec: BoardSpec, corners: list[Corners], size: tuple[int, int]) -> float:
    """OpenCV's calibration RMS (px) over views given as (ids, points): one corner finder against another."""
    objects = [corner_points_m(spec, ids).astype(np.float32) for ids, _ in corners]
    return float(cv2.calibrateCamera(objects, [p.astype(np.float32) for _, p in corners], size, None, None)[0])


def chessboard_corners(grey: np.ndarray, spec: BoardSpec = CHESSBOARD) -> dict[str, Corners | None]:
    """One photo's chessboard corners by each finder: OpenCV's two, and each refined by the saddle fit."""
    sb = detect_corners(grey, spec)
    pattern = (spec.squares_x - 1, spec.squares_y - 1)
    found, points = cv2.findChessboardCorners(grey, pattern)
    subpix = None
    if found:
        points = cv2.cornerSubPix(grey, points, (11, 11), (-1, -1), SUBPIX_CRITERIA)
        subpix = (np.arange(spec.inner_corners), points.reshape(-1, 2).astype(float))
    return {
        "findChessboardCornersSB": sb,
        "findChessboardCornersSB + saddle": None if sb is None else refine_corners(grey, spec, *sb),
        "findChessboardCorners + cornerSubPix": subpix,
        "findChessboardCorners + saddle": None if subpix is None else refine_corners(grey, spec, *subpix),
    }


def charuco_corners(grey: np.ndarray, spec: BoardSpec = CALISCOPE) -> tuple[Corners, Corners] | None:
    """OpenCV's CharucoDetector corners and ours on a photo as the board is found (inverted, un-mirrored)."""
    view = find_board(grey, spec, "frame")
    if view is None:
        return None
    seen = cv2.flip(grey, 1) if view.mirrored else grey
    seen = cv2.bitwise_not(seen) if view.inverted else seen
    detected = detect_corners(seen, spec)
    if detected is None:
        return None
    return detected, (np.asarray(view.corner_ids), np.asarray(view.corners_px))


def _chessboard_bench() -> dict:
    greys = [cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) for path in sorted((FIXTURES / "opencv_left").glob("*.jpg"))]
    per_photo = [chessboard_corners(grey) for grey in greys]
    rms = {}
    for finder in per_photo[0]:
        found = [corners[finder] for corners in per_photo]
        rms[finder] = {
            "photos": sum(c is not None for c in found),
            "rms_px": calibration_rms_px(CHESSBOARD, [c for c in found if c is not None], (640, 480)),
        }
    views = [
        find_board(grey, CHESSBOARD, path.name)
        for grey, path in zip(greys, sorted((FIXTURES / "opencv_left").glob("*.jpg")), strict=True)
    ]
    report = calibrate([v for v in views if v is not None], CHESSBOARD, device_profiles()["xiaomi-mi8-front"])
    fitted = report.fitted
    ours = (
        {}
        if fitted is None
        else {
            "fx": fitted.fx,
            "fy": fitted.fy,
            "cx": fitted.cx,
            "cy": fitted.cy,
            "k1": fitted.distortion[0],
            "rms_px": report.rms_px,
        }
    )
    return {
        "photos": len(greys),
        "rms_by_finder": rms,
        "fit": ours,
        "published": PUBLISHED,
        "ok": report.ok,
        "trusted": None if fitted is None else fitted.trusted,
        "advice": report.advice,
    }


def _frames(videos: Path | None) -> dict[str, list[np.ndarray]]:
    """Grey frames per camera: the shipped ones, or every frame of caliscope's videos in `videos`."""
    cameras: dict[str, list[np.ndarray]] = {}
    if videos is None:
        for path in sorted((FIXTURES / "caliscope_charuco").glob("*.jpg")):
            camera = path.name.split("_frame")[0]
            cameras.setdefault(camera, []).append(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE))
        return cameras
    for path in sorted(videos.glob("cam_*.mp4")):
        capture = cv2.VideoCapture(str(path))
        frames = cameras.setdefault(path.stem, [])
        while True:
            read, frame = capture.read()
            if not read:
                break
            frames.append(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
    return cameras


def _charuco_bench(videos: Path | None) -> dict:
    result = {}
    for camera, greys in _frames(videos).items():
        views = [find_board(grey, CALISCOPE, f"{camera}-{k}") for k, grey in enumerate(greys)]
        found: list[BoardView] = [v for v in views if v is not None]
        pairs = [p for p in (charuco_corners(grey) for grey in greys) if p is not None]
        height, width = greys[0].shape
        entry: dict = {
            "frames": len(greys),
            "found": len(found),
            "inverted": sum(v.inverted for v in found),
            "mirrored": sum(v.mirrored for v in found),
        }
        if len(pairs) >= 3:
            entry["rms_px"] = {
                "CharucoDetector": calibration_rms_px(CALISCOPE, [opencv for opencv, _ in pairs], (width, height)),
                "saddle": calibration_rms_px(CALISCOPE, [ours for _, ours in pairs], (width, height)),
            }
        if len(found) >= 3:
            report = calibrate(found, CALISCOPE, device_profiles()["xiaomi-mi8-front"])
            entry.update(ok=report.ok, coverage=report.coverage, advice=report.advice, message=report.message)
            if report.fitted is not None:
                entry["fitted"] = report.fitted.model_dump()
        result[camera] = entry
    return result


def bench_boards(videos: Path | None = None) -> dict:
    return {"opencv_chessboard": _chessboard_bench(), "caliscope_charuco": _charuco_bench(videos)}


def format_boards(result: dict) -> str:
    chess = result["opencv_chessboard"]
    lines = [
        f"OpenCV's chessboards (left01..14, {chess['photos']} photos, 640 x 480): calibration RMS per corner finder"
    ]
    lines += [f"  {name:40s} {v['rms_px']:.3f} px ({v['photos']} photos)" for name, v in chess["rms_by_finder"].items()]
    fit, published = chess["fit"], chess["published"]
    lines.append("  fit against OpenCV's published calibration (samples/data/left_intrinsics.yml):")
    lines += [
        f"    {name:6s} {fit[name]:10.4f}  published {published[name]:10.4f}  "
        f"difference {fit[name] - published[name]:+.4f}"
        for name in ("fx", "fy", "cx", "cy", "k1", "rms_px")
        if name in fit
    ]
    lines.append(
        f"  verdict: {'ok' if chess['ok'] else 'refused'} (trusted {chess['trusted']}): {'; '.join(chess['advice'])}"
    )
    lines.append("caliscope's inverted 4 x 5 DICT_4X4_1000 ChArUco board (1280 x 720 webcams):")
    for camera, entry in result["caliscope_charuco"].items():
        lines.append(
            f"  {camera}: found on {entry['found']} of {entry['frames']} frames "
            f"({entry['inverted']} inverted, {entry['mirrored']} mirrored)"
        )
        if "rms_px" in entry:
            rms = entry["rms_px"]
            lines.append(
                f"    calibration RMS: CharucoDetector {rms['CharucoDetector']:.3f} px, saddle {rms['saddle']:.3f} px"
            )
        if "fitted" in entry:
            f = entry["fitted"]
            lines.append(
                f"    {'ok' if entry['ok'] else 'refused'} (coverage {100 * entry['coverage']:.0f} %), fitted "
                f"fx {f['fx']:.1f} fy {f['fy']:.1f} cx {f['cx']:.1f} cy {f['cy']:.1f} k1 {f['distortion'][0]:+.3f}"
                f" (trusted {f['trusted']})"
            )
    return "\n".join(lines)
