"""Phone photos (JPEG, MPO, PNG, HEIC) to an 8-bit luma plane and the EXIF facts the camera model needs.

Luma is taken as the camera made it: a JPEG's own stored Y channel (libjpeg decodes straight to
grey, no RGB round trip), and for RGB sources the BT.601 luma of the encoded (gamma) values, as
JPEG and Camera2 compute it. Sizes are checked from the header before anything is decoded (a
small file may declare 20000 x 20000 pixels). One orientation rule on every path: the pixels are turned
upright by the EXIF orientation's rotation (1, 3, 6, 8) as they are decoded; mirrored orientations (2, 4,
5, 7) are refused, as no phone camera writes them. The size of a photo is its upright size.

A JPEG (or MPO: a JPEG with an MPF extension, read as its first, primary image) larger than the luma bound
(`max_pixels`) is decoded at 1/2, 1/4 or 1/8 by libjpeg's DCT scaling (`Image.draft`): a 108 MP phone photo
becomes 27 MP of luma without the full-size image ever existing. `Photo.reduction` says by how much, so the
camera matrix is scaled with it. A HEIC whose boxes run past the end of the file (cut short) is refused
before decoding: libheif decodes the tiles it has and fills the rest with grey.
"""

from __future__ import annotations

import io
import math
import struct
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
from PIL import Image, UnidentifiedImageError

from shared_schemas.fixture_files import PNG_SIGNATURE, SNIFF_BYTES, sniffed_photo_type

MAX_PHOTO_PIXELS = 100_000_000  # as a frame (server.ingest.MAX_PIXELS): a 50 MP phone photo fits twice
# A JPEG's header may declare up to this many pixels (the largest phone mode is 200 MP, 16320 x 12240): it is
# decoded at a reduction that fits `max_pixels`; its entropy-coded data is still read whole (~1 s at 108 MP).
MAX_JPEG_PIXELS = 210_000_000
JPEG_REDUCTIONS = (1, 2, 4, 8)  # libjpeg's DCT scalings (scale_denom), as Pillow's draft offers them
PHOTO_KINDS = ("JPEG", "MPO", "PNG", "HEIF")
REDUCIBLE_KINDS = ("JPEG", "MPO")  # an MPO's primary image is a baseline JPEG
# Pillow warns above its MAX_IMAGE_PIXELS (89 MP) and refuses above twice that, from the header: our own size
# checks are the guard (MAX_JPEG_PIXELS, `max_pixels`), so Pillow's refusal sits above the largest JPEG we take,
# and its warning (a site-packages path on the user's terminal) is silenced: once here, since
# warnings.catch_warnings around each open is not thread-safe (the API opens photos on many threads).
Image.MAX_IMAGE_PIXELS = MAX_JPEG_PIXELS
warnings.filterwarnings("ignore", category=Image.DecompressionBombWarning, module=r"PIL\.Image")
MIRRORED_ORIENTATIONS = (2, 4, 5, 7)

try:  # HEIC is optional: without pillow-heif it is refused by name
    from pillow_heif import register_heif_opener

    register_heif_opener()
    HEIC_READABLE = True
except ImportError:  # pragma: no cover - the project depends on it
    HEIC_READABLE = False

# EXIF tags (the TIFF/EXIF 2.3 numbers); the Exif sub-IFD holds the shot's settings.
_MAKE, _MODEL, _ORIENTATION, _EXIF_IFD = 0x010F, 0x0110, 0x0112, 0x8769
_EXPOSURE_TIME, _ISO, _FOCAL_LENGTH, _FOCAL_35MM = 0x829A, 0x8827, 0x920A, 0xA405
_PIXEL_X, _PIXEL_Y = 0xA002, 0xA003  # PixelXDimension, PixelYDimension (exiftool: ExifImageWidth, -Height)


class PhotoError(ValueError):
    """A photo that cannot be used; the message names it and what is wrong, `field` the contract's field."""

    def __init__(self, message: str, field: str = "frame") -> None:
        super().__init__(message)
        self.field = field


