"""`lumipose calibrate board` and `lumipose calibrate camera`: files, exit codes, bad input named."""

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from lumipose_cli.main import main
from server.calibration.board import find_board
from shared_schemas import DeviceProfile
from shared_schemas.calibration import BoardSpec, CalibrationReport
from simulator.board import PoseSet
from tests.calibration_photos import BOARD, encoded, photo_set


@pytest.fixture(scope="module")
def shots(tmp_path_factory):
    """The good set as PNG (grey and colour) and JPEG files, the frontal set, and board.json."""
    folder = tmp_path_factory.mktemp("shots")
    (folder / "board.json").write_text(BOARD.model_dump_json(by_alias=True))
    good = []
    for k, photo in enumerate(photo_set(PoseSet.good)[0]):
        extension = ".jpg" if k % 4 == 3 else ".png"
        path = folder / f"good{k:02d}{extension}"
        path.write_bytes(encoded(photo, extension, colour=k % 2 == 1))
        good.append(path)
    frontal = []
    for k, photo in enumerate(photo_set(PoseSet.frontal)[0]):
        frontal.append(folder / f"frontal{k:02d}.png")
        frontal[-1].write_bytes(encoded(photo))
    return folder, good, frontal


def _camera(shots, photos, *extra):
    folder, _, _ = shots
    return main(["calibrate", "camera", *map(str, photos), "--board", str(folder / "board.json"),
                 "--device", "xiaomi-mi8-front", *extra])


def test_board_pdf_is_at_true_scale_with_its_spec(tmp_path, capsys):
    out = tmp_path / "board.pdf"
    assert main(["calibrate", "board", "--out", str(out), "--squares", "5x4", "--square-mm", "30", "--dpi", "300"]) == 0
    spec = BoardSpec.model_validate_json((tmp_path / "board.json").read_text())
    assert (spec.squares_x, spec.squares_y, spec.dictionary.value) == (5, 4, "DICT_5X5_100")
    assert (spec.square_m, spec.marker_m) == (0.030, 0.018)  # vectors: the sizes asked, --dpi is a PNG's
    text = out.read_bytes()
    assert text.startswith(b"%PDF")
    # an A4 page, landscape, in points (1/72 inch); tests/server/calibration/test_printing.py reads it whole
    box = [float(v) for v in text.split(b"/MediaBox [")[1].split(b"]")[0].split()]
    assert (box[2] / 72 * 25.4, box[3] / 72 * 25.4) == (pytest.approx(297, abs=1e-3), pytest.approx(210, abs=1e-3))
    assert "print at 100 %" in capsys.readouterr().out


def test_board_png_is_found_whole(tmp_path):
    out = tmp_path / "screen.png"
    assert main(["calibrate", "board", "--out", str(out), "--squares", "6x5", "--square-mm", "20", "--dpi", "100"]) == 0
    spec = BoardSpec.model_validate_json((tmp_path / "screen.json").read_text())
    image = np.asarray(Image.open(out))
    assert Image.open(out).info["dpi"][0] == pytest.approx(100, abs=0.01)  # PNG stores dots per metre
    view = find_board(image, spec, "screen")
    assert view is not None and len(view.corner_ids) == spec.inner_corners


@pytest.mark.parametrize("args, message", [
    (["--squares", "11by8"], "--squares must be like 11x8"),
    (["--squares", "2x8"], "squares_x"),
    (["--square-mm", "20", "--marker-mm", "25"], "must be smaller than square_m"),
    (["--squares", "20x20", "--dictionary", "DICT_4X4_50"], "needs 200 markers"),
])
def test_bad_board_options_are_named(tmp_path, capsys, args, message):
    assert main(["calibrate", "board", "--out", str(tmp_path / "b.pdf"), *args]) == 2
    assert message in capsys.readouterr().err


def test_board_needs_pdf_or_png(tmp_path, capsys):
    assert main(["calibrate", "board", "--out", str(tmp_path / "b.svg")]) == 2
    assert "must end in .pdf or .png" in capsys.readouterr().err


