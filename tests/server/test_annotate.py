"""Pictures of what the pipeline saw (`lumipose locate --annotate`, `server.annotate`): the markers
land on the corners found, a refusal is pictured with its reason, a room's panels each get theirs."""

import json
from dataclasses import replace

import cv2
import numpy as np

from lumipose_cli.main import main
from server.annotate import CONTOUR, CORNER, REFUSED, annotate, display_px, display_scale, enlarged_part
from server.diagnostics import Diagnostics
from server.ingest import LumaFrame, read_fixture
from server.locator import locate
from server.options import LocateOptions
from server.outcomes import located
from server.pipeline import PipelineOptions
from server.rooms import locate_panel
from server.vision.beacons import find_beacon_blobs
from shared_schemas import DEMO_MAP_PATH, BeaconIdSource, FailureReason, LocateResult, load_map
from tests.conftest import FIXTURE
from tests.helpers import TWO_PANELS, WIDTH, two_panel_frame


def _annotated(frame: LumaFrame, beacon_map=None):
    diagnostics = Diagnostics()
    options = LocateOptions(pipeline=PipelineOptions(diagnostics=diagnostics))
    result = locate(frame, beacon_map or load_map(DEMO_MAP_PATH), options)
    return result, diagnostics, annotate(frame, diagnostics, result)


def _decoded(png: bytes) -> np.ndarray:
    image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    assert image is not None and image.ndim == 3
    return image


def _marker_pixels(image, corners_px, sights, result, size) -> np.ndarray:
    """The display pixels (BGR) where the main view draws `corners_px` (frame pixels)."""
    part = enlarged_part(sights, result, size)
    points = np.rint(display_px(np.asarray(corners_px), part, display_scale(part[2] - part[0], part[3] - part[1])))
    return np.array([image[int(y), int(x)] for x, y in points])


def _near(image: np.ndarray, colour, tolerance: int = 40) -> np.ndarray:
    return np.all(np.abs(image.astype(int) - colour) <= tolerance, axis=-1)


def test_the_corners_are_marked_where_the_pipeline_found_them():
    frame = read_fixture(FIXTURE)
    plain = locate(frame, load_map(DEMO_MAP_PATH))
    result, diagnostics, png = _annotated(frame)
    assert result.ok and result.position_m == plain.position_m  # recording changes nothing
    [sight] = diagnostics.panels
    assert sight.contour_px is not None and sight.sides_px.shape == (4, 25, 2) and sight.roi_px is not None
    image = _decoded(png)
    assert 600 <= image.shape[1] <= 2000 and 500 <= image.shape[0] <= 2000
    height, width = frame.pixels.shape
    markers = _marker_pixels(image, result.corners_px, diagnostics.panels, result, (width, height))
    assert (markers == CORNER).all(), markers
    # only the markers and numbers are pure green: a picture painted green all over would not pass
    assert (image == CORNER).all(axis=-1).mean() < 0.01
    # the sub-pixel sides pass within a pixel of the corners they meet at (the lines are the corners' own)
    assert np.abs(sight.sides_px[:, 0] - sight.sides_px[[3, 0, 1, 2], -1]).max() < 1e-6


def test_a_refusal_is_pictured_with_the_blob_found_and_its_reason():
    frame = read_fixture(FIXTURE)
    pixels = np.full_like(frame.pixels, 12)
    cv2.circle(pixels, (480, 700), 70, 250, -1)  # a round lamp, not the square panel
    result, diagnostics, png = _annotated(replace(frame, pixels=pixels))
    assert not result.ok and result.reason is FailureReason.not_a_square
    [sight] = diagnostics.panels
    assert sight.contour_px is not None and sight.sides_px is None
    image = _decoded(png)
    assert _near(image, CONTOUR).sum() > 100  # the lamp's contour is drawn
    assert _near(image, REFUSED).sum() > 50  # and the reason, in the refusal's colour
    assert not (image == CORNER).all(axis=-1).any()  # no corners: there is no fix


