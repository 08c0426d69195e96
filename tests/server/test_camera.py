"""A frame's camera from a profile table: stored (calibrated) profiles beside the bundled ones."""

import numpy as np
import pytest

from server.camera import intrinsics_from_profile, profile_table, resolve_camera
from server.ingest import decode_frame
from server.locator import locate
from server.outcomes import FrameError
from shared_schemas import DeviceProfile, device_profiles, load_map
from tests.helpers import CALIBRATED, DATASHEET, FRONT, LENS_HEIGHT, LENS_WIDTH, calibrated_lens_frame

POSITIONS_M = [(0.05, -0.03, 0.0), (-0.1, 0.08, 0.0), (0.12, 0.1, 0.0)]


def _error_mm(profile, position_m, seed) -> float:
    meta, data = calibrated_lens_frame(position_m, seed)
    result = locate(decode_frame(data, meta, profile_table([profile])), load_map())
    assert result.ok, result.message
    return 1000 * float(np.linalg.norm(np.subtract(result.position_m, position_m)))


def test_a_calibrated_profile_is_used_exactly_and_beats_the_datasheet():
    """Rendered through a lens with fx != fy and an off-centre principal point: located with its
    calibrated profile the fix is within 3 mm; with the datasheet pinhole (same id, no intrinsics)
    it is off by centimetres (the principal point alone is 15 px, 1.7 degrees, at this size)."""
    calibrated = [_error_mm(CALIBRATED, position, seed) for seed, position in enumerate(POSITIONS_M)]
    datasheet = [_error_mm(DATASHEET, position, seed) for seed, position in enumerate(POSITIONS_M)]
    assert max(calibrated) < 3.0, calibrated
    assert min(datasheet) > 20.0 and min(datasheet) > 10 * max(calibrated), (calibrated, datasheet)


def test_the_frame_gets_the_calibrated_pinhole_scaled_to_its_size():
    meta, _ = calibrated_lens_frame(POSITIONS_M[0])
    camera = resolve_camera(meta, profile_table([CALIBRATED]))
    measured, scale = CALIBRATED.intrinsics, LENS_WIDTH / CALIBRATED.width
    assert LENS_HEIGHT / CALIBRATED.height == scale  # the same aspect: no crop
    assert camera.fx == pytest.approx(measured.fx * scale) and camera.fy == pytest.approx(measured.fy * scale)
    assert camera.cx == pytest.approx((measured.cx + 0.5) * scale - 0.5)
    assert camera.cy == pytest.approx((measured.cy + 0.5) * scale - 0.5)


def test_an_unknown_profile_is_refused_listing_the_table():
    meta, _ = calibrated_lens_frame(POSITIONS_M[0])
    with pytest.raises(FrameError) as refused:
        resolve_camera(meta)  # the bundled profiles only
    assert refused.value.field == "camera.profile"
    assert "unknown device profile 'mi8-front-calibrated'; known: xiaomi-mi8-front, xiaomi-mi8-rear" in str(
        refused.value
    )
    assert resolve_camera(meta, profile_table([CALIBRATED])).fx > 0


def test_a_table_refuses_an_extra_profile_with_a_taken_id():
    with pytest.raises(ValueError, match="'xiaomi-mi8-front' has a bundled profile's id"):
        profile_table([FRONT])
    with pytest.raises(ValueError, match="another given profile's id"):
        profile_table([CALIBRATED, DATASHEET])


def _named(profile_id: str, name: str, calibrated: bool = False) -> DeviceProfile:
    rear = device_profiles()["xiaomi-mi8-rear"]
    intrinsics = intrinsics_from_profile(rear, rear.width, rear.height) if calibrated else None
    return rear.model_copy(update={"id": profile_id, "name": name, "intrinsics": intrinsics})


def test_exif_matches_whole_words_and_prefers_a_calibrated_profile():
    from server.camera import profile_for_exif
    from server.photos import PhotoExif

    table = {
        p.id: p
        for p in (
            _named("mi8-lite", "Xiaomi Mi 8 Lite rear camera"),
            _named("ip13-pro", "Apple iPhone 13 Pro rear camera"),
            _named("ip13", "Apple iPhone 13 rear camera"),
            _named("ip13-cal", "Apple iPhone 13 rear camera (calibrated)", calibrated=True),
        )
    }
    assert profile_for_exif(PhotoExif(make="Xiaomi", model="MI 8"), table) is None  # not the Lite
    assert profile_for_exif(PhotoExif(make="Xiaomi", model="MI 8 Lite"), table).id == "mi8-lite"
    assert profile_for_exif(PhotoExif(make="Apple", model="iPhone 13"), table).id == "ip13-cal"
    assert profile_for_exif(PhotoExif(make="Apple", model="iPhone 13", focal_length_mm=4.2), table).id == "ip13-cal"
    assert profile_for_exif(PhotoExif(make="Apple", model="iPhone 13 Pro"), table).id == "ip13-pro"
    assert profile_for_exif(PhotoExif(make="Apple", model="iPhone 1"), table) is None


def test_a_lens_the_table_lacks_gets_no_profile_of_the_phone():
    """A telephoto photo of a phone whose table knows only the wide camera: no profile (the nearest, another
    lens, would be a pinhole 40 % off with a profile's 1.5 % uncertainty); the 35 mm rule then takes it."""
    from server.camera import photo_camera, profile_for_exif
    from server.photos import PhotoExif
    from shared_schemas.models import CameraSource

    rear = device_profiles()["xiaomi-mi8-rear"]  # 4.216 mm
    table = {rear.id: rear}
    assert profile_for_exif(PhotoExif(make="Xiaomi", model="MI 8", focal_length_mm=4.22), table).id == rear.id
    assert profile_for_exif(PhotoExif(make="Xiaomi", model="MI 8", focal_length_mm=6.0), table) is None
    tele = PhotoExif(make="Xiaomi", model="MI 8", focal_length_mm=6.0, focal_35mm_mm=52.0)
    assert photo_camera(tele, (4032, 3024), table).source == CameraSource.exif_35mm


def test_a_bad_profile_file_is_named_by_field_not_dumped(tmp_path, capsys):
    from lumipose_cli.main import main

    bad = tmp_path / "bad.json"
    bad.write_text('{"id": "x", "width": -3}')
    for command in (
        ["locate", "photo.jpg"],
        ["fov"],
        ["survey", "p.jpg", "--map", "test-bench", "--anchor", "1", "--out", str(tmp_path / "m.json")],
    ):
        code = main([*command, "--profile", str(bad)])
        err = capsys.readouterr().err
        assert code == 2, (command, err)
        assert "cannot read the device profile" in err and str(bad) in err, err
        assert "errors.pydantic.dev" not in err and "validation error" not in err.lower(), err
