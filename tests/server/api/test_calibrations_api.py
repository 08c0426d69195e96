"""POST /v1/calibrations/views and POST /v1/calibrations against a real server: views, JSON and
multipart calibrations, and bad input answered with a clear 4xx."""

from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

from lumipose_client import LumiposeError
from server.calibration.board import find_board
from shared_schemas import CameraIntrinsics, FrameMeta
from shared_schemas.calibration import BoardSpec, BoardView, CalibrationReport, CalibrationRequest
from simulator.board import PoseSet
from tests.calibration_photos import BOARD, HEIGHT, WIDTH, encoded, photo_set, view_set

META = FrameMeta(width=WIDTH, height=HEIGHT, format="PNG", camera=CameraIntrinsics(fx=500, fy=500, cx=320, cy=240))


def _refusal(call) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call()
    return refused.value


def test_a_view_is_found_on_a_photo(client):
    photo = photo_set(PoseSet.good)[0][1]
    view = client.calibrate_view(encoded(photo), META, BOARD, name="shot-1")
    assert isinstance(view, BoardView) and view.name == "shot-1" and (view.width, view.height) == (WIDTH, HEIGHT)
    local = next(v for v in view_set(PoseSet.good) if v.name == "good-01")
    assert view.corner_ids == local.corner_ids and np.allclose(view.corners_px, local.corners_px)


def test_a_photo_without_board_or_with_another_board_is_422(client):
    blank = encoded(np.full((HEIGHT, WIDTH), 90, np.uint8))
    refused = _refusal(lambda: client.calibrate_view(blank, META, BOARD))
    assert refused.status == 422 and refused.body.error == "no_board" and "7 x 5 DICT_4X4_50" in refused.body.message
    other = BoardSpec.model_validate({**BOARD.model_dump(), "dictionary": "DICT_5X5_100"})
    photo = encoded(photo_set(PoseSet.good)[0][1])
    assert _refusal(lambda: client.calibrate_view(photo, META, other)).body.error == "no_board"


@pytest.mark.parametrize("header, message", [
    (None, "the board spec (JSON) is missing"),
    ("{not json", "not valid JSON"),
    ('{"squares_x": 7, "squares_y": 5, "square_m": 0.04, "marker_m": 0.05}', "must be smaller than square_m"),
])
def test_a_bad_board_header_is_422(server_url, header, message):
    headers = {"Content-Type": "image/png", "X-Lumipose-Frame": META.model_dump_json(exclude_none=True)}
    if header is not None:
        headers["X-Lumipose-Board"] = header
    response = httpx.post(f"{server_url}/v1/calibrations/views", content=encoded(photo_set()[0][0]), headers=headers)
    assert response.status_code == 422 and message in response.json()["message"], response.text
    assert response.json()["field"] == "X-Lumipose-Board"


def test_json_views_calibrate(client):
    request = CalibrationRequest(board=BOARD, views=list(view_set(PoseSet.good)), device="xiaomi-mi8-front",
                                 profile_id="mi8-api")
    report = client.calibrate(request)
    assert isinstance(report, CalibrationReport) and report.ok, report.advice
    assert report.profile.id == "mi8-api" and report.profile.intrinsics.views == len(request.views)


def test_a_poor_set_is_200_with_advice(client):
    report = client.calibrate(CalibrationRequest(board=BOARD, views=list(view_set(PoseSet.frontal)),
                                                 device="xiaomi-mi8-front"))
    assert not report.ok and report.profile is None
    assert "tilt the board more: no view is tilted beyond 20 degrees" in report.advice