def test_a_frame_without_anything_is_the_whole_frame_with_the_reason():
    frame = read_fixture(FIXTURE)
    result, diagnostics, png = _annotated(replace(frame, pixels=np.full_like(frame.pixels, 12)))
    assert result.reason is FailureReason.no_beacon and diagnostics.panels[0].roi_px is None
    image = _decoded(png)
    assert _near(image, REFUSED).sum() > 50


def test_each_panel_of_a_room_is_marked_in_the_whole_frame():
    frame = two_panel_frame()
    found = find_beacon_blobs(frame.pixels)
    diagnostics = Diagnostics()
    fixes = []
    for blob in found.blobs:
        beacon = TWO_PANELS.beacons[0] if blob.centroid_px[0] < WIDTH / 2 else TWO_PANELS.beacons[1]
        others = [b for b in found.blobs if b is not blob]
        options = PipelineOptions(diagnostics=diagnostics)
        fixes.append(locate_panel(frame, blob, others, beacon, BeaconIdSource.vlc, options, found.levels))
    assert sorted(s.beacon_id for s in diagnostics.panels) == [17, 42]
    # each panel's crop lands back on the frame: the sights carry the frame's corners
    for sight, fix in zip(diagnostics.panels, fixes, strict=True):
        np.testing.assert_allclose(sight.outcome.corners_px, fix.corners_px)
        assert sight.contour_px[:, 0].min() > fix.corners_px[:, 0].min() - 3
    result = located(fixes[0])
    image = _decoded(annotate(frame, diagnostics, result))
    height, width = frame.pixels.shape
    for fix in fixes:
        markers = _marker_pixels(image, fix.corners_px, diagnostics.panels, result, (width, height))
        assert (markers == CORNER).all(), markers


