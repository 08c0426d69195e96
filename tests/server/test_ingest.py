"""Frame ingest: good formats decode without copies, every bad case names its field."""

import json

import cv2
import numpy as np
import pytest

from server.camera import intrinsics_from_profile
from server.ingest import decode_frame, parse_meta, read_fixture
from server.outcomes import FrameError
from shared_schemas import device_profiles

CAMERA = {"fx": 500.0, "fy": 500.0, "cx": 3.5, "cy": 2.5}


def meta(**changes):
    base = {"schema": "lumipose.frame/1", "format": "Y8", "width": 8, "height": 6, "row_stride": 10, "camera": CAMERA}
    return {**base, **changes}


def image():
    return (np.arange(48, dtype=np.uint8).reshape(6, 8) * 5)


def padded(stride=10):
    rows = np.zeros((6, stride), np.uint8)
    rows[:, :8] = image()
    return rows.tobytes()


def test_y8_with_row_padding_and_without_the_last_rows_padding():
    frame = decode_frame(padded(), parse_meta(meta()))
    np.testing.assert_array_equal(frame.pixels, image())
    short = decode_frame(padded()[:-2], parse_meta(meta()))
    np.testing.assert_array_equal(short.pixels, image())


@pytest.mark.parametrize("fmt", ["NV21", "I420"])
def test_yuv_formats_use_the_luma_plane(fmt):
    data = padded() + bytes(30)
    np.testing.assert_array_equal(decode_frame(data, parse_meta(meta(format=fmt))).pixels, image())


def test_png():
    ok, png = cv2.imencode(".png", image())
    frame = decode_frame(png.tobytes(), parse_meta(meta(format="PNG", row_stride=8)))
    np.testing.assert_array_equal(frame.pixels, image())


@pytest.mark.parametrize(
    "changes, data, field, phrase",
    [
        ({}, padded()[:-20], "frame", "needs 60"),
        ({"row_stride": 12}, padded(), "row_stride", "needs 72"),
        ({"row_stride": 6}, padded(), "row_stride", "smaller than width"),
        ({"width": 0}, padded(), "width", "greater than or equal to 1"),
        ({"height": -4}, padded(), "height", "greater than or equal to 1"),
        ({"format": "RGB"}, padded(), "format", "Y8"),
        ({"camera": {**CAMERA, "fx": -1}}, padded(), "camera.fx", "greater than or equal to 1"),
        ({"camera": {"profile": "nokia-3310"}}, padded(), "camera.profile", "unknown device profile"),
        ({"format": "PNG", "row_stride": 8}, cv2.imencode(".png", np.zeros((5, 8), np.uint8))[1].tobytes(), "width", "metadata says"),
        ({"format": "PNG", "row_stride": 8}, cv2.imencode(".png", np.zeros((6, 8, 3), np.uint8))[1].tobytes(), "frame", "channels"),
        ({"format": "PNG", "row_stride": 8}, cv2.imencode(".png", np.zeros((6, 8), np.uint16))[1].tobytes(), "frame", "8-bit"),
    ],
    ids=["truncated", "wrong-stride", "stride-below-width", "zero-width", "negative-height", "unknown-format",
         "negative-fx", "unknown-profile", "png-size", "png-colour", "png-16-bit"],
)
def test_bad_frames_are_named(changes, data, field, phrase):
    with pytest.raises(FrameError) as error:
        decode_frame(data, parse_meta(meta(**changes)))
    assert error.value.field == field
    assert phrase in error.value.message


def test_nan_focal_length_and_bad_json():
    text = json.dumps(meta()).replace('"fx": 500.0', '"fx": NaN')
    with pytest.raises(FrameError, match="camera.fx: Input should be a finite number"):
        parse_meta(text)
    with pytest.raises(FrameError, match="not valid JSON"):
        parse_meta("{width: 3")
    with pytest.raises(FrameError) as error:
        parse_meta(meta(camera={**CAMERA, "fx": float("nan")}))
    assert error.value.field == "camera.fx"


def test_profile_intrinsics_scale_with_the_frame():
    front, rear = device_profiles()["xiaomi-mi8-front"], device_profiles()["xiaomi-mi8-rear"]
    full = intrinsics_from_profile(front, 3880, 5184)
    assert full.fx == pytest.approx(3911.11, abs=0.01) and full.cx == 1939.5
    assert intrinsics_from_profile(front, 970, 1296).fx == pytest.approx(977.78, abs=0.01)
    assert intrinsics_from_profile(rear, 3024, 4032).fx == pytest.approx(3011.43, abs=0.01)


def test_missing_fixture_is_a_frame_error(tmp_path):
    with pytest.raises(FrameError, match="no frame metadata"):
        read_fixture(tmp_path / "nothing.json")


def test_a_profile_scaled_out_of_the_contracts_ranges_is_a_frame_error():
    """A 1 x 1 frame of a 3024 x 4032 profile would have fx = 0.996 px, below the contract's 1 px."""
    with pytest.raises(FrameError) as error:
        decode_frame(bytes(1), parse_meta(meta(width=1, height=1, row_stride=1, camera={"profile": "xiaomi-mi8-rear"})))
    assert error.value.field == "width" and "fx" in error.value.message