def test_json_views_of_different_sizes_or_another_board_are_422(client):
    views = list(view_set(PoseSet.good))
    mixed = [views[0].model_copy(update={"width": 2 * WIDTH, "height": 2 * HEIGHT}), *views[1:]]  # corners on it
    mi8 = "xiaomi-mi8-front"
    refused = _refusal(lambda: client.calibrate(CalibrationRequest(board=BOARD, views=mixed, device=mi8)))
    assert refused.status == 422 and "must all have one size" in refused.body.message
    small = BoardSpec.model_validate({**BOARD.model_dump(), "squares_x": 4, "squares_y": 4})
    refused = _refusal(lambda: client.calibrate(CalibrationRequest(board=small, views=views, device=mi8)))
    assert refused.status == 422 and "is not on a 4 x 4 board" in refused.body.message
    unknown = _refusal(lambda: client.calibrate(CalibrationRequest(board=BOARD, views=views, device="nokia-3310")))
    assert unknown.status == 422 and unknown.body.field == "device" and "no device profile 'nokia-3310'" in \
        unknown.body.message


def _multipart(server_url, photos, board=BOARD.model_dump_json(), device="xiaomi-mi8-front", **fields):
    data = {"device": device, **fields}
    if board is not None:
        data["board"] = board
    # without photos a file of another field keeps the body multipart
    files = [("photos", (name, content, "image/png")) for name, content in photos] or [("note", ("n.txt", b"-"))]
    return httpx.post(f"{server_url}/v1/calibrations", data=data, files=files, timeout=120)


def test_multipart_photos_calibrate_and_list_a_photo_without_board(server_url):
    photos = [(f"p{k}.{'jpg' if k % 3 == 2 else 'png'}", encoded(p, ".jpg" if k % 3 == 2 else ".png"))
              for k, p in enumerate(photo_set(PoseSet.good)[0])]
    photos.append(("blank.png", encoded(np.full((HEIGHT, WIDTH), 90, np.uint8))))
    response = _multipart(server_url, photos, profile_id="mi8-photos")
    assert response.status_code == 200, response.text
    report = CalibrationReport.model_validate_json(response.content)
    assert report.ok and report.profile.id == "mi8-photos"
    assert any(v.name == "blank.png" and "no board found" in v.note for v in report.views)


@pytest.mark.parametrize("change, status, field, message", [
    ({"board": None}, 422, "board", "the board spec (JSON) is missing"),
    ({"device": "nokia-3310"}, 422, "device", "no device profile"),
    ({"profile_id": "bad id!"}, 422, "profile_id", "should match pattern"),
    ({"photos": [("a.png", b"not a photo")]}, 400, "photos", "no photo is readable"),
    ({"photos": "mixed"}, 422, "photos", "must all have one size"),
    ({"photos": []}, 422, "photos", "no photo was sent"),
])
def test_bad_multipart_input_is_named(server_url, change, status, field, message):
    good = [(f"p{k}.png", encoded(p)) for k, p in enumerate(photo_set(PoseSet.good)[0][:3])]
    photos = change.pop("photos", good)
    if photos == "mixed":
        photos = [*good, ("small.png", encoded(np.full((240, 320), 90, np.uint8)))]
    response = _multipart(server_url, photos, **change)
    assert response.status_code == status and response.json()["field"] == field, response.text
    assert message in response.json()["message"]


def test_another_content_type_is_415(server_url):
    response = httpx.post(f"{server_url}/v1/calibrations", content=b"x", headers={"Content-Type": "text/plain"})
    assert response.status_code == 415 and response.json()["field"] == "Content-Type"


def test_views_of_noise_are_refused_not_a_server_error(client):
    rng = np.random.default_rng(2)
    views = [BoardView(name=f"noise{k}", width=WIDTH, height=HEIGHT, corner_ids=list(range(20)),
                       corners_px=(rng.uniform(0, 1, (20, 2)) * [WIDTH - 1, HEIGHT - 1]).tolist()) for k in range(12)]
    report = client.calibrate(CalibrationRequest(board=BOARD, views=views, device="xiaomi-mi8-front"))
    assert not report.ok and report.profile is None and report.advice


def test_a_body_over_the_upload_limit_is_413_before_it_is_read(server_url):
    big = b"x" * (5 << 20)  # the test server's frame and photo limit is 4 MB
    response = httpx.post(f"{server_url}/v1/calibrations", content=big,
                          headers={"Content-Type": "multipart/form-data; boundary=x"}, timeout=30)
    assert response.status_code == 413 and response.json()["error"] == "too_large"