@dataclass(frozen=True)
class PhotoExif:
    """What a photo's EXIF says about its camera; None where it says nothing (or nonsense)."""

    make: str | None = None
    model: str | None = None
    focal_length_mm: float | None = None
    focal_35mm_mm: float | None = None
    orientation: int = 1  # EXIF 1-8; 6 and 8 mean the stored image is turned a quarter against the display
    exposure_s: float | None = None
    iso: float | None = None
    # the image size the camera wrote, (PixelXDimension, PixelYDimension); editors keep it when they crop
    pixel_size: tuple[int, int] | None = None

    def fields(self) -> list[str]:
        """The EXIF fields this photo has of those the camera model reads (for a message when none suffices)."""
        named = {
            "Make": self.make,
            "Model": self.model,
            "FocalLength": self.focal_length_mm,
            "FocalLengthIn35mmFilm": self.focal_35mm_mm,
            "PixelXDimension/PixelYDimension": self.pixel_size,
        }
        return [name for name, value in named.items() if value is not None]


@dataclass(frozen=True)
class Photo:
    pixels: np.ndarray  # (height, width) uint8 luma, upright (the EXIF orientation applied), read-only
    exif: PhotoExif
    kind: str  # "JPEG", "MPO", "PNG" or "HEIF"
    reduction: int = 1  # the photo's upright size is `reduction` x the pixels' (a JPEG decoded at 1/2, 1/4, 1/8)
    stored_size: tuple[int, int] = (0, 0)  # (width, height) in the file, before the EXIF orientation


# What Pillow and pillow-heif raise on a damaged file: truncated data, a bad EXIF offset or value (a
# negative SLONG is a negative seek), a TIFF header that is none (SyntaxError), libheif's refusals (ValueError,
# RuntimeError for its security limits, for example an `ispe` size that lies).
_DAMAGE = (OSError, ValueError, SyntaxError, EOFError, struct.error, RuntimeError)


@contextmanager
def _reading(name: str) -> Iterator[None]:
    """Any damage met while reading the photo's header, EXIF or pixels, as one PhotoError naming the photo."""
    try:
        yield
    except PhotoError:
        raise
    except Image.DecompressionBombError as error:  # Pillow's own limit, far above ours
        raise PhotoError(f"'{name}' has more than {MAX_PHOTO_PIXELS // 1_000_000} megapixels ({error})") from None
    except _DAMAGE as error:
        raise PhotoError(f"'{name}' cannot be decoded (damaged or truncated: {error})") from None


def _open(data: bytes, name: str) -> Image.Image:
    try:
        image = Image.open(io.BytesIO(data))
    except Image.DecompressionBombError as error:  # Pillow's own limit, far above ours, refused from the header
        raise PhotoError(f"'{name}' has more than {MAX_PHOTO_PIXELS // 1_000_000} megapixels ({error})") from None
    except UnidentifiedImageError:  # its message names the in-memory buffer, not the photo
        raise PhotoError(f"'{name}' is not a readable JPEG, PNG or HEIC photo (not an image file)") from None
    except _DAMAGE as error:
        raise PhotoError(f"'{name}' is not a readable JPEG, PNG or HEIC photo ({error})") from None
    if image.format not in PHOTO_KINDS:
        image.close()
        raise PhotoError(f"'{name}' is a {image.format} image; give a JPEG, PNG or HEIC photo")
    return image


def _iso_boxes_end(data: bytes) -> int:
    """Where the top-level ISO-BMFF boxes of a HEIF file (ftyp, meta, mdat, ...) say the file ends: each box's
    32-bit size, or its 64-bit size after the type when that is 1; a size of 0 runs to the end of the file."""
    at = 0
    while at + 8 <= len(data):
        size = struct.unpack(">I", data[at : at + 4])[0]
        if size == 1 and at + 16 <= len(data):
            size = struct.unpack(">Q", data[at + 8 : at + 16])[0]
        if size < 8:  # 0: to the end of the file; below 8 no box (libheif refuses it)
            return len(data)
        at += size
    return at


