"""The fit and its verdict: a good set against the truth, the poor sets refused with their reason,
the covariance against OpenCV's, bad input named."""

import numpy as np
import pytest

from server.calibration.fit import fit_views
from server.calibration.lens import Lens, distortion_difference_px
from server.calibration.quality import image_part
from server.calibration.report import CalibrationInputError, CalibrationRules, calibrate
from shared_schemas import device_profiles
from simulator.board import PoseSet
from tests.calibration_photos import BOARD, HEIGHT, LENS, WIDTH, view_set

DEVICE = device_profiles()["xiaomi-mi8-front"]


def test_a_good_set_calibrates_near_the_truth():
    views = list(view_set(PoseSet.good))
    assert len(views) >= 10
    report = calibrate(views, BOARD, DEVICE, "mi8-test")
    assert report.ok, report.advice
    profile = report.profile
    assert profile.id == "mi8-test" and (profile.width, profile.height) == (WIDTH, HEIGHT)
    assert profile.name == DEVICE.name and profile.pixel_size_m == DEVICE.pixel_size_m
    p = profile.intrinsics
    assert p.views == len(views) and p.rms_px == pytest.approx(report.rms_px)
    # 640 x 480 and 12 views: far looser than the full-size bench's targets, and within 3 sigma
    for name, fitted, true in (
        ("fx", p.fx, LENS.fx),
        ("fy", p.fy, LENS.fy),
        ("cx", p.cx, LENS.cx),
        ("cy", p.cy, LENS.cy),
    ):
        assert abs(fitted - true) < max(3 * report.sigmas[name], 0.2), (name, fitted, true, report.sigmas[name])
    fitted = Lens(p.fx, p.fy, p.cx, p.cy, tuple(profile.distortion))
    assert distortion_difference_px(LENS, fitted, WIDTH, HEIGHT) < 0.3
    assert report.rms_px < 0.1 and report.distortion_sigma_px < 0.3 and report.coverage >= 0.75
    assert report.max_tilt_deg > 20 and all(10 <= v.tilt_deg <= 51 for v in report.views)
    assert all(0.25 < v.distance_m < 0.6 for v in report.views)


def test_the_covariance_is_opencvs_where_both_exist():
    fit = fit_views(list(view_set(PoseSet.good)), BOARD)
    assert np.allclose(np.sqrt(np.diag(fit.covariance)), fit.opencv_sigmas, rtol=1e-3)


def test_all_frontal_views_are_refused_for_their_tilt():
    report = calibrate(list(view_set(PoseSet.frontal)), BOARD, DEVICE)
    assert not report.ok and report.profile is None
    assert "tilt the board more: no view is tilted beyond 20 degrees" in report.advice
    assert report.max_tilt_deg < 5


def test_the_board_in_one_corner_only_is_refused_for_coverage():
    report = calibrate(list(view_set(PoseSet.corner)), BOARD, DEVICE)
    assert not report.ok and report.profile is None
    assert "cover the corners: no view reaches the bottom-right corner of the image" in report.advice
    assert report.coverage < 0.3 and sum(report.coverage_cells[-1]) == 0


def test_too_few_views_ask_for_more_photos():
    report = calibrate(list(view_set(PoseSet.good))[:5], BOARD, DEVICE)
    assert not report.ok and "more photos: 5 with the board found, at least 10 needed" in report.advice
    two = calibrate(list(view_set(PoseSet.good))[:2], BOARD, DEVICE)
    assert not two.ok and two.rms_px is None and "more photos: 2" in two.advice[0]


def test_views_of_two_sizes_are_bad_input():
    views = list(view_set(PoseSet.good))
    views[3] = views[3].model_copy(update={"width": 480, "height": 640})
    with pytest.raises(CalibrationInputError, match=rf"one size; got 480x640 \('{views[3].name}'\), 640x480"):
        calibrate(views, BOARD, DEVICE)


def test_views_from_another_board_are_bad_input():
    small = BOARD.model_copy(update={"squares_x": 4, "squares_y": 4})
    with pytest.raises(CalibrationInputError, match="is not on a 4 x 4 board"):
        calibrate(list(view_set(PoseSet.good)), small, DEVICE)


def test_a_view_with_too_few_corners_is_listed_with_a_note():
    views = list(view_set(PoseSet.good))
    views[0] = views[0].model_copy(
        update={"corner_ids": views[0].corner_ids[:3], "corners_px": views[0].corners_px[:3]}
    )
    report = calibrate(views, BOARD, DEVICE)
    note = next(v for v in report.views if v.name == views[0].name)
    assert note.rms_px is None and "too few corners (3" in note.note


def test_the_shift_jacobian_is_the_distortions_derivative():
    lens = Lens(500.0, 498.0, 320.0, 240.0, (0.05, -0.02, 1e-3, -5e-4, 0.01))
    points = np.array([[0.3, -0.2], [-0.4, 0.35], [0.0, 0.1]])
    jacobian = lens.shift_jacobian(points)
    for k in range(5):
        step = np.zeros(5)
        step[k] = 1e-6
        moved = Lens(lens.fx, lens.fy, lens.cx, lens.cy, tuple(lens.coefficients + step))
        ideal = points * [lens.fx, lens.fy] + [lens.cx, lens.cy]
        numeric = (moved.distort(ideal) - lens.distort(ideal)) / 1e-6
        assert np.allclose(jacobian[:, :, k], numeric, rtol=1e-4, atol=1e-6)


def test_the_distortion_difference_is_zero_for_one_lens_and_sees_a_change():
    assert distortion_difference_px(LENS, LENS, WIDTH, HEIGHT) < 1e-6
    other = Lens(LENS.fx, LENS.fy, LENS.cx, LENS.cy, (0.061, -0.03, 5e-4, -4e-4, 0.0))
    # k1 + 0.001 moves a point at normalised radius r by fx r^3 / 1000: the corner's r is ~0.7
    assert 0.1 < distortion_difference_px(LENS, other, WIDTH, HEIGHT) < 0.3


def test_the_report_names_the_fixed_terms_and_where_the_distortion_is_least_sharp():
    report = calibrate(list(view_set(PoseSet.good)), BOARD, DEVICE)
    # the tests' lens has k3 = 0, and 12 small views do not support one
    assert report.ok and "k3" in report.fixed_terms and report.profile.distortion[4] == 0 and report.sigmas["k3"] == 0
    assert "k3 fixed at 0 (the views do not support it" in report.message
    # 640 x 480 leaves the distortion less sharp than the 0.05 px of a full-size set: the message says where
    assert report.distortion_sigma_px > CalibrationRules().sharp_distortion_sigma_px
    assert f"the distortion is uncertain by up to {report.distortion_sigma_px:.3f} px at the " in report.message
    assert "more photos with the board reaching into it would sharpen it" in report.message
    strict = calibrate(
        list(view_set(PoseSet.good)), BOARD, DEVICE, rules=CalibrationRules(max_distortion_sigma_px=0.01)
    )
    assert not strict.ok and strict.profile is None
    assert any(
        a.startswith("more photos with the board reaching into the ") and "corner of the image" in a
        for a in strict.advice
    ), strict.advice


@pytest.mark.parametrize(
    ("point", "words"),
    [
        ((10, 10), "the top-left corner"),
        ((630, 470), "the bottom-right corner"),
        ((320, 5), "the top edge"),
        ((5, 240), "the left edge"),
        ((320, 240), "the centre"),
        ((639, 0), "the top-right corner"),
    ],
)
def test_image_parts_in_words(point, words):
    assert image_part(np.array(point, float), 640, 480) == words