def test_a_stored_profile_is_a_calibrations_device(client):
    """`device` may name a stored profile (a phone the service learnt earlier), not only a bundled one;
    an unknown id is a 422 listing the known ones, stored ones included."""
    base = client.profile("xiaomi-mi8-front").model_copy(update={"id": "lab-phone", "name": "the lab's phone"})
    client.put_profile(base)
    try:
        request = CalibrationRequest(board=BOARD, views=list(view_set(PoseSet.good)), device="lab-phone")
        report = client.calibrate(request)
        assert report.ok and report.profile.id == "lab-phone-calibrated" and report.profile.name == "the lab's phone"
        unknown = _refusal(lambda: client.calibrate(request.model_copy(update={"device": "no-such-phone"})))
        assert unknown.status == 422 and unknown.body.field == "device" and "lab-phone" in unknown.body.message
    finally:
        client.delete_profile("lab-phone")  # the server is the session's: other tests list its profiles


def test_a_board_photo_needs_no_camera_and_is_turned_upright(server_url):
    import io

    from PIL import Image

    photo = photo_set(PoseSet.good)[0][1]
    local = next(v for v in view_set(PoseSet.good) if v.name == "good-01")
    headers = {"Content-Type": "image/png", "X-Lumipose-Board": BOARD.model_dump_json()}
    for orientation, turns in ((1, 0), (6, 1)):  # a phone's stored rows, shown a quarter clockwise
        exif = Image.Exif()
        exif[0x0112] = orientation
        buffer = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(np.rot90(photo, turns))).save(buffer, "PNG", exif=exif.tobytes())
        response = httpx.post(f"{server_url}/v1/calibrations/views", content=buffer.getvalue(), headers=headers)
        assert response.status_code == 200, response.text  # no EXIF focal, no ?profile=: the board needs none
        view = BoardView.model_validate(response.json())
        assert (view.width, view.height) == (WIDTH, HEIGHT)
        assert view.corner_ids == local.corner_ids and np.allclose(view.corners_px, local.corners_px, atol=1e-3)


@pytest.mark.parametrize("board, message", [
    ({"kind": "chessboard", "squares_x": 10, "squares_y": 7, "square_m": 0.025, "marker_m": 0.01},
     "board: Value error, a chessboard has no markers"),
    ({"squares_x": 7, "squares_y": 5, "square_m": 0.04, "marker_m": 0.028, "dictionary": "DICT_4X4_50",
      "first_marker_id": 40}, "needs 17 markers from id 40; DICT_4X4_50 has 50"),
    ({"kind": "hexagons", "squares_x": 7, "squares_y": 5, "square_m": 0.04}, "board.kind: Input should be"),
])
def test_a_board_spec_that_cannot_be_is_422_in_a_calibration_request(server_url, board, message):
    view = view_set(PoseSet.good)[0].model_dump()
    body = {"board": board, "views": [view], "device": "xiaomi-mi8-front"}
    response = httpx.post(f"{server_url}/v1/calibrations", json=body, timeout=60)
    assert response.status_code == 422 and message in response.json()["message"], response.text


def test_json_views_of_a_chessboard_calibrate_and_a_refused_fit_is_untrusted(client):
    board = BoardSpec(kind="chessboard", squares_x=10, squares_y=7, square_m=0.025)
    photos = sorted((Path(__file__).parents[2] / "fixtures" / "calibration" / "opencv_left").glob("*.jpg"))[:5]
    views = [find_board(np.asarray(Image.open(path)), board, path.name) for path in photos]
    report = client.calibrate(CalibrationRequest(board=board, views=views, device="xiaomi-mi8-front"))
    assert not report.ok and report.profile is None and report.fitted is not None and not report.fitted.trusted
    assert 500 < report.fitted.fx < 570 and report.advice
