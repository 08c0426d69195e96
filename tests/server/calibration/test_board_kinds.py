"""Every kind of board a spec describes (issue 29): printed by `printing`, found by `find_board` with the right
spec and not with a wrong one; inverted prints and mirrored photos found and said."""

import cv2
import numpy as np
import pytest
from pydantic import ValidationError

from server.calibration.board import find_board
from server.calibration.printing import board_image, printed_spec, spec_json
from shared_schemas.calibration import BoardSpec

DPI = 60.0  # 24 mm squares of 57 px: small images, markers still read


def _spec(**fields) -> BoardSpec:
    return BoardSpec(**{"squares_x": 6, "squares_y": 4, "square_m": 0.024, "marker_m": 0.016, **fields})


def _printed(spec: BoardSpec) -> tuple[BoardSpec, np.ndarray]:
    printed = printed_spec(spec, DPI)
    return printed, board_image(printed, DPI)


KINDS = {
    "chessboard": dict(kind="chessboard", marker_m=None),
    "apriltag, first marker 100": dict(dictionary="DICT_APRILTAG_36h11", first_marker_id=100),
    "legacy layout": dict(dictionary="DICT_6X6_250", legacy=True),
    "7x7": dict(dictionary="DICT_7X7_50"),
    "aruco original": dict(dictionary="DICT_ARUCO_ORIGINAL"),
    "inverted": dict(dictionary="DICT_4X4_1000", inverted=True),
}


@pytest.mark.parametrize("fields", KINDS.values(), ids=KINDS.keys())
def test_each_kind_of_board_is_printed_and_found_whole(fields):
    spec, image = _printed(_spec(**fields))
    view = find_board(image, spec, "print")
    assert view is not None and sorted(view.corner_ids) == list(range(spec.inner_corners))
    assert view.inverted == spec.inverted and not view.mirrored


@pytest.mark.parametrize(
    ("printed", "wrong"),
    [
        (dict(dictionary="DICT_APRILTAG_36h11", first_marker_id=100), dict(dictionary="DICT_APRILTAG_36h11")),
        (dict(dictionary="DICT_6X6_250", legacy=True), dict(dictionary="DICT_6X6_250")),
    ],
    ids=["first marker", "legacy layout"],
)
def test_a_spec_missing_the_boards_layout_does_not_find_it(printed, wrong):
    _, image = _printed(_spec(**printed))
    assert find_board(image, printed_spec(_spec(**wrong), DPI), "print") is None


def test_an_inverted_print_is_found_with_a_plain_spec_and_said():
    spec, image = _printed(_spec(dictionary="DICT_5X5_50"))
    view = find_board(255 - image, spec, "inverted")
    assert view is not None and view.inverted and len(view.corner_ids) == spec.inner_corners


def test_a_mirrored_photo_gives_the_unmirrored_photos_corners():
    spec, image = _printed(_spec(dictionary="DICT_5X5_50"))
    plain, mirrored = find_board(image, spec, "plain"), find_board(cv2.flip(image, 1), spec, "mirrored")
    assert plain is not None and mirrored is not None and mirrored.mirrored and not plain.mirrored
    order = np.argsort(mirrored.corner_ids)
    assert np.array(mirrored.corner_ids)[order].tolist() == sorted(plain.corner_ids)
    unmirrored = np.asarray(mirrored.corners_px)[order]
    assert np.abs(unmirrored - np.asarray(plain.corners_px)[np.argsort(plain.corner_ids)]).max() < 0.01


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        (dict(kind="chessboard"), "a chessboard has no markers"),
        (dict(kind="chessboard", marker_m=None, dictionary="DICT_4X4_50"), "first_marker_id and dictionary are"),
        (dict(kind="chessboard", marker_m=None, dictionary="DICT_5X5_100"), "a chessboard has no markers"),
        (dict(marker_m=None), "a ChArUco board needs marker_m"),
        (dict(dictionary="DICT_4X4_50", first_marker_id=40), "needs 12 markers from id 40; DICT_4X4_50 has 50"),
        (dict(dictionary="DICT_APRILTAG_16h5", squares_x=9, squares_y=9), "DICT_APRILTAG_16h5 has 30"),
        (dict(dictionary="DICT_8X8_50"), "Input should be"),
    ],
)
def test_a_spec_that_cannot_be_is_refused_saying_why(fields, message):
    with pytest.raises(ValidationError, match=message):
        _spec(**fields)


def test_a_chessboards_spec_is_written_without_a_dictionary_and_read_back():
    chessboard = _spec(kind="chessboard", marker_m=None)
    for written in (spec_json(chessboard), chessboard.model_dump_json(by_alias=True)):
        assert "dictionary" not in written and BoardSpec.model_validate_json(written) == chessboard
    assert "dictionary" in spec_json(_spec()) and "dictionary" in _spec().model_dump_json()
