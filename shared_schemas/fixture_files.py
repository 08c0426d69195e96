"""A recorded frame on disk: NAME.json beside NAME.y, NAME.yuv or NAME.png.

One reader for the server (`server.ingest.read_fixture`, which decodes the pixels) and the
client (which sends the bytes as they are), so both take the same file and the same format
for it. Only the standard library and the contract's models: no numpy or OpenCV here.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from shared_schemas.models import FrameFormat, FrameMeta

RAW_SUFFIXES = (".y", ".yuv", ".png")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# A phone photo's suffix and the Content-Type it is sent with (client) and accepted as (server).
PHOTO_TYPES = {
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".jpe": "image/jpeg",
    ".jfif": "image/jpeg",
    ".mpo": "image/jpeg",  # a JPEG with an MPF extension (several images, the first the photo)
    ".png": "image/png",
    ".heic": "image/heic",
    ".heif": "image/heif",
}
# ISO-BMFF brands (ftyp) of HEIF still images, HEVC-coded ones first
HEIF_BRANDS = {
    b"heic": "image/heic",
    b"heix": "image/heic",
    b"heim": "image/heic",
    b"heis": "image/heic",
    b"mif1": "image/heif",
    b"msf1": "image/heif",
}
SNIFF_BYTES = 16


def sniffed_photo_type(head: bytes) -> str | None:
    """The Content-Type a photo's first bytes say (JPEG's SOI marker, PNG's signature, a HEIF ftyp box), or None."""
    if head[:3] == b"\xff\xd8\xff":
        return "image/jpeg"
    if head[: len(PNG_SIGNATURE)] == PNG_SIGNATURE:
        return "image/png"
    if head[4:8] == b"ftyp":
        return HEIF_BRANDS.get(head[8:12])
    return None


def photo_type(path: Path) -> str | None:
    """The Content-Type of a photo file, by its content (any suffix or none), else its suffix: a JPEG (MPO too) or
    HEIC/HEIF, or a PNG with no frame JSON beside it (a recorded PNG frame has one); None for anything else,
    recorded frames' raw planes (.y, .yuv) and JSON included."""
    suffix = path.suffix.lower()
    kind = None
    if suffix not in (*RAW_SUFFIXES, ".json") or suffix == ".png":
        try:
            with path.open("rb") as file:
                kind = sniffed_photo_type(file.read(SNIFF_BYTES))
        except OSError:  # not there (a fixture's stem) or unreadable: its reader says which
            kind = None
    kind = kind or PHOTO_TYPES.get(suffix)
    if kind == "image/png" and path.with_suffix(".json").exists():
        return None
    return kind


def fixture_paths(path: Path | str) -> tuple[Path, Path]:
    """(metadata path, frame-bytes path) of the fixture named by any of its files or its stem.

    Raises FileNotFoundError naming what is missing.
    """
    path = Path(path)
    meta_path = path.with_suffix(".json")
    if not meta_path.is_file():
        raise FileNotFoundError(f"no frame metadata at {meta_path}")
    raw_paths = [path] if path.suffix in RAW_SUFFIXES else [path.with_suffix(s) for s in RAW_SUFFIXES]
    raw_path = next((p for p in raw_paths if p.is_file()), None)
    if raw_path is None:
        raise FileNotFoundError(f"no frame data beside {meta_path} (looked for {', '.join(p.name for p in raw_paths)})")
    return meta_path, raw_path


def with_actual_format(meta: FrameMeta, data: bytes) -> FrameMeta:
    """`meta` with the format the frame bytes really have.

    Bytes that start with the PNG signature are a PNG whatever the JSON says (a fixture's JSON
    written for a raw plane, kept beside a PNG of it); raw bytes under a JSON that says PNG are
    read as one Y8 luma plane (its size is checked when the frame is decoded). Otherwise the
    JSON's raw format (Y8, NV21, I420) stands: the bytes cannot tell them apart.
    """
    if data[: len(PNG_SIGNATURE)] == PNG_SIGNATURE:
        actual = FrameFormat.png
    elif meta.format is FrameFormat.png:
        actual = FrameFormat.y8
    else:
        return meta
    return meta if meta.format is actual else meta.model_copy(update={"format": actual})


def read_fixture_files(
    path: Path | str, parse_meta: Callable[[bytes], FrameMeta] = FrameMeta.model_validate_json
) -> tuple[FrameMeta, bytes]:
    """The metadata and frame bytes of a recorded frame, named by any of its files or its stem,
    with the format of the file actually found (`with_actual_format`).

    `parse_meta` reads the JSON (the server passes its own, which names the faulty field).
    Raises FileNotFoundError naming what is missing.
    """
    meta_path, raw_path = fixture_paths(path)
    meta = parse_meta(meta_path.read_bytes())
    data = raw_path.read_bytes()
    return with_actual_format(meta, data), data