def _refuse_cut_heif(data: bytes, name: str) -> None:
    """A HEIC cut short decodes (libheif fills the tiles it lacks with grey): refused from its box sizes."""
    end = _iso_boxes_end(data)
    if end > len(data):
        raise PhotoError(
            f"'{name}' is truncated: its HEIF boxes declare {end} bytes, the file has {len(data)} "
            f"({100 * len(data) / end:.0f} % of it)"
        )


def jpeg_reduction(size: tuple[int, int], max_pixels: int) -> int | None:
    """The smallest of libjpeg's reductions (1, 2, 4, 8) whose decoded image (each side ceil(side / r)) has at
    most `max_pixels`; None when even 1/8 has more."""
    width, height = size
    return next((r for r in JPEG_REDUCTIONS if math.ceil(width / r) * math.ceil(height / r) <= max_pixels), None)


def _refuse_heic_unreadable(data: bytes, name: str) -> None:
    if not HEIC_READABLE and sniffed_photo_type(data[:SNIFF_BYTES]) in ("image/heic", "image/heif"):
        raise PhotoError(f"'{name}' is HEIC, which needs the pillow-heif package (pip install pillow-heif)")


@contextmanager
def _header(data: bytes, name: str, max_pixels: int) -> Iterator[tuple[Image.Image, PhotoExif, int]]:
    """The opened photo, its EXIF and the reduction it is decoded at, in this order: its size from the header
    checked first (before any EXIF or pixel is read: Pillow decodes a whole PNG to find an EXIF chunk after its
    pixels): at most `max_pixels`, or for a JPEG at most MAX_JPEG_PIXELS and a reduction within `max_pixels`;
    then its EXIF, then its orientation; every path (`photo_size`, `read_photo`) reads a photo so."""
    _refuse_heic_unreadable(data, name)
    with _open(data, name) as image:
        reduction = _check_size(image, name, max_pixels)
        if image.format == "HEIF":
            _refuse_cut_heif(data, name)
        with _reading(name):
            exif = _exif(image, data)
        _upright_orientation(exif, name)
        yield image, exif, reduction


def photo_size(data: bytes, name: str, max_pixels: int = MAX_PHOTO_PIXELS) -> tuple[int, int]:
    """The upright (width, height) of the luma `read_photo` gives (a large JPEG's reduced), from the header without
    decoding; PhotoError when it is no photo, too large, has a damaged EXIF, or is mirrored (as `read_photo`)."""
    with _header(data, name, max_pixels) as (image, exif, reduction):
        width, height = (math.ceil(side / reduction) for side in image.size)
        return (height, width) if exif.orientation in (6, 8) else (width, height)


def _check_size(image: Image.Image, name: str, max_pixels: int) -> int:
    """The reduction the photo is decoded at (1 but for a large JPEG), or PhotoError when it is too large."""
    width, height = image.size
    too_many = f"'{name}' has {width}x{height} pixels, more than the"
    if image.format in REDUCIBLE_KINDS:
        if width * height > MAX_JPEG_PIXELS:
            raise PhotoError(f"{too_many} {MAX_JPEG_PIXELS / 1e6:.4g} megapixels allowed")
        reduction = jpeg_reduction(image.size, max_pixels)
        if reduction is None:
            raise PhotoError(
                f"{too_many} {max_pixels / 1e6:.4g} megapixels allowed, even decoded at 1/{JPEG_REDUCTIONS[-1]}"
            )
        return reduction
    if width * height > max_pixels:
        raise PhotoError(f"{too_many} {max_pixels / 1e6:.4g} megapixels allowed")
    return 1


_STRIP_ROWS = 256  # rows of a colour photo turned to luma at a time: a few MB
COLOUR_DECODE_BUDGET_BYTES = 256 << 20  # decoded colour the process's photo decodes hold at once, beyond their luma


