"""Boards users already own, on real photos no one here made (issue 29): OpenCV's chessboard set against
OpenCV's published calibration of it, and caliscope's webcam frames of an inverted ChArUco board, one
camera mirrored. Sources, commits and licences: tests/fixtures/calibration/*/README.md."""

from functools import cache
from pathlib import Path

import cv2
import numpy as np
import pytest

from server.calibration.board import corner_points_m, detect_corners, find_board, refine_corners
from server.calibration.photos import find_views
from server.calibration.report import calibrate
from shared_schemas import device_profiles
from shared_schemas.calibration import BoardSpec, CalibrationReport

FIXTURES = Path(__file__).parents[2] / "fixtures" / "calibration"
# OpenCV's samples/data left01..14: 9 x 6 inner corners; the square's size does not change the intrinsics
CHESSBOARD = BoardSpec(kind="chessboard", squares_x=10, squares_y=7, square_m=0.025)
# OpenCV's samples/data/left_intrinsics.yml (tests/fixtures/calibration/opencv_left/README.md)
PUBLISHED = {"fx": 535.9157, "fy": 535.9157, "cx": 342.2832, "cy": 235.5708, "k1": -0.266373}
# caliscope's tests/sessions/prerecorded_calibration/charuco.toml
CALISCOPE = BoardSpec(squares_x=4, squares_y=5, square_m=0.054, marker_m=0.0405, dictionary="DICT_4X4_1000")


def _photos(folder: str, pattern: str = "*.jpg") -> list[tuple[str, bytes]]:
    return [(path.name, path.read_bytes()) for path in sorted((FIXTURES / folder).glob(pattern))]


@cache
def _chessboard_report() -> CalibrationReport:
    views, skipped = find_views(_photos("opencv_left"), CHESSBOARD)
    assert len(views) == 13 and not skipped
    return calibrate(views, CHESSBOARD, device_profiles()["xiaomi-mi8-front"])


@cache
def _caliscope_report() -> CalibrationReport:
    views, skipped = find_views(_photos("caliscope_charuco", "cam_1_*.jpg"), CALISCOPE)
    assert len(views) == 10 and not skipped, skipped
    return calibrate(views, CALISCOPE, device_profiles()["xiaomi-mi8-front"])


def _calibration_rms_px(spec: BoardSpec, corners: list[tuple[np.ndarray, np.ndarray]], size: tuple[int, int]) -> float:
    """OpenCV's calibration RMS of (ids, points) per view: the corners' noise, for one detector against another."""
    objects = [corner_points_m(spec, ids).astype(np.float32) for ids, _ in corners]
    return cv2.calibrateCamera(objects, [p.astype(np.float32) for _, p in corners], size, None, None)[0]


def test_opencvs_chessboards_calibrate_to_opencvs_published_result():
    report = _chessboard_report()
    fitted = report.fitted
    assert fitted is not None and (fitted.width, fitted.height) == (640, 480)
    errors = {
        "fx": fitted.fx - PUBLISHED["fx"],
        "fy": fitted.fy - PUBLISHED["fy"],
        "cx": fitted.cx - PUBLISHED["cx"],
        "cy": fitted.cy - PUBLISHED["cy"],
        "k1": fitted.distortion[0] - PUBLISHED["k1"],
    }
    assert all(abs(errors[name]) <= 3.0 for name in ("fx", "fy", "cx", "cy")), errors
    assert abs(errors["k1"]) <= 0.02, errors
    assert report.rms_px is not None and report.rms_px < 0.2  # OpenCV's own: 0.39 (cornerSubPix, 11 x 11)


def test_a_refused_set_keeps_its_fit_marked_untrusted_with_the_reasons():
    # OpenCV's 13 photos leave three corners of the frame empty: refused, its numbers still given
    report = _chessboard_report()
    assert not report.ok and report.profile is None
    assert report.fitted is not None and report.fitted.trusted is False
    assert any(advice.startswith("cover the corners") for advice in report.advice), report.advice
    assert report.message is not None and report.message.startswith("the set is not good enough")


def test_the_saddle_refinement_beats_opencvs_chessboard_corners():
    greys = [cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) for path in sorted((FIXTURES / "opencv_left").glob("*.jpg"))]
    found = [detect_corners(grey, CHESSBOARD) for grey in greys]
    assert all(corners is not None for corners in found)
    ours = [refine_corners(grey, CHESSBOARD, *corners) for grey, corners in zip(greys, found, strict=True)]
    assert all(corners is not None and len(corners[0]) == 54 for corners in ours)
    subpix = []
    for grey in greys:  # OpenCV's tutorial: findChessboardCorners, then cornerSubPix over 11 x 11
        _, points = cv2.findChessboardCorners(grey, (9, 6))
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
        points = cv2.cornerSubPix(grey, points, (11, 11), (-1, -1), criteria)
        subpix.append((np.arange(54), points.reshape(-1, 2)))
    rms = {
        name: _calibration_rms_px(CHESSBOARD, corners, (640, 480))  # type: ignore[arg-type]
        for name, corners in (("ours", ours), ("sb", found), ("subpix", subpix))
    }
    assert rms["ours"] < 0.8 * min(rms["sb"], rms["subpix"]), rms


def test_an_inverted_board_on_mirrored_frames_is_found_and_said():
    mirrored = _photos("caliscope_charuco", "cam_1_*.jpg")[0]
    plain = _photos("caliscope_charuco", "cam_0_*.jpg")[0]
    seen = {}
    for name, data in (mirrored, plain):
        view = find_board(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE), CALISCOPE, name)
        assert view is not None and len(view.corner_ids) == 12, name
        seen[name] = (view.inverted, view.mirrored)
    assert seen == {mirrored[0]: (True, True), plain[0]: (True, False)}
    report = _caliscope_report()
    assert all(view.inverted and view.mirrored for view in report.views)
    assert "board found inverted (white markers on black) on 10 of 10 photos" in (report.message or "")
    assert "photos were mirrored: un-mirrored before fitting (10 of 10)" in (report.message or "")


def test_webcam_frames_that_do_not_cover_the_frame_are_refused_with_their_fit():
    report = _caliscope_report()
    assert not report.ok and report.profile is None
    assert report.coverage < 0.5
    assert any(advice.startswith("cover the corners") for advice in report.advice), report.advice
    assert any(advice.startswith("cover more of the image") for advice in report.advice), report.advice
    fitted = report.fitted
    assert fitted is not None and fitted.trusted is False
    # a 1280 x 720 webcam: the principal point near the centre, the focal length of a ~80 degree lens
    assert abs(fitted.cx - 640) < 60 and abs(fitted.cy - 360) < 60 and 500 < fitted.fx < 1000, fitted


@pytest.mark.parametrize("camera", ["cam_0", "cam_1"])
def test_the_refined_charuco_corners_are_no_worse_than_opencvs(camera):
    corners = []
    for _, data in _photos("caliscope_charuco", f"{camera}_*.jpg"):
        grey = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
        grey = cv2.bitwise_not(cv2.flip(grey, 1) if camera == "cam_1" else grey)
        detected = detect_corners(grey, CALISCOPE)
        assert detected is not None
        corners.append((detected, refine_corners(grey, CALISCOPE, *detected)))
    opencv = _calibration_rms_px(CALISCOPE, [found for found, _ in corners], (1280, 720))
    ours = _calibration_rms_px(CALISCOPE, [refined for _, refined in corners], (1280, 720))  # type: ignore[misc]
    assert ours <= opencv, (ours, opencv)
