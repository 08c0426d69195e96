"""`lumipose locate PHOTO`: JPEG, PNG and HEIC photos with their EXIF, the intrinsics chosen and how sure."""

import functools
import io
import json
import struct
import zlib

import httpx
import numpy as np
import pytest
from PIL import Image

from lumipose_cli.main import main
from server.camera import FOCAL_SIGMA_EXIF_35MM, FULL_FRAME_DIAGONAL_MM, intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.photos import HEIC_READABLE, read_photo, turn_upright
from shared_schemas import DEMO_MAP_PATH, BeaconMap, device_profiles, load_map
from simulator.render import CameraPose, SensorModel, render_frame

REAR = device_profiles()["xiaomi-mi8-rear"]
WIDTH, HEIGHT = 378, 504  # the rear camera's upright 3024 x 4032 at 1/8
CAMERA = intrinsics_from_profile(REAR, WIDTH, HEIGHT)
PANEL = load_map(DEMO_MAP_PATH).beacons[0]  # the service's active map by default: nothing to store or clean up
TRUTH = np.array([0.04, -0.03, 0.4])
DISTANCE_M = float(np.linalg.norm(np.array(PANEL.center_m) - TRUTH))


@functools.cache
def upright_frame() -> np.ndarray:
    """The panel as the phone, held upright, sees it (portrait, like the bundled profiles)."""
    pose = CameraPose(TRUTH, rotation_from_ypr(15.0, 3.0, -2.0))
    return render_frame(PANEL, CAMERA, pose, WIDTH, HEIGHT, SensorModel(), np.random.default_rng(3))


def jpeg(pixels: np.ndarray, **tags) -> bytes:
    """An RGB JPEG (as phones write them) of grey `pixels` with EXIF: make, model, focal, focal_35mm, orientation."""
    exif = Image.Exif()
    for tag, value in ((0x010F, tags.get("make")), (0x0110, tags.get("model")), (0x0112, tags.get("orientation"))):
        if value is not None:
            exif[tag] = value
    shot = exif.get_ifd(0x8769)
    shot[0x829A], shot[0x8827] = 0.01, 200  # 1/100 s at ISO 200
    if "focal" in tags:
        shot[0x920A] = tags["focal"]
    if "focal_35mm" in tags:
        shot[0xA405] = tags["focal_35mm"]
    buffer = io.BytesIO()
    Image.fromarray(np.stack([pixels] * 3, axis=-1)).save(buffer, "JPEG", quality=95, exif=exif.tobytes())
    return buffer.getvalue()


@pytest.fixture
def room(tmp_path):
    path = tmp_path / "room.json"
    path.write_text(BeaconMap(name="room", beacons=[PANEL]).model_dump_json(by_alias=True))
    return path


def locate(capsys, photo, room, *flags) -> tuple[int, dict]:
    code = main(["locate", str(photo), "--map", str(room), "--json", *flags])
    return code, json.loads(capsys.readouterr().out)


def assert_near_truth(result: dict, tolerance_m: float) -> None:
    assert result["ok"], result
    assert np.linalg.norm(np.array(result["position_m"]) - TRUTH) < tolerance_m, result["position_m"]


def test_jpeg_luma_is_the_stored_y_channel_and_exif_is_read():
    photo = read_photo(jpeg(upright_frame(), make="Xiaomi", model="MI 8", focal=4.22, orientation=6), "a.jpg")
    assert photo.kind == "JPEG" and photo.pixels.shape == (HEIGHT, WIDTH)
    assert np.abs(photo.pixels.astype(int) - upright_frame()).mean() < 1.0
    assert (photo.exif.make, photo.exif.model, photo.exif.orientation) == ("Xiaomi", "MI 8", 6)
    assert photo.exif.exposure_s == pytest.approx(0.01) and photo.exif.iso == 200
    assert photo.exif.focal_length_mm == pytest.approx(4.22)


