"""Recorded frames sent the way the app sends its captures (docs/vlc.md, docs/android.md).

The app shoots a capture as a pose frame, then a burst of ID frames, and uploads the burst's ID
frames first, then its pose frame: a device's session keeps ID frames for its next pose frame.
`lumipose locate` and `lumipose client locate` take frames listed as shot and send them so.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from shared_schemas.cli import BadInput
from shared_schemas.models import FailureReason, FrameKind, LocateResult


def bursts_in_upload_order(kinds: Sequence[FrameKind]) -> list[list[int]]:
    """The captures of frames listed as shot (indices into `kinds`), each in the order the app sends it.

    A capture is a pose frame and the ID frames listed after it (ID frames before the first pose
    frame are a capture of their own); within it, its ID frames go first, then its pose frame.
    """
    captures: list[list[int]] = []
    for index, kind in enumerate(kinds):
        if kind is FrameKind.pose or not captures:
            captures.append([index])
        else:
            captures[-1].append(index)
    return [capture[1:] + capture[:1] if kinds[capture[0]] is FrameKind.pose else capture for capture in captures]


def all_located(results: Sequence[LocateResult]) -> bool:
    """The commands' exit 0: some frame has a fix and every other one too, or is an ID frame kept for
    its session (`id_frame`: it has no fix of its own). One frame: its fix, as before."""
    kept = [result.ok or result.reason is FailureReason.id_frame for result in results]
    return all(kept) and any(result.ok for result in results)


def add_frame_series_arguments(parser: argparse.ArgumentParser) -> None:
    """`FRAME...`, `--beacon-id` and `--device`, as `lumipose locate` and `lumipose client locate` take them."""
    parser.add_argument(
        "frames",
        type=Path,
        nargs="+",
        metavar="FRAME",
        help="NAME.json, NAME.y, NAME.yuv or NAME.png, or a photo (JPEG, PNG without JSON, HEIC); several "
        "(a walk's, listed as shot) are located in turn, "
        "each capture's ID frames before its pose frame as the app sends them",
    )
    parser.add_argument(
        "--beacon-id",
        type=int,
        metavar="N",
        default=None,
        help="the map beacon the frames see, as the app may send it (default: none; the map or VLC tells)",
    )
    parser.add_argument(
        "--device",
        metavar="NAME",
        default=None,
        help="a device name: the frames go through its session (ID frames, tracking), as the app's do "
        "(default: none, each frame on its own)",
    )


def annotation_path(annotate: Path, frame_path: Path, several: bool) -> Path:
    """Where `--annotate PNG` puts a frame's picture: PNG itself for one frame; for several, one each
    beside it, named PNG's stem, '-', the frame's stem."""
    return annotate.with_name(f"{annotate.stem}-{frame_path.stem}.png") if several else annotate


def annotation_paths(annotate: Path | None, frames: Sequence[Path]) -> list[Path | None]:
    """Each frame's picture for `--annotate PNG` (`annotation_path`), or None without the flag. Two frames
    whose pictures would land on one file (a/x.json and b/x.json) are refused before any work."""
    if annotate is None:
        return [None] * len(frames)
    pictures = [annotation_path(annotate, frame, several=len(frames) > 1) for frame in frames]
    seen: dict[Path, Path] = {}
    for frame, picture in zip(frames, pictures, strict=True):
        if picture in seen:
            raise BadInput(
                f"--annotate: {seen[picture]} and {frame} would both write {picture} (frames with one name)",
                field="annotate",
            )
        seen[picture] = frame
    return list(pictures)