def test_locate_annotate_writes_the_picture_and_says_when_it_cannot(tmp_path, capsys):
    picture = tmp_path / "seen.png"
    assert main(["locate", str(FIXTURE), "--annotate", str(picture), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ok"]
    assert _decoded(picture.read_bytes()).shape[0] > 500
    nowhere = tmp_path / "missing" / "seen.png"
    assert main(["locate", str(FIXTURE), "--annotate", str(nowhere), "--json"]) == 2
    error = json.loads(capsys.readouterr().out)
    assert error["field"] == "annotate" and str(nowhere) in error["message"]


def test_locate_refuses_a_picture_name_that_asks_for_another_format(tmp_path, capsys):
    """Issue 31: `--annotate seen.jpg` wrote PNG bytes under a JPEG's name; the picture is a PNG (lossless: the
    contour's pixels as drawn), so another suffix is refused, by the flag, before any work."""
    for name in ("seen.jpg", "seen.JPEG", "seen"):
        assert main(["locate", str(FIXTURE), "--annotate", str(tmp_path / name)]) == 2
        captured = capsys.readouterr()
        assert captured.out == "" and f"--annotate {tmp_path / name}: the picture is a PNG" in captured.err
        assert not (tmp_path / name).exists()
    assert main(["locate", str(FIXTURE), "--annotate", str(tmp_path / "seen.PNG")]) == 0
    assert capsys.readouterr().err == f"picture: {tmp_path / 'seen.PNG'}\n"


def test_panels_are_named_by_the_result_in_a_device_session_and_by_their_own_beacon_elsewhere():
    from server.annotate import _panel_name
    from server.diagnostics import PanelSight
    from server.outcomes import Fix, Refusal
    from shared_schemas import FailureReason, LocateResult, TrackState

    fixed = PanelSight(17, Fix(np.zeros(3), np.eye(3), 17, None, 0.1, False, center_px=np.array([100.0, 50.0])))
    other = PanelSight(17, Refusal(FailureReason.pose_uncertain, "unsure"))
    track = TrackState(filtered_position_m=[0, 0, 0], velocity_mps=[0, 0, 0], outlier=False)
    session = LocateResult(ok=True, beacon_id=42, center_px=[100.2, 50.0], track=track)  # measured on a template
    assert (_panel_name(fixed, session, True), _panel_name(other, session, True)) == ("beacon 42", "panel")
    refused = LocateResult(ok=False, reason=FailureReason.beacon_cut_off, message="cut")  # a session's, no track
    assert _panel_name(other, refused, True) == "panel"
    single = LocateResult(ok=True, beacon_id=17, center_px=[300.0, 50.0])
    assert (_panel_name(fixed, single, False), _panel_name(other, single, False)) == ("beacon 17", "beacon 17")


def _texts_drawn(monkeypatch) -> list[tuple[str, tuple[int, int], tuple[int, int]]]:
    """Every text the picture draws: (text, origin, the image's height and width), recorded as drawn."""
    drawn, put_text = [], cv2.putText

    def record(image, text, origin, *args):
        drawn.append((text, tuple(origin), image.shape[:2]))
        return put_text(image, text, origin, *args)

    monkeypatch.setattr(cv2, "putText", record)
    return drawn


def test_a_refusal_that_found_no_beacon_names_none(monkeypatch):
    """Issue 31: 'beacon 0: no_beacon' said a beacon was there and was not; a panel whose ID is unknown is a
    panel, not the template beacon it was measured against."""
    from server.diagnostics import PanelSight
    from server.outcomes import Refusal

    frame = read_fixture(FIXTURE)
    blob = np.array([[400.0, 600.0], [420.0, 600.0], [420.0, 620.0], [400.0, 620.0]])  # too small to be a panel
    labels = {}
    for reason in (FailureReason.no_beacon, FailureReason.unknown_beacon, FailureReason.not_a_square):
        diagnostics = Diagnostics()
        diagnostics.add(PanelSight(0, Refusal(reason, "why"), contour_px=blob))
        drawn = _texts_drawn(monkeypatch)
        annotate(frame, diagnostics, LocateResult(ok=False, reason=reason, message="why"))
        labels[reason] = drawn[0][0]
    assert labels == {
        FailureReason.no_beacon: "no_beacon",
        FailureReason.unknown_beacon: "panel: unknown_beacon",
        FailureReason.not_a_square: "beacon 0: not_a_square",
    }


def test_the_caption_counts_the_panels_as_the_result_does(monkeypatch):
    """Issue 31: a room refused for want of an ID said '0 panels tried' while its result's beacons_in_view was 2:
    the panels were seen, none was measured."""
    frame = two_panel_frame()
    drawn = _texts_drawn(monkeypatch)
    result, diagnostics, _ = _annotated(frame, TWO_PANELS)
    assert result.reason is FailureReason.unknown_beacon and result.beacons_in_view == 2 and not diagnostics.panels
    captions = [text for text, _, _ in drawn if text.startswith("frame pixels")]
    assert len(captions) == 1 and captions[0].endswith("; 2 panels in view, 0 measured"), captions
    drawn.clear()
    _annotated(read_fixture(FIXTURE))  # one panel's map: its path counts no blobs, it measured one
    assert [text for text, _, _ in drawn if text.startswith("frame pixels")][0].endswith("; 1 panel measured")


def test_the_label_of_a_panel_at_the_frames_top_is_whole_and_off_the_panel(tmp_path, monkeypatch):
    """Issue 31: at quarter scale a panel cut by the frame's top edge had its label drawn over it, cut off."""
    stem = tmp_path / "top"
    assert main(["render", str(stem), "--scale", "0.25", "--position", "0", "0.6", "0"]) == 0
    frame = read_fixture(stem.with_suffix(".json"))
    drawn = _texts_drawn(monkeypatch)
    result, diagnostics, _ = _annotated(frame)
    assert result.ok and diagnostics.panels[0].cut and diagnostics.panels[0].contour_px[:, 1].min() == 0
    [(text, (x, y), (height, width))] = [entry for entry in drawn if entry[0] == "beacon 0"]
    (text_width, text_height), below = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 1)
    assert x >= 0 and x + text_width <= width and y - text_height >= 0 and y + below <= height
    part = enlarged_part(diagnostics.panels, result, frame.pixels.shape[::-1])
    scale = display_scale(part[2] - part[0], part[3] - part[1])
    [sight] = diagnostics.panels
    panel_y = display_px(np.vstack([sight.contour_px, sight.outline_px]), part, scale)[:, 1]  # to the frame's edge
    assert y - text_height > panel_y.max() or y + below < panel_y.min()  # beside the panel, not over it