@pytest.mark.parametrize("stored", ["portrait", "landscape"])
def test_exif_make_and_model_pick_the_profile_in_either_stored_orientation(tmp_path, capsys, room, stored):
    # A phone stores its sensor's landscape rows and says "turn 90 degrees clockwise" (orientation 6).
    pixels, orientation = upright_frame(), 1
    if stored == "landscape":
        pixels, orientation = np.ascontiguousarray(np.rot90(upright_frame())), 6
        assert np.array_equal(turn_upright(pixels, 6), upright_frame())
    photo = tmp_path / "photo.jpg"
    photo.write_bytes(jpeg(pixels, make="Xiaomi", model="MI 8", focal=4.22, orientation=orientation))
    code, result = locate(capsys, photo, room)
    assert code == 0
    assert_near_truth(result, 0.005)  # the datasheet profile is the render's camera
    used = result["camera_used"]
    assert (used["source"], used["profile"], used["focal_sigma_rel"]) == ("exif_profile", "xiaomi-mi8-rear", 0.015)
    assert used["fx"] == pytest.approx(CAMERA.fx) and used["cx"] == pytest.approx(CAMERA.cx)
    assert main(["locate", str(photo), "--map", str(room)]) == 0
    out = capsys.readouterr().out
    assert "EXIF 'Xiaomi MI 8' -> datasheet profile 'xiaomi-mi8-rear'" in out and "focal uncertainty 1.5 %" in out


def test_only_the_35mm_equivalent_gives_a_rougher_camera(tmp_path, capsys, room):
    focal_35mm = round(CAMERA.fx / np.hypot(WIDTH, HEIGHT) * FULL_FRAME_DIAGONAL_MM)
    photo = tmp_path / "photo.jpg"
    photo.write_bytes(jpeg(upright_frame(), focal_35mm=focal_35mm))
    code, result = locate(capsys, photo, room)
    assert code == 0
    assert_near_truth(result, 3 * FOCAL_SIGMA_EXIF_35MM * DISTANCE_M)
    assert result["camera_used"]["source"] == "exif_35mm"
    assert result["camera_used"]["focal_sigma_rel"] == FOCAL_SIGMA_EXIF_35MM
    assert main(["locate", str(photo), "--map", str(room)]) == 0
    assert f"EXIF 35 mm equivalent focal length {focal_35mm} mm" in capsys.readouterr().out


def test_camera_flag_wins_and_a_png_needs_no_json(tmp_path, capsys, room):
    photo = tmp_path / "photo.png"
    Image.fromarray(np.stack([upright_frame()] * 3, axis=-1)).save(photo)  # RGB PNG, no EXIF
    flag = f"{CAMERA.fx},{CAMERA.fy},{CAMERA.cx},{CAMERA.cy}"
    code, result = locate(capsys, photo, room, "--camera", flag, "--profile", "xiaomi-mi8-front")
    assert code == 0
    assert_near_truth(result, 0.005)
    assert result["camera_used"]["source"] == "camera" and result["camera_used"]["focal_sigma_rel"] is None
    code, result = locate(capsys, photo, room, "--profile", "xiaomi-mi8-rear")
    assert code == 0
    assert_near_truth(result, 0.005)
    code, result = locate(capsys, photo, room, "--camera", "1,2,3")
    assert code == 2 and result["field"] == "camera" and "4 to 9 numbers" in result["message"]


@pytest.mark.skipif(not HEIC_READABLE, reason="pillow-heif is not installed")
def test_heic_photo(tmp_path, capsys, room):
    photo = tmp_path / "photo.heic"
    Image.fromarray(np.stack([upright_frame()] * 3, axis=-1)).save(photo, "HEIF", quality=95)
    code, result = locate(capsys, photo, room, "--profile", "xiaomi-mi8-rear")
    assert code == 0
    assert_near_truth(result, 0.01)


def png_claiming(width: int, height: int) -> bytes:
    """A few hundred bytes whose header says `width` x `height` grey pixels (a decompression bomb's shape)."""

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
    return b"\x89PNG\r\n\x1a\n" + header + chunk(b"IDAT", zlib.compress(b"\0" * 1000)) + chunk(b"IEND", b"")


