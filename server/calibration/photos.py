"""Calibration photos: the board's views on PNG, JPEG or HEIC photos (read by `server.photos`).

Photos are turned upright by their EXIF orientation, as every photo is (`server.photos`), in the
command, the multipart /v1/calibrations and /v1/calibrations/views alike: a profile calibrated from
portrait photos is portrait, and `server.camera` turns a profile of the transposed shape to fit a photo.
"""

from __future__ import annotations

from collections.abc import Sequence

from server.calibration.board import find_board
from server.photos import MAX_PHOTO_PIXELS, PhotoError, photo_size, read_grey
from shared_schemas.calibration import BoardSpec, BoardView, ViewFit

__all__ = ["PhotoError", "UnreadablePhotos", "find_views"]


class UnreadablePhotos(PhotoError):
    """Not one of the photos can be read (each one's reason in the message): bad input, as one unreadable photo
    sent to /v1/calibrations/views is."""


UNREADABLE = "unreadable: "  # how a left-out photo's note starts when it cannot be read


def _none_readable(skipped: list[ViewFit]) -> UnreadablePhotos:
    """The error when not one photo can be read: each one named with why (bad input, exit 2 / 400)."""
    reasons = [(view.note or "").removeprefix(UNREADABLE) for view in skipped]
    return UnreadablePhotos(f"no photo is readable ({len(skipped)} given): " + "; ".join(reasons))


def photo_sizes(
    photos: Sequence[tuple[str, bytes]], max_pixels: int = MAX_PHOTO_PIXELS
) -> tuple[dict[str, tuple[int, int]], list[ViewFit]]:
    """Each photo's upright size from its header alone (nothing decoded), and the photos left out with why:
    the check a server makes before any other work. Raises UnreadablePhotos when none is readable and
    PhotoError when the photos differ in size (one camera mode only)."""
    sizes, skipped = {}, []
    for name, data in photos:
        try:
            sizes[name] = photo_size(data, name, max_pixels)
        except PhotoError as error:
            skipped.append(ViewFit(name=name, corners=0, note=f"{UNREADABLE}{error}"))
    if not sizes:
        raise _none_readable(skipped)
    distinct = sorted(set(sizes.values()))
    if len(distinct) > 1:
        examples = ", ".join(f"{w}x{h} ('{next(n for n, s in sizes.items() if s == (w, h))}')" for w, h in distinct)
        raise PhotoError(f"the photos must all have one size; got {examples}")
    return sizes, skipped


def find_views(
    photos: Sequence[tuple[str, bytes]], spec: BoardSpec, max_pixels: int = MAX_PHOTO_PIXELS
) -> tuple[list[BoardView], list[ViewFit]]:
    """The board's views on (name, bytes) photos, and the photos left out with why (unreadable, no board).

    Each photo is read as every photo is (`server.photos`): its size from the header against `max_pixels`
    first, then its EXIF, then its pixels; one that fails any of them is left out with why.
    Raises PhotoError when no photo is readable or the photos differ in size (one camera mode only).
    """
    sizes, skipped = photo_sizes(photos, max_pixels)
    views, decoded = [], 0
    first = None  # a set is shot of one print with one camera: what worked on a photo is tried first on the next
    for name, data in photos:
        if name not in sizes:
            continue
        try:
            pixels = read_grey(data, name, max_pixels)
        except PhotoError as error:
            skipped.append(ViewFit(name=name, corners=0, note=f"{UNREADABLE}{error}"))
            continue
        decoded += 1
        view = find_board(pixels, spec, name, first=first)
        if view is None:
            skipped.append(
                ViewFit(
                    name=name,
                    corners=0,
                    note="no board found, as it is, inverted or mirrored (does the board spec match it?)",
                )
            )
        else:
            views.append(view)
            first = (view.inverted, view.mirrored)
    if not decoded:  # every header read, no pixels: as unreadable as no header
        raise _none_readable(skipped)
    return views, skipped
