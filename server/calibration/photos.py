"""Calibration photos: PNG or JPEG bytes to an 8-bit grey image, sizes checked before decoding.

Pixels are taken as stored: an EXIF orientation is ignored, as the app's frames (the sensor's
own rows) are never turned; a profile calibrated from turned photos would not fit them.
"""

from __future__ import annotations

import io
from collections.abc import Sequence

import cv2
import numpy as np
from PIL import Image, UnidentifiedImageError

from server.calibration.board import find_board
from shared_schemas.calibration import BoardSpec, BoardView, ViewFit

MAX_PHOTO_PIXELS = 100_000_000  # as a frame (server.ingest.MAX_PIXELS): a 50 MP phone photo fits twice


class PhotoError(ValueError):
    """A photo that cannot be used; the message names it."""


def photo_size(data: bytes, name: str) -> tuple[int, int]:
    """(width, height) from the photo's header, without decoding it; PhotoError when it is no PNG or JPEG."""
    try:
        with Image.open(io.BytesIO(data)) as image:
            kind, size = image.format, image.size
    except UnidentifiedImageError:  # its message names the in-memory buffer, not the photo
        raise PhotoError(f"'{name}' is not a readable PNG or JPEG photo (not an image file)") from None
    except (OSError, ValueError) as error:
        raise PhotoError(f"'{name}' is not a readable PNG or JPEG photo ({error})") from None
    if kind not in ("PNG", "JPEG"):
        raise PhotoError(f"'{name}' is a {kind} image; give PNG or JPEG photos")
    return size


def read_photo(data: bytes, name: str, max_pixels: int = MAX_PHOTO_PIXELS) -> np.ndarray:
    """The photo as an 8-bit grey image (height, width); PhotoError names what is wrong."""
    width, height = photo_size(data, name)
    if width * height > max_pixels:
        raise PhotoError(f"'{name}' has {width}x{height} pixels, more than {max_pixels // 1_000_000} megapixels")
    flags = cv2.IMREAD_GRAYSCALE | cv2.IMREAD_IGNORE_ORIENTATION
    image = cv2.imdecode(np.frombuffer(data, np.uint8), flags)
    if image is None or image.shape != (height, width):
        raise PhotoError(f"'{name}' cannot be decoded (damaged or truncated)")
    return image


def find_views(photos: Sequence[tuple[str, bytes]], spec: BoardSpec) -> tuple[list[BoardView], list[ViewFit]]:
    """The board's views on (name, bytes) photos, and the photos left out with why (unreadable, no board).

    Raises PhotoError when no photo is readable or the photos differ in size (one camera mode only).
    """
    sizes, skipped = {}, []
    for name, data in photos:
        try:
            sizes[name] = photo_size(data, name)
        except PhotoError as error:
            skipped.append(ViewFit(name=name, corners=0, note=f"unreadable: {error}"))
    if not sizes:
        raise PhotoError("no photo is readable: " + "; ".join(view.note or "" for view in skipped))
    distinct = sorted(set(sizes.values()))
    if len(distinct) > 1:
        examples = ", ".join(f"{w}x{h} ('{next(n for n, s in sizes.items() if s == (w, h))}')" for w, h in distinct)
        raise PhotoError(f"the photos must all have one size; got {examples}")
    views = []
    for name, data in photos:
        if name not in sizes:
            continue
        try:
            view = find_board(read_photo(data, name), spec, name)
        except PhotoError as error:
            skipped.append(ViewFit(name=name, corners=0, note=f"unreadable: {error}"))
            continue
        if view is None:
            skipped.append(ViewFit(name=name, corners=0, note="no board found (does the board spec match it?)"))
        else:
            views.append(view)
    return views, skipped