class _DecodeBudget:
    """The decoded colour pixels that photo decodes hold at once in this process (Pillow's RGB, RGBA, CMYK or
    palette image, 4 bytes a pixel, before it becomes the 1-byte luma that stays): a decode waits until its copy fits
    the budget, and one larger than the whole budget runs alone. Its only owner is this module (`_COLOUR`)."""

    def __init__(self, limit_bytes: int) -> None:
        self._limit, self._held = limit_bytes, 0
        self._changed = threading.Condition()

    @contextmanager
    def holding(self, size_bytes: int) -> Iterator[None]:
        with self._changed:
            self._changed.wait_for(lambda: self._held == 0 or self._held + size_bytes <= self._limit)
            self._held += size_bytes
        try:
            yield
        finally:
            with self._changed:
                self._held -= size_bytes
                self._changed.notify_all()


_COLOUR = _DecodeBudget(COLOUR_DECODE_BUDGET_BYTES)
# Pillow keeps an image in blocks of 16 MB by default: below glibc's largest mmap threshold (32 MB), so a
# decoded photo's blocks come from the malloc arena of the thread that decoded it and stay in the process
# once freed (six 67-megapixel colour photos left +0.4-0.9 GB behind). Blocks of 64 MB are mapped and unmapped
# whole; an image smaller than a block takes only its own size.
PILLOW_BLOCK_BYTES = 64 << 20
Image.core.set_block_size(PILLOW_BLOCK_BYTES)


def _strip_luma(image: Image.Image) -> np.ndarray:
    """The luma of a decoded image, copied (and for colour converted) a strip at a time into one array: the decoded
    image and the luma are all it holds (no full-size L image, nor the full-size bytes and their chunks that
    `np.asarray(image)` makes: three times the luma at once). Pillow's L conversion is ITU-R BT.601
    (299, 587, 114) on the encoded values, from RGB, RGBA (alpha dropped), palette or CMYK."""
    width, height = image.size
    luma = np.empty((height, width), np.uint8)
    for row in range(0, height, _STRIP_ROWS):
        with image.crop((0, row, width, min(height, row + _STRIP_ROWS))) as strip:
            if strip.mode == "L":
                luma[row : row + strip.height] = np.asarray(strip)
                continue
            with strip.convert("L") as grey:
                luma[row : row + grey.height] = np.asarray(grey)
    return luma


