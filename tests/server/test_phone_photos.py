"""Phone photos as phones write them (issue 29 section 3): MPO, any suffix or none, Content-Type aliases, a HEIC cut
short, a cropped photo, 108 MP, a batch with one bad photo, and what "camera unknown" says.

Real photos are in tests/fixtures/phone_photos (manifest.json: sources and licences); the others are the rendered
panel of tests/server/test_photos.py written as a phone would.
"""

import io
import json
import struct
import warnings
from pathlib import Path

import cv2
import httpx
import numpy as np
import pytest
from PIL import Image

from lumipose_cli.main import main
from server.camera import FULL_FRAME_DIAGONAL_MM, exif_scale, photo_camera, profile_table
from server.ingest import decode_photo
from server.locator import locate
from server.outcomes import FrameError
from server import photos
from server.photos import PhotoError, photo_size, read_photo
from shared_schemas import BeaconMap
from shared_schemas.fixture_files import SNIFF_BYTES, sniffed_photo_type
from tests.server.test_photos import CAMERA, HEIGHT, PANEL, WIDTH, assert_near_truth, png_claiming, upright_frame

PHOTOS = Path(__file__).parents[1] / "fixtures" / "phone_photos"
REAL_PHOTOS = Path(__file__).parents[1] / "fixtures" / "real_photos"
FOCAL_35MM = round(CAMERA.fx / np.hypot(WIDTH, HEIGHT) * FULL_FRAME_DIAGONAL_MM)  # the render's lens, as EXIF says


@pytest.fixture
def room(tmp_path):
    path = tmp_path / "room.json"
    path.write_text(BeaconMap(name="room", beacons=[PANEL]).model_dump_json(by_alias=True))
    return path


def exif_bytes(pixel_size=None, focal_35mm=None, make=None, model=None) -> bytes:
    exif = Image.Exif()
    if make:
        exif[0x010F], exif[0x0110] = make, model
    shot = exif.get_ifd(0x8769)
    if focal_35mm is not None:
        shot[0xA405] = focal_35mm
    if pixel_size is not None:
        shot[0xA002], shot[0xA003] = pixel_size
    return exif.tobytes()


def phone_jpeg(pixels: np.ndarray, kind: str = "JPEG", **tags) -> bytes:
    """An RGB JPEG (or MPO, with a second image as cameras add) of grey `pixels` with the EXIF `exif_bytes` takes."""
    image, buffer = Image.fromarray(np.stack([pixels] * 3, axis=-1)), io.BytesIO()
    extra = {"save_all": True, "append_images": [image.resize((64, 48))]} if kind == "MPO" else {}
    image.save(buffer, kind, quality=95, exif=exif_bytes(**tags), **extra)
    return buffer.getvalue()


def locate_json(capsys, *args) -> tuple[int, list[dict]]:
    code = main(["locate", *map(str, args), "--json"])
    out = capsys.readouterr().out
    return code, [json.loads(line) for line in out.splitlines()] if out.startswith('{"') else [json.loads(out)]


# 1. MPO, suffixes, content types


def test_a_real_mpo_is_read_as_its_primary_jpeg():
    data = (PHOTOS / "exif-jpg_tests_22-canon_tags.mpo").read_bytes()
    assert Image.open(io.BytesIO(data)).format == "MPO"
    photo = read_photo(data, "22-canon_tags.mpo")
    primary = read_photo((REAL_PHOTOS / "exif-jpg_tests_22-canon_tags.jpg").read_bytes(), "22-canon_tags.jpg")
    assert photo.kind == "MPO" and photo.pixels.shape == primary.pixels.shape == (480, 640)
    assert np.abs(photo.pixels.astype(int) - primary.pixels).mean() < 3  # re-encoded at q85 from the same pixels
    assert (photo.exif.make, photo.exif.model, photo.exif.focal_length_mm) == ("Canon", "Canon PowerShot SD300", 5.8)


@pytest.mark.parametrize("name", ["photo.mpo", "photo.jpe", "photo.jfif", "IMG_0001", "photo.JPG.part"])
def test_a_photo_is_known_by_its_bytes_whatever_its_name(tmp_path, capsys, room, name):
    photo = tmp_path / name
    kind = "MPO" if name.endswith("mpo") else "JPEG"
    photo.write_bytes(phone_jpeg(upright_frame(), kind=kind, focal_35mm=FOCAL_35MM))
    code, (result,) = locate_json(capsys, photo, "--map", room)
    assert code == 0, result
    assert_near_truth(result, 0.05)


