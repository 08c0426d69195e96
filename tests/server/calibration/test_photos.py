"""Photos in: PNG or JPEG, grey or colour, sizes checked before decoding, each problem named."""

import io

import numpy as np
import pytest
from PIL import Image

from server.calibration.board import find_board
from server.calibration.photos import find_views
from server.photos import PhotoError, photo_size
from server.photos import read_grey as read_photo
from simulator.board import PoseSet
from tests.calibration_photos import BOARD, encoded, photo_set


def test_png_and_jpeg_grey_or_colour_read_as_grey():
    photo = photo_set(PoseSet.good)[0][0]
    assert np.array_equal(read_photo(encoded(photo), "a.png"), photo)
    assert np.array_equal(read_photo(encoded(photo, colour=True), "b.png"), photo)
    jpeg = read_photo(encoded(photo, ".jpg"), "c.jpg")
    assert jpeg.shape == photo.shape and np.abs(jpeg.astype(int) - photo).mean() < 2


def test_other_formats_and_damaged_files_are_named():
    buffer = io.BytesIO()
    Image.new("L", (8, 8)).save(buffer, "GIF")
    with pytest.raises(PhotoError, match="'g.gif' is a GIF image; give a JPEG, PNG or HEIC"):
        photo_size(buffer.getvalue(), "g.gif")
    with pytest.raises(PhotoError, match="'x.png' is not a readable JPEG, PNG or HEIC"):
        read_photo(b"\x89PNG\r\n\x1a\n garbage", "x.png")
    truncated = encoded(photo_set(PoseSet.good)[0][0])[:2000]
    with pytest.raises(PhotoError, match="'t.png'"):
        read_photo(truncated, "t.png")


def test_a_photo_too_large_is_refused_before_decoding():
    with pytest.raises(PhotoError, match="640x480 pixels, more than the 0.1 megapixels allowed"):
        read_photo(encoded(photo_set(PoseSet.good)[0][0]), "big.png", max_pixels=100_000)


def test_find_views_lists_what_it_leaves_out():
    photos = [(f"p{k}.png", encoded(p)) for k, p in enumerate(photo_set(PoseSet.good)[0][:3])]
    blank = ("blank.png", encoded(np.full((480, 640), 90, np.uint8)))
    views, skipped = find_views([*photos, blank, ("junk.png", b"junk")], BOARD)
    with_board = [f"p{k}.png" for k, p in enumerate(photo_set(PoseSet.good)[0][:3]) if find_board(p, BOARD, "-")]
    assert [v.name for v in views] == with_board and len(with_board) >= 2
    notes = {v.name: v.note for v in skipped}
    assert "no board found" in notes["blank.png"] and notes["junk.png"].startswith("unreadable:")