def test_bad_photos_exit_2_with_the_contract_error(tmp_path, capsys, room):
    bare = tmp_path / "bare.jpg"
    bare.write_bytes(jpeg(upright_frame()))
    code, error = locate(capsys, bare, room)
    assert code == 2 and error["field"] == "camera" and "--profile" in error["message"]
    unknown = tmp_path / "unknown.jpg"
    unknown.write_bytes(jpeg(upright_frame(), make="Acme", model="Phone 1"))
    code, error = locate(capsys, unknown, room)
    assert code == 2 and "'Acme Phone 1' matches no profile" in error["message"]
    truncated = tmp_path / "truncated.jpg"
    truncated.write_bytes(jpeg(upright_frame(), make="Xiaomi", model="MI 8")[:3000])
    code, error = locate(capsys, truncated, room)
    assert code == 2 and error["error"] == "bad_frame" and "damaged or truncated" in error["message"]
    huge = tmp_path / "huge.png"
    huge.write_bytes(png_claiming(12_000, 9_000))
    code, error = locate(capsys, huge, room, "--profile", "xiaomi-mi8-rear")
    assert code == 2 and "12000x9000 pixels, more than 100 megapixels" in error["message"]
    huge.write_bytes(png_claiming(20_000, 20_000))  # beyond Pillow's own bomb limit too
    code, error = locate(capsys, huge, room, "--profile", "xiaomi-mi8-rear")
    assert code == 2 and "more than 100 megapixels" in error["message"]
    code, error = locate(capsys, bare, room, "--profile", "no-such-phone")
    assert code == 2 and error["field"] == "profile" and "xiaomi-mi8-rear" in error["message"]


def test_fov_takes_a_profile_name_or_file(capsys):
    assert main(["fov", "--profile", "xiaomi-mi8-rear"]) == 0
    by_name = capsys.readouterr().out
    assert main(["fov", "--profile", "shared_schemas/profiles/xiaomi-mi8-rear.json"]) == 2  # the bundled id is taken
    assert "has a bundled profile's id" in capsys.readouterr().err
    assert main(["fov", "--profile", "no-such-phone"]) == 2
    assert "known: xiaomi-mi8-front, xiaomi-mi8-rear" in capsys.readouterr().err
    assert "sensor" in by_name


def test_photo_over_http_with_a_profile_name(server_url, capsys, tmp_path):
    photo = tmp_path / "photo.jpg"
    photo.write_bytes(jpeg(upright_frame()))  # no EXIF camera: the profile comes from the query
    assert main(["client", "--url", server_url, "locate", str(photo), "--profile", "xiaomi-mi8-rear"]) == 0
    assert_near_truth(json.loads(capsys.readouterr().out), 0.005)
    exif = tmp_path / "exif.jpg"
    exif.write_bytes(jpeg(np.ascontiguousarray(np.rot90(upright_frame())), make="Xiaomi", model="MI 8", orientation=6))
    assert main(["client", "--url", server_url, "locate", str(exif)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert_near_truth(result, 0.005)
    assert result["camera_used"]["source"] == "exif_profile" and "orientation 6" in result["camera_used"]["detail"]
    assert main(["client", "--url", server_url, "locate", str(photo)]) == 2
    assert "--profile" in capsys.readouterr().err
    truncated = tmp_path / "truncated.jpg"
    truncated.write_bytes(photo.read_bytes()[:2000])
    assert main(["client", "--url", server_url, "locate", str(truncated), "--profile", "xiaomi-mi8-rear"]) == 2
    assert "damaged or truncated" in capsys.readouterr().err
    with httpx.Client(base_url=server_url) as http:
        response = http.post(
            "/v1/locate", params={"profile": "xiaomi-mi8-rear"}, content=truncated.read_bytes(),
            headers={"Content-Type": "image/jpeg"},
        )
        assert response.status_code == 400 and response.json()["error"] == "bad_frame"
        assert "damaged or truncated" in response.json()["message"]
        files = {"frame": ("photo.jpg", photo.read_bytes(), "image/jpeg")}
        response = http.post("/v1/locate", params={"profile": "xiaomi-mi8-rear"}, files=files)
        assert response.status_code == 200 and response.json()["ok"], response.text
        response = http.post("/v1/locate", params={"profile": "nope"}, content=photo.read_bytes(),
                             headers={"Content-Type": "image/jpeg"})
        assert response.status_code == 404 and response.json()["field"] == "profile"
