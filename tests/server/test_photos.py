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
from server.camera import FOCAL_SIGMA_EXIF_35MM, FULL_FRAME_DIAGONAL_MM, intrinsics_from_profile, turn_intrinsics
from server.geometry import rotation_from_ypr
from server.photos import HEIC_READABLE, read_photo
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
    photo = read_photo(jpeg(upright_frame(), make="Xiaomi", model="MI 8", focal=4.22, orientation=1), "a.jpg")
    assert photo.kind == "JPEG" and photo.pixels.shape == (HEIGHT, WIDTH)
    assert np.abs(photo.pixels.astype(int) - upright_frame()).mean() < 1.0
    assert (photo.exif.make, photo.exif.model, photo.exif.orientation) == ("Xiaomi", "MI 8", 1)
    assert photo.exif.exposure_s == pytest.approx(0.01) and photo.exif.iso == 200
    assert photo.exif.focal_length_mm == pytest.approx(4.22)


@pytest.mark.parametrize("stored", ["portrait", "landscape"])
def test_exif_make_and_model_pick_the_profile_in_either_stored_orientation(tmp_path, capsys, room, stored):
    # A phone stores its sensor's landscape rows and says "turn 90 degrees clockwise" (orientation 6).
    pixels, orientation = upright_frame(), 1
    if stored == "landscape":
        pixels, orientation = np.ascontiguousarray(np.rot90(upright_frame())), 6
        assert np.abs(read_photo(jpeg(pixels, orientation=6), 'p.jpg').pixels.astype(int) - upright_frame()).mean() < 1
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
    assert code == 2 and "12000x9000 pixels, more than the 100 megapixels allowed" in error["message"]
    huge.write_bytes(png_claiming(30_000, 30_000))  # beyond Pillow's own bomb limit too (2 x MAX_JPEG_PIXELS)
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
    assert main(["client", "--url", server_url, "locate", str(photo), "--profile", "xiaomi-mi8-rear", "--json"]) == 0
    assert_near_truth(json.loads(capsys.readouterr().out), 0.005)
    exif = tmp_path / "exif.jpg"
    exif.write_bytes(jpeg(np.ascontiguousarray(np.rot90(upright_frame())), make="Xiaomi", model="MI 8", orientation=6))
    assert main(["client", "--url", server_url, "locate", str(exif), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert_near_truth(result, 0.005)
    assert result["camera_used"]["source"] == "exif_profile" and "EXIF orientation 6" in result["camera_used"]["detail"]
    assert main(["client", "--url", server_url, "locate", str(photo)]) == 2
    # the command's message names its flags (issue 31); the API's own names its query parameters (below)
    error = capsys.readouterr().err
    assert "pass --profile ID (known: " in error and " or --camera fx,fy,cx,cy" in error and "?" not in error, error
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


# One orientation rule (issue 15 review): the photo is turned upright by its EXIF rotation on every path.
STORED = {1: 0, 6: 1, 3: 2, 8: 3}  # EXIF orientation -> np.rot90 turns (counter-clockwise) of the upright image
SHIFTED = CAMERA.model_copy(update={"cx": CAMERA.cx + 14.0, "cy": CAMERA.cy - 9.0})  # off-centre, as calibrated


@functools.cache
def shifted_frame() -> np.ndarray:
    pose = CameraPose(TRUTH, rotation_from_ypr(15.0, 3.0, -2.0))
    return render_frame(PANEL, SHIFTED, pose, WIDTH, HEIGHT, SensorModel(), np.random.default_rng(3))


def exif_png(pixels: np.ndarray, orientation: int, **tags) -> bytes:
    """A grey PNG (lossless: each orientation stores the same pixels) with EXIF orientation, make, model, 35 mm."""
    exif = Image.Exif()
    exif[0x0112] = orientation
    for tag, key in ((0x010F, "make"), (0x0110, "model")):
        if key in tags:
            exif[tag] = tags[key]
    if "focal_35mm" in tags:
        exif.get_ifd(0x8769)[0xA405] = tags["focal_35mm"]
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, "PNG", exif=exif.tobytes())
    return buffer.getvalue()


def calibrated_profile(path, camera, width: int, height: int, profile_id: str):
    profile = REAR.model_copy(update={"id": profile_id, "width": width, "height": height, "intrinsics": camera})
    path.write_text(profile.model_dump_json(by_alias=True))
    return path


def test_turn_intrinsics_matches_turning_the_projected_pixels():
    import cv2

    camera = CAMERA.model_copy(update={"cx": 170.0, "cy": 260.0, "fy": CAMERA.fy * 1.01})
    camera = camera.model_copy(update={"distortion": [0.08, -0.03, 0.004, -0.002, 0.01]})
    rng = np.random.default_rng(1)
    points = np.column_stack([rng.uniform(-0.4, 0.4, 30), rng.uniform(-0.5, 0.5, 30), rng.uniform(0.8, 2, 30)])

    def project(cam, xyz):
        k = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1.0]])
        return cv2.projectPoints(xyz, np.zeros(3), np.zeros(3), k, np.array(cam.distortion))[0].reshape(-1, 2)

    u, v = project(camera, points).T
    x, y, z = points.T
    turns = {  # orientation: (pixels turned upright, the camera's axes turned alike)
        6: (np.column_stack([HEIGHT - 1 - v, u]), np.column_stack([-y, x, z])),
        8: (np.column_stack([v, WIDTH - 1 - u]), np.column_stack([y, -x, z])),
        3: (np.column_stack([WIDTH - 1 - u, HEIGHT - 1 - v]), np.column_stack([-x, -y, z])),
    }
    for orientation, (pixels, turned_points) in turns.items():
        turned = turn_intrinsics(camera, WIDTH, HEIGHT, orientation)
        assert np.abs(project(turned, turned_points) - pixels).max() < 1e-6, orientation