def _luma(image: Image.Image, reduction: int = 1) -> np.ndarray:
    """The photo's luma plane as stored (not yet turned upright); a colour decode within the process's budget.
    A JPEG's at 1/`reduction` of its size, by libjpeg's scaled IDCT (an output pixel is the mean of r x r)."""
    if image.format in REDUCIBLE_KINDS:  # libjpeg hands out the stored Y channel itself
        image.draft("L", (max(1, image.width // reduction), max(1, image.height // reduction)))
    if image.mode in ("I;16", "I;16B", "I", "F"):
        raise PhotoError(f"{image.mode} images are not 8-bit; give an 8-bit photo")
    width, height = image.size
    with _COLOUR.holding(0 if image.mode == "L" else 4 * width * height):
        image.load()
        return _strip_luma(image)


def _positive(value: object) -> float | None:
    try:
        number = float(value)  # type: ignore[arg-type]  # EXIF rationals, ints or junk
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return number if np.isfinite(number) and number > 0 else None


# EXIF strings have no length limit of their own (a 20 MB Model was tried); real makes and models are
# under 40 characters, and they are quoted in a result's camera_used.detail: cut to this many
MAX_EXIF_TEXT = 64


def _text(value: object) -> str | None:
    if isinstance(value, bytes | str):
        value = value[: 4 * MAX_EXIF_TEXT]  # before decoding: a long string is never copied whole
    text = value.decode("ascii", "replace") if isinstance(value, bytes) else value
    return text.strip("\x00 ").strip()[:MAX_EXIF_TEXT] or None if isinstance(text, str) else None


def _png_exif_chunk(data: bytes) -> bytes | None:
    """The data of a PNG's eXIf chunk, before or after its pixels, found by walking the chunk headers."""
    at = len(PNG_SIGNATURE)
    while at + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[at : at + 8])
        if kind == b"eXIf":
            return data[at + 8 : at + 8 + length]
        if kind == b"IEND":
            break
        at += 12 + length  # length, type, data, CRC
    return None


def _exif(image: Image.Image, data: bytes) -> PhotoExif:
    """The camera facts of the photo's EXIF (empty when it has none); a PNG's without decoding its pixels."""
    if image.format == "PNG":
        tags = Image.Exif()
        chunk = _png_exif_chunk(data)
        if chunk:
            tags.load(chunk)
    else:
        tags = image.getexif()
    shot = tags.get_ifd(_EXIF_IFD)
    orientation = tags.get(_ORIENTATION, 1)
    iso = shot.get(_ISO)
    pixel_x, pixel_y = _positive(shot.get(_PIXEL_X)), _positive(shot.get(_PIXEL_Y))
    return PhotoExif(
        make=_text(tags.get(_MAKE)),
        model=_text(tags.get(_MODEL)),
        focal_length_mm=_positive(shot.get(_FOCAL_LENGTH)),
        focal_35mm_mm=_positive(shot.get(_FOCAL_35MM)),
        orientation=orientation if isinstance(orientation, int) and 1 <= orientation <= 8 else 1,
        exposure_s=_positive(shot.get(_EXPOSURE_TIME)),
        iso=_positive(iso[0] if isinstance(iso, tuple) and iso else iso),
        pixel_size=(int(pixel_x), int(pixel_y)) if pixel_x and pixel_y and max(pixel_x, pixel_y) < 2**31 else None,
    )


def _upright_orientation(exif: PhotoExif, name: str) -> int:
    if exif.orientation in MIRRORED_ORIENTATIONS:
        raise PhotoError(
            f"'{name}' has the mirrored EXIF orientation {exif.orientation}, which phone cameras do not write; "
            "give the photo as the camera stored it (orientation 1, 3, 6 or 8)",
            field="orientation",
        )
    return exif.orientation


# EXIF orientation -> the counter-clockwise quarter turns (np.rot90) that show the stored image upright
_UPRIGHT_TURNS = {3: 2, 6: -1, 8: 1}


def read_photo(data: bytes, name: str, max_pixels: int = MAX_PHOTO_PIXELS, upright: bool = True) -> Photo:
    """The photo's luma, turned upright by its EXIF orientation (as stored when not `upright`: the sensor's
    readout rows), and its EXIF; PhotoError names what is wrong.

    Too many pixels are refused from the header before anything else is read, a damaged EXIF and mirrored
    orientations before decoding (`_header`, as `photo_size`).
    """
    with _header(data, name, max_pixels) as (image, exif, reduction):
        kind, size = image.format or "", image.size
        with _reading(name):
            pixels = _luma(image, reduction)
    expected = tuple(math.ceil(side / reduction) for side in size)
    if pixels.shape != (expected[1], expected[0]):
        raise PhotoError(f"'{name}' cannot be decoded (damaged or truncated)")
    turns = _UPRIGHT_TURNS.get(exif.orientation, 0) if upright else 0
    if turns:
        pixels = np.ascontiguousarray(np.rot90(pixels, turns))
    pixels.flags.writeable = False
    return Photo(pixels=pixels, exif=exif, kind=kind, reduction=reduction, stored_size=size)


def read_grey(data: bytes, name: str, max_pixels: int = MAX_PHOTO_PIXELS) -> np.ndarray:
    """The photo as an upright 8-bit grey image (height, width); PhotoError names what is wrong."""
    return read_photo(data, name, max_pixels).pixels