def test_image_jpg_and_untyped_photos_are_accepted_over_http(server_url):
    data = phone_jpeg(upright_frame())
    params = {"profile": "xiaomi-mi8-rear"}
    with httpx.Client(base_url=server_url) as http:
        for content_type in ("image/jpg", "image/pjpeg", "image/JPG; charset=binary", "application/octet-stream"):
            response = http.post("/v1/locate", params=params, content=data, headers={"Content-Type": content_type})
            assert response.status_code == 200 and response.json()["ok"], (content_type, response.text)
        for part_type in ("image/jpg", "application/octet-stream"):
            response = http.post("/v1/locate", params=params, files={"frame": ("p", data, part_type)})
            assert response.status_code == 200 and response.json()["ok"], (part_type, response.text)
        response = http.post("/v1/locate", params=params, content=data, headers={"Content-Type": "image/gif"})
        assert response.status_code == 415


# 2. A HEIC cut short


def test_a_real_heic_cut_short_is_refused_naming_it(tmp_path, capsys, room):
    data = (PHOTOS / "exif-heic_IMG_5195_first25pc.heic").read_bytes()
    cut = r"'IMG_5195.HEIC' is truncated: its HEIF boxes declare 833284 bytes, the file has 208321 \(25 % of it\)"
    with pytest.raises(PhotoError, match=cut):
        read_photo(data, "IMG_5195.HEIC")
    photo = tmp_path / "IMG_5195.HEIC"
    photo.write_bytes(data)
    code, (error,) = locate_json(capsys, photo, "--map", room)
    assert code == 2 and error["error"] == "bad_frame" and "truncated" in error["message"]


@pytest.mark.parametrize("brand", [b"heic", b"heix", b"heim", b"heis", b"mif1", b"msf1"])
def test_every_heif_brand_the_upload_takes_is_named_when_pillow_heif_is_missing(monkeypatch, brand):
    monkeypatch.setattr(photos, "HEIC_READABLE", False)
    header = struct.pack(">I", 24) + b"ftyp" + brand + b"\0\0\0\0" + b"mif1heic"
    assert sniffed_photo_type(header[:SNIFF_BYTES]) in ("image/heic", "image/heif")
    with pytest.raises(PhotoError, match=r"'x.heic' is HEIC, which needs the pillow-heif package"):
        read_photo(header, "x.heic")


# 3. A cropped photo


def test_a_real_cropped_heic_is_refused_for_the_35mm_rule():
    photo = read_photo((PHOTOS / "exif-heic_IMG_5195_cropped.heic").read_bytes(), "IMG_5195.HEIC")
    assert photo.pixels.shape == (3313, 2566) and photo.exif.pixel_size == (4032, 3024)
    with pytest.raises(FrameError, match=r"2566x3313 pixels but its EXIF says the camera wrote 4032x3024") as caught:
        photo_camera(photo.exif, (2566, 3313), profile_table())
    assert caught.value.field == "exif.PixelXDimension" and "principal point is unknown" in caught.value.message


def test_a_given_profile_is_applied_to_a_crop_with_a_note():
    photo = read_photo((PHOTOS / "exif-heic_IMG_5195_cropped.heic").read_bytes(), "IMG_5195.HEIC")
    profile = profile_table()["xiaomi-mi8-rear"]
    given = photo_camera(photo.exif, (2566, 3313), profile_table(), profile=profile)
    assert given.profile == "xiaomi-mi8-rear" and given.detail.startswith("datasheet profile 'xiaomi-mi8-rear'")
    assert "the photo looks cropped from 4032x3024" in given.detail and "principal point may be off" in given.detail
    whole = photo_camera(photo.exif, (3024, 4032), profile_table(), profile=profile)
    assert "cropped" not in whole.detail


def test_a_crop_is_refused_and_a_uniform_downscale_kept(tmp_path, capsys, room):
    full = (WIDTH * 8, HEIGHT * 8)  # the camera's 3024 x 4032: the test photo is its 1/8, or a crop of that
    scaled = tmp_path / "scaled.jpg"
    # the EXIF size landscape, as iPhones write it for a portrait photo
    scaled.write_bytes(phone_jpeg(upright_frame(), pixel_size=full[::-1], focal_35mm=FOCAL_35MM))
    code, (result,) = locate_json(capsys, scaled, "--map", room)
    assert code == 0 and "scaled 0.125 x from the EXIF size 4032x3024" in result["camera_used"]["detail"]
    assert_near_truth(result, 0.05)
    cropped = tmp_path / "cropped.jpg"
    cropped.write_bytes(phone_jpeg(upright_frame()[40:400, 30:330], pixel_size=full, focal_35mm=FOCAL_35MM))
    code, (error,) = locate_json(capsys, cropped, "--map", room)
    assert code == 2 and error["field"] == "exif.PixelXDimension" and "a crop" in error["message"]
    cropped.write_bytes(phone_jpeg(upright_frame()[40:400, 30:330], pixel_size=full, make="Xiaomi", model="MI 8"))
    code, (error,) = locate_json(capsys, cropped, "--map", room)
    assert code == 2 and "the profile its EXIF names ('xiaomi-mi8-rear')" in error["message"]
    crop_camera = f"{CAMERA.fx},{CAMERA.fy},{CAMERA.cx - 30},{CAMERA.cy - 40}"
    code, (result,) = locate_json(capsys, cropped, "--map", room, "--camera", crop_camera)  # the user's word wins
    assert code == 0
    assert_near_truth(result, 0.01)