@pytest.mark.parametrize("orientation", [1, 3, 6, 8])
def test_every_intrinsics_path_gives_one_position_for_every_orientation(tmp_path, capsys, room, orientation):
    stored = np.ascontiguousarray(np.rot90(upright_frame(), STORED[orientation]))
    focal_35mm = round(CAMERA.fx / np.hypot(WIDTH, HEIGHT) * FULL_FRAME_DIAGONAL_MM)
    paths = {  # photo bytes, flags, tolerance to the truth
        "camera": (exif_png(stored, orientation), ["--camera", f"{CAMERA.fx},{CAMERA.fy},{CAMERA.cx},{CAMERA.cy}"]),
        "profile": (exif_png(stored, orientation), ["--profile", "xiaomi-mi8-rear"]),
        "exif_profile": (exif_png(stored, orientation, make="Xiaomi", model="MI 8"), []),
        "exif_35mm": (exif_png(stored, orientation, focal_35mm=focal_35mm), []),
    }
    for source, (data, flags) in paths.items():
        photo = tmp_path / f"{source}.png"
        photo.write_bytes(data)
        code, result = locate(capsys, photo, room, *flags)
        assert code == 0 and result["camera_used"]["source"] == source, result
        tolerance = 3 * FOCAL_SIGMA_EXIF_35MM * DISTANCE_M if source == "exif_35mm" else 0.005
        assert_near_truth(result, tolerance)


@pytest.mark.parametrize("orientation", [1, 3, 6, 8])
def test_a_calibrated_profile_turns_with_the_photo(tmp_path, capsys, room, orientation):
    """A portrait (upright) calibration fits every orientation; a landscape one, calibrated from the stored
    sensor rows, fits the photos a phone turns upright by a quarter clockwise (EXIF 6, or turned already)."""
    stored = np.ascontiguousarray(np.rot90(shifted_frame(), STORED[orientation]))
    photo = tmp_path / "photo.png"
    photo.write_bytes(exif_png(stored, orientation))
    portrait = calibrated_profile(tmp_path / "portrait.json", SHIFTED, WIDTH, HEIGHT, "cal-portrait")
    code, result = locate(capsys, photo, room, "--profile", str(portrait))
    assert code == 0
    assert_near_truth(result, 0.005)
    if orientation in (1, 6):
        sensor = turn_intrinsics(SHIFTED, WIDTH, HEIGHT, 8)  # the sensor's rows: upright turned back
        landscape = calibrated_profile(tmp_path / "landscape.json", sensor, HEIGHT, WIDTH, "cal-landscape")
        code, turned = locate(capsys, photo, room, "--profile", str(landscape))
        assert code == 0
        assert turned["camera_used"]["cx"] == pytest.approx(SHIFTED.cx)
        assert turned["camera_used"]["cy"] == pytest.approx(SHIFTED.cy)
        assert np.linalg.norm(np.subtract(turned["position_m"], result["position_m"])) < 1e-4