def test_camera_calibrates_writes_the_profile_and_lists_a_photo_without_board(shots, tmp_path, capsys):
    folder, good, _ = shots
    blank = folder / "blank.png"
    blank.write_bytes(encoded(np.full((480, 640), 100, np.uint8)))
    out = tmp_path / "profile.json"
    assert _camera(shots, [*good, blank], "--id", "mi8-cal", "--out", str(out)) == 0
    text = capsys.readouterr().out
    assert "profile  mi8-cal at 640x480" in text and "coverage" in text and "ok: calibrated from" in text
    assert "blank.png" in text and "no board found" in text
    profile = DeviceProfile.model_validate_json(out.read_text())
    assert profile.id == "mi8-cal" and profile.intrinsics is not None and len(profile.distortion) == 5


def test_camera_json_prints_the_report(shots, capsys):
    assert _camera(shots, shots[1], "--json") == 0
    report = CalibrationReport.model_validate_json(capsys.readouterr().out)
    assert report.ok and report.profile.id == "xiaomi-mi8-front-calibrated"


def test_a_frontal_set_is_refused_with_its_advice(shots, capsys):
    assert _camera(shots, shots[2]) == 1
    text = capsys.readouterr().out
    assert "refused:" in text and "advice: tilt the board more: no view is tilted beyond 20 degrees" in text


def test_photos_of_mixed_sizes_are_bad_input(shots, tmp_path, capsys):
    other = tmp_path / "other.png"
    other.write_bytes(encoded(np.full((360, 480), 100, np.uint8)))
    assert _camera(shots, [*shots[1][:3], other]) == 2
    assert "must all have one size; got 480x360" in capsys.readouterr().err


def test_no_readable_photo_is_bad_input(tmp_path, shots, capsys):
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not a photo")
    assert _camera(shots, [junk]) == 2
    assert "no photo is readable" in capsys.readouterr().err


def test_an_invalid_board_spec_is_bad_input(shots, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"squares_x": 7, "squares_y": 5, "square_m": 0.04, "marker_m": 0.05}))
    assert main(["calibrate", "camera", str(shots[1][0]), "--board", str(bad), "--device", "xiaomi-mi8-front"]) == 2
    assert "is not a board spec" in capsys.readouterr().err


def test_a_board_spec_that_does_not_match_refuses(shots, tmp_path, capsys):
    other = tmp_path / "other.json"
    other.write_text(BoardSpec.model_validate({**BOARD.model_dump(), "dictionary": "DICT_6X6_250"}).model_dump_json())
    assert main(["calibrate", "camera", *map(str, shots[1][:3]), "--board", str(other),
                 "--device", "xiaomi-mi8-front"]) == 1
    assert "no photo shows the board" in capsys.readouterr().out


def test_an_unknown_device_is_bad_input(shots, capsys):
    folder, good, _ = shots
    assert main(["calibrate", "camera", str(good[0]), "--board", str(folder / "board.json"),
                 "--device", "nokia-3310"]) == 2
    assert "neither a bundled profile" in capsys.readouterr().err


def test_board_prints_a_chessboard_and_its_spec(tmp_path, capsys):
    out = tmp_path / "chess.png"
    args = ["--kind", "chessboard", "--squares", "10x7", "--square-mm", "25", "--dpi", "60"]
    assert main(["calibrate", "board", "--out", str(out), *args]) == 0
    assert "10 x 7 chessboard (9 x 6 inner corners" in capsys.readouterr().out
    spec = BoardSpec.model_validate_json((tmp_path / "chess.json").read_text())
    assert (spec.kind.value, spec.marker_m) == ("chessboard", None)
    assert "dictionary" not in (tmp_path / "chess.json").read_text()
    view = find_board(np.asarray(Image.open(out)), spec, "chess")
    assert view is not None and len(view.corner_ids) == 54


def test_board_prints_a_charuco_board_of_any_layout(tmp_path):
    out = tmp_path / "tag.png"
    args = ["--squares", "6x4", "--dictionary", "DICT_APRILTAG_36h11", "--legacy", "--first-marker", "7", "--inverted"]
    assert main(["calibrate", "board", "--out", str(out), "--dpi", "60", *args]) == 0
    spec = BoardSpec.model_validate_json((tmp_path / "tag.json").read_text())
    assert (spec.dictionary.value, spec.legacy, spec.first_marker_id, spec.inverted) == ("DICT_APRILTAG_36h11", True, 7,
                                                                                         True)
    view = find_board(np.asarray(Image.open(out)), spec, "tag")
    assert view is not None and view.inverted and len(view.corner_ids) == spec.inner_corners


