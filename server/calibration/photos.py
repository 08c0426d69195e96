"""Calibration photos: the board's views on PNG, JPEG or HEIC photos (read by `server.photos`).

Photos are turned upright by their EXIF orientation, as every photo is (`server.photos`), in the
command, the multipart /v1/calibrations and /v1/calibrations/views alike: a profile calibrated from
portrait photos is portrait, and `server.camera` turns a profile of the transposed shape to fit a photo.
"""

from __future__ import annotations

from collections.abc import Sequence

from server.calibration.board import find_board
from server.photos import PhotoError, photo_size, read_grey
from shared_schemas.calibration import BoardSpec, BoardView, ViewFit

__all__ = ["PhotoError", "find_views"]


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
            view = find_board(read_grey(data, name), spec, name)
        except PhotoError as error:
            skipped.append(ViewFit(name=name, corners=0, note=f"unreadable: {error}"))
            continue
        if view is None:
            skipped.append(ViewFit(name=name, corners=0, note="no board found (does the board spec match it?)"))
        else:
            views.append(view)
    return views, skipped