def test_a_mirrored_orientation_is_refused(tmp_path, capsys, room):
    photo = tmp_path / "photo.png"
    photo.write_bytes(exif_png(upright_frame(), 2))
    code, result = locate(capsys, photo, room, "--profile", "xiaomi-mi8-rear")
    assert code == 2 and result["field"] == "orientation" and "mirrored EXIF orientation 2" in result["message"]


def test_a_refusal_says_which_intrinsics_it_tried(tmp_path, capsys, room):
    photo = tmp_path / "dark.png"
    photo.write_bytes(exif_png(np.zeros((HEIGHT, WIDTH), np.uint8), 6))
    code, result = locate(capsys, photo, room, "--profile", "xiaomi-mi8-rear")
    assert code == 1 and not result["ok"]
    assert result["camera_used"]["profile"] == "xiaomi-mi8-rear" and "EXIF orientation 6" in result["camera_used"]["detail"]


def test_http_caps_a_photo_at_what_a_y8_upload_holds_and_names_query_parameters(server_url, tmp_path):
    with httpx.Client(base_url=server_url) as http:
        response = http.post(
            "/v1/locate", content=png_claiming(3_000, 3_000), headers={"Content-Type": "image/png"},
            params={"profile": "xiaomi-mi8-rear"},
        )
        assert response.status_code == 400, response.text
        # the session server's max_upload_mb is 4: a Y8 frame of 4 MiB holds 4.194 megapixels
        assert "3000x3000 pixels, more than the 4.194 megapixels allowed" in response.json()["message"]
        response = http.post("/v1/locate", content=jpeg(upright_frame()), headers={"Content-Type": "image/jpeg"})
        message = response.json()["message"]
        assert response.status_code == 400 and "?profile=ID" in message and "?camera=" in message, message
        assert "--profile" not in message
        response = http.post("/v1/locate", content=jpeg(upright_frame()), headers={"Content-Type": "image/jpeg"},
                             params={"camera": "1,2"})
        assert response.status_code == 400 and "--camera" not in response.json()["message"]


def test_client_locate_photo_keeps_its_options(server_url, capsys, tmp_path):
    photo = tmp_path / "photo.jpg"
    photo.write_bytes(jpeg(upright_frame(), make="Xiaomi", model="MI 8"))
    picture = tmp_path / "seen.png"
    url = ["client", "--url", server_url, "locate", str(photo)]
    assert main([*url, "--annotate", str(picture), "--device", "phone-1", "--json"]) == 0
    captured = capsys.readouterr()
    assert_near_truth(json.loads(captured.out), 0.005)
    assert Image.open(picture).format == "PNG" and captured.err == f"picture: {picture}\n"  # as `locate` says
    assert main([*url, "--annotate", str(picture)]) == 0  # the summary, as `lumipose locate PHOTO` prints it
    assert "focal uncertainty 1.5 %, about " in capsys.readouterr().out  # the fix's distance from the map
    assert main([*url, "--annotate", str(tmp_path / "seen.jpg")]) == 2  # not PNG bytes under a JPEG's name
    assert "--annotate" in capsys.readouterr().err and not (tmp_path / "seen.jpg").exists()
    assert main([*url, "--beacon-id", "200", "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["field"] == "beacon_id"
    profile = tmp_path / "mine.json"
    profile.write_text(REAR.model_dump_json())
    assert main([*url, "--profile", str(profile), "--json"]) == 2
    error = json.loads(capsys.readouterr().out)
    assert error["field"] == "profile" and "client profiles put" in error["message"]
