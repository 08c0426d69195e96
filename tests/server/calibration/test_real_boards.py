"""Boards users already own, on real photos no one here made (issue 29): OpenCV's chessboard set against
OpenCV's published calibration of it, and caliscope's webcam frames of an inverted ChArUco board, one
camera mirrored. Sources, commits and licences: tests/fixtures/calibration/*/README.md."""

from functools import cache

import cv2
import numpy as np
import pytest

from server.calibration.board import find_board
from server.calibration.photos import find_views
from server.calibration.report import calibrate
from shared_schemas import device_profiles
from shared_schemas.calibration import CalibrationReport
from simulator.bench_boards import (
    CALISCOPE,
    CHESSBOARD,
    FIXTURES,
    PUBLISHED,
    calibration_rms_px,
    charuco_corners,
    chessboard_corners,
)


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
    per_photo = [chessboard_corners(grey) for grey in greys]
    rms = {}
    for finder in per_photo[0]:
        found = [corners[finder] for corners in per_photo]
        assert all(corners is not None and len(corners[0]) == 54 for corners in found), finder
        rms[finder] = calibration_rms_px(CHESSBOARD, found, (640, 480))
    # OpenCV's two finders (the tutorial's cornerSubPix over 11 x 11), each refined by the saddle fit
    opencv = min(rms["findChessboardCornersSB"], rms["findChessboardCorners + cornerSubPix"])
    ours = max(rms["findChessboardCornersSB + saddle"], rms["findChessboardCorners + saddle"])
    assert ours < 0.8 * opencv, rms


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
    pairs = []
    for _, data in _photos("caliscope_charuco", f"{camera}_*.jpg"):
        pair = charuco_corners(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE))
        assert pair is not None
        pairs.append(pair)
    opencv = calibration_rms_px(CALISCOPE, [found for found, _ in pairs], (1280, 720))
    ours = calibration_rms_px(CALISCOPE, [refined for _, refined in pairs], (1280, 720))
    assert ours <= opencv, (ours, opencv)