@pytest.mark.parametrize("option", [["--legacy"], ["--dictionary", "DICT_4X4_50"]])
def test_a_chessboard_with_a_charuco_option_is_bad_input(tmp_path, capsys, option):
    assert main(["calibrate", "board", "--out", str(tmp_path / "c.png"), "--kind", "chessboard", *option]) == 2
    assert "a chessboard has no markers" in capsys.readouterr().err
    assert not (tmp_path / "c.json").exists()


def test_camera_prints_a_refused_sets_fit_as_not_trusted(capsys):
    # five of OpenCV's own chessboard photos (tests/fixtures/calibration/opencv_left): too few to trust
    photos = sorted((Path(__file__).parents[1] / "fixtures" / "calibration" / "opencv_left").glob("*.jpg"))[:5]
    board = '{"kind": "chessboard", "squares_x": 10, "squares_y": 7, "square_m": 0.025}'  # the spec itself
    assert main(["calibrate", "camera", *map(str, photos), "--board", board, "--device", "xiaomi-mi8-front"]) == 1
    text = capsys.readouterr().out
    assert "fitted   at 640x480, NOT TRUSTED: the set was refused" in text and "pinhole  fx 5" in text, text
    assert "refused: " in text and "advice: more photos: 5 with the board found" in text


def test_the_default_boards_json_keeps_its_fields(tmp_path):
    # app builds before issue 29 (BoardSpec.fromJson) refuse fields they do not know: the fields added for other boards
    # are written only when a board needs them
    assert main(["calibrate", "board", "--out", str(tmp_path / "b.png"), "--dpi", "60"]) == 0
    written = json.loads((tmp_path / "b.json").read_text())
    assert set(written) == {"schema", "squares_x", "squares_y", "square_m", "marker_m", "dictionary"}


def test_only_unreadable_photos_are_bad_input_naming_each(tmp_path, shots, capsys):
    # a file that is no image, and a PNG whose header reads but whose pixels are cut off
    junk, cut = tmp_path / "junk.jpg", tmp_path / "cut.png"
    junk.write_bytes(b"not a photo")
    cut.write_bytes(encoded(photo_set(PoseSet.good)[0][0])[:3000])
    assert _camera(shots, [junk, cut]) == 2
    err = capsys.readouterr().err
    assert f"no photo is readable (2 given): '{junk}' is not a readable JPEG, PNG or HEIC photo" in err, err
    assert f"; '{cut}' cannot be decoded (damaged or truncated" in err


def test_readable_photos_without_the_board_are_refused_naming_the_unreadable_ones(tmp_path, shots, capsys):
    # exit 1 (the spec may not match the print), but the unreadable photos are no clue to the spec: named
    junk, blank = tmp_path / "junk.jpg", tmp_path / "blank.png"
    junk.write_bytes(b"not a photo")
    blank.write_bytes(encoded(np.full((480, 640), 100, np.uint8)))
    assert _camera(shots, [junk, blank]) == 1
    out = capsys.readouterr().out
    assert "refused: no readable photo shows the board (1 read, 1 unreadable: " in out and "junk.jpg): does" in out


def test_photos_are_turned_upright_by_their_exif_orientation(shots, tmp_path, capsys):
    # the set as a phone held in portrait stores it: the rows turned a quarter, EXIF orientation 6 to show it
    # upright; the profile is of the upright photos, as the same photos stored upright give
    stored, profiles = [], {}
    for k, photo in enumerate(photo_set(PoseSet.good)[0]):
        exif = Image.Exif()
        exif[0x0112] = 6
        stored.append(tmp_path / f"turned{k:02d}.png")
        Image.fromarray(np.ascontiguousarray(np.rot90(photo, 1))).save(stored[-1], "PNG", exif=exif.tobytes())
    for name, photos in (("upright", shots[1]), ("turned", stored)):
        assert _camera(shots, photos, "--out", str(tmp_path / f"{name}.json")) == 0
        profiles[name] = DeviceProfile.model_validate_json((tmp_path / f"{name}.json").read_text())
    assert (profiles["turned"].width, profiles["turned"].height) == (640, 480)
    assert profiles["turned"].intrinsics.fx == pytest.approx(profiles["upright"].intrinsics.fx, rel=1e-3)
    assert profiles["turned"].intrinsics.cx == pytest.approx(profiles["upright"].intrinsics.cx, abs=0.5)
    capsys.readouterr()
    doc = (Path(__file__).parents[2] / "docs" / "calibration.md").read_text()
    assert "each photo is turned upright by its exif orientation" in " ".join(doc.lower().split())