def test_no_shipped_real_photo_scaled_as_a_whole_passes_for_a_crop():
    for path in sorted(REAL_PHOTOS.glob("*.jpg")):
        photo = read_photo(path.read_bytes(), path.name)
        height, width = photo.pixels.shape
        assert exif_scale(photo.exif, (width, height)) is not None, (path.name, photo.exif.pixel_size)


# 4. 108 MP


def test_a_108_megapixel_jpeg_is_decoded_at_half_size_within_the_bound():
    stored = cv2.resize(upright_frame(), (12000, 9000), interpolation=cv2.INTER_LINEAR)  # 12000 x 9000, as phones
    ok, encoded = cv2.imencode(".jpg", stored, [cv2.IMWRITE_JPEG_QUALITY, 80])
    assert photo_size(encoded.tobytes(), "108mp.jpg") == (6000, 4500)
    photo = read_photo(encoded.tobytes(), "108mp.jpg")
    assert photo.reduction == 2 and photo.pixels.shape == (4500, 6000) and photo.stored_size == (12000, 9000)
    halved = cv2.resize(stored, (6000, 4500), interpolation=cv2.INTER_AREA)  # the mean of each 2 x 2
    assert np.abs(photo.pixels.astype(int) - halved).mean() < 1.0


def test_a_reduced_decode_scales_the_given_camera_and_locates_as_the_full_photo():
    # the panel photographed at twice the size: decoded at 1/2 by a luma bound of a quarter of its pixels
    data = phone_jpeg(cv2.resize(upright_frame(), (2 * WIDTH, 2 * HEIGHT), interpolation=cv2.INTER_LINEAR))
    given = CAMERA.model_copy(update={"fx": 2 * CAMERA.fx, "fy": 2 * CAMERA.fy, "cx": 2 * CAMERA.cx + 0.5,
                                      "cy": 2 * CAMERA.cy + 0.5})  # fmt: skip  # pixel centres: (u + 1/2) 2 - 1/2
    frame, chosen = decode_photo(data, "2x.jpg", camera=given, max_pixels=WIDTH * HEIGHT)
    assert frame.pixels.shape == (HEIGHT, WIDTH) and "decoded at 1/2" in chosen.detail
    assert (frame.camera.fx, frame.camera.cx, frame.camera.cy) == pytest.approx((CAMERA.fx, CAMERA.cx, CAMERA.cy))
    result = locate(frame, BeaconMap(name="room", beacons=[PANEL]))
    assert_near_truth(result.model_dump(), 0.005)


def test_a_95_megapixel_header_raises_no_pillow_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(PhotoError, match="cannot be decoded"):  # the header is read, the pixels are not there
            read_photo(png_claiming(11_000, 8_700), "95mp.png")


# 5. A batch with one unreadable photo


def test_one_unreadable_photo_is_its_own_line_in_a_batch(tmp_path, capsys, room):
    good, bad = tmp_path / "a.jpg", tmp_path / "b.jpg"
    good.write_bytes(phone_jpeg(upright_frame(), focal_35mm=FOCAL_35MM))
    bad.write_bytes(good.read_bytes()[:3000])
    code, lines = locate_json(capsys, good, bad, good, "--map", room)
    assert code == 2 and len(lines) == 3
    assert lines[0]["ok"] and lines[2]["ok"]
    assert lines[1] == {"error": "bad_frame", "field": "frame", "message": lines[1]["message"]}
    assert "'b.jpg' cannot be decoded" in lines[1]["message"]
    assert main(["locate", str(good), str(bad), "--map", str(room)]) == 2
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and out[1].startswith("b.jpg  error: 'b.jpg' cannot be decoded")


# 6. What "camera unknown" says


def test_camera_unknown_names_the_exif_fields_it_has(tmp_path, capsys, room):
    photo = tmp_path / "acme.jpg"
    exif = Image.Exif()
    exif[0x010F], exif[0x0110] = "Acme", "Phone 1"
    exif.get_ifd(0x8769)[0x920A] = 4.2
    buffer = io.BytesIO()
    Image.fromarray(upright_frame()).save(buffer, "JPEG", exif=exif.tobytes())
    photo.write_bytes(buffer.getvalue())
    code, (error,) = locate_json(capsys, photo, "--map", room)
    assert code == 2 and "its EXIF has Make, Model, FocalLength)" in error["message"], error
