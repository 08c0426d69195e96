"""Receive one frame: raw bytes with the frame JSON in a header, or multipart; gzip or zstd.

Limits hold at every step: the declared length, the bytes received, the decompressed size
and the time to receive them, so a huge or slow upload is refused early with a 4xx.
"""

from __future__ import annotations

import asyncio
import threading
import zlib
from dataclasses import dataclass

import zstandard
from starlette.datastructures import UploadFile
from starlette.formparsers import MultiPartException, MultiPartParser
from starlette.requests import ClientDisconnect, Request

from server.api.errors import ApiError
from server.ingest import parse_meta
from shared_schemas import CameraUsed, FrameFormat, FrameMeta
from shared_schemas.fixture_files import PHOTO_TYPES as PHOTO_SUFFIX_TYPES
from shared_schemas.fixture_files import SNIFF_BYTES, sniffed_photo_type

FRAME_HEADER = "X-Lumipose-Frame"
RAW_TYPES = ("application/octet-stream", "image/png")
# A phone photo: no frame JSON, the camera from a profile or intrinsics in the query, or the photo's EXIF.
PHOTO_TYPES = tuple(sorted(set(PHOTO_SUFFIX_TYPES.values())))
# What browsers, old Windows and some apps send for the same formats (the photo reader looks at the bytes anyway)
PHOTO_TYPE_ALIASES = {
    "image/jpg": "image/jpeg",
    "image/pjpeg": "image/jpeg",
    "image/jfif": "image/jpeg",
    "image/mpo": "image/jpeg",
    "image/x-png": "image/png",
    "image/x-heic": "image/heic",
}
UNTYPED = ("", "application/octet-stream")  # a part or body whose sender did not say: its bytes say


def media_type(header: str | None) -> str:
    """A Content-Type header's media type, lower case, with the aliases of photo types made the type itself."""
    media = (header or "").split(";")[0].strip().lower()
    return PHOTO_TYPE_ALIASES.get(media, media)


def _is_photo(media: str, data: bytes | bytearray | memoryview) -> bool:
    """A photo by its type, or by its bytes (JPEG, PNG, HEIF) when it comes untyped."""
    return media in PHOTO_TYPES or (media in UNTYPED and sniffed_photo_type(bytes(data[:SNIFF_BYTES])) is not None)


MULTIPART = "multipart/form-data"
ZSTD_PIECE = 4096


@dataclass(frozen=True)
class FrameUpload:
    meta: FrameMeta
    data: bytes | bytearray | memoryview  # uncompressed frame bytes as the contract's fixture file holds them
    camera_used: CameraUsed | None = None  # a photo's chosen intrinsics (else the frame JSON's camera says)


@dataclass(frozen=True)
class PhotoUpload:
    """A photo (JPEG, PNG or HEIC) sent without frame JSON: decoded by `server.api.params.frame_upload`,
    which knows the service's profiles."""

    data: bytes | bytearray | memoryview


def too_large(limit: int) -> ApiError:
    return ApiError(413, "too_large", f"the body exceeds the limit of {limit} bytes", field="body").closing()


RECEIVE_BUFFER = "lumipose_receive_buffer"  # `request.state` key: a frame route's `BufferLease` (server.api.guard)
BUFFER_STEP = 1 << 20  # buffers come in whole MiB: frames a few bytes apart share one


class ReceiveBuffers:
    """The buffers frame bodies are received into, kept from one request to the next: a fresh 20 MB
    `bytearray` costs ~4,900 page faults, more than the rest of the upload's copies together.

    The pool is their one owner: a buffer is free here or lent to one request (`BufferLease`), and
    lent again only once nothing views it (a `bytearray` refuses to resize while a memoryview or a
    numpy array views it): a view still held when the request gives its buffer back (a worker
    thread's last reference, a result that kept a frame) keeps that buffer from the next request.
    At most `keep` buffers wait here, each no larger than the largest body it held (rounded up to
    `BUFFER_STEP`): no more memory than `keep` frames in flight take anyway. Safe from any thread.
    """

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._free: list[bytearray] = []
        self._lock = threading.Lock()

    def take(self, size: int) -> bytearray:
        """A buffer of at least `size` bytes that nothing views, the caller's alone until `give_back`."""
        with self._lock:
            for buffer in sorted(self._free, key=len):
                if len(buffer) >= size and not _viewed(buffer):
                    self._free.remove(buffer)
                    return buffer
        return bytearray(-(-max(size, 1) // BUFFER_STEP) * BUFFER_STEP)

    def give_back(self, buffer: bytearray) -> None:
        """Keep `buffer` for a later request (the smallest kept is dropped beyond `keep`)."""
        with self._lock:
            self._free.append(buffer)
            if len(self._free) > self.keep:
                self._free.remove(min(self._free, key=len))

    @property
    def free(self) -> int:
        """Buffers kept (some may still be viewed for a moment)."""
        return len(self._free)


def _viewed(buffer: bytearray) -> bool:
    """Whether a memoryview or an array views `buffer` (resizing is refused then): a one-byte shrink
    and regrowth within its allocation, no copy."""
    try:
        del buffer[-1:]
    except BufferError:
        return True
    buffer.append(0)
    return False


class BufferLease:
    """One request's claim on a receive buffer: taken on the first `view`, given back by `close` (the
    route's guard, once the request is answered: its frame is no longer read)."""

    def __init__(self, buffers: ReceiveBuffers) -> None:
        self._buffers = buffers
        self._buffer: bytearray | None = None

    def view(self, size: int) -> memoryview:
        """`size` writable bytes of the lent buffer (what a previous request left there until written)."""
        if self._buffer is None:
            self._buffer = self._buffers.take(size)
        elif len(self._buffer) < size:
            raise ValueError(f"the lease holds {len(self._buffer)} bytes, not {size}")
        return memoryview(self._buffer)[:size]

    def close(self) -> None:
        if self._buffer is not None:
            self._buffers.give_back(self._buffer)
            self._buffer = None


def too_long(expected: int) -> ApiError:
    return ApiError(400, "bad_length", f"the body is longer than its Content-Length {expected}", field="body")


async def receive_body(
    request: Request, limit: int, timeout_s: float, lease: BufferLease | None = None
) -> bytearray | memoryview:
    """The request's body, at most `limit` bytes, within `timeout_s`; 413, 408 or 400 otherwise.

    With a declared length the chunks land in one buffer (`lease`'s when given, else a new one): no
    second copy of a 20 MB frame. They are read from the ASGI channel itself and each written once,
    through a memoryview (a bytearray's slice assignment copies the chunk to a temporary first).
    """
    declared = request.headers.get("content-length")
    expected = int(declared) if declared is not None and declared.isdigit() else None
    if expected is not None and expected > limit:
        raise too_large(limit)
    grown = bytearray()  # without a declared length
    view = None if expected is None else lease.view(expected) if lease else memoryview(bytearray(expected))
    size = 0
    try:
        async with asyncio.timeout(timeout_s):
            more = True
            while more:
                message = await request.receive()
                if message["type"] == "http.disconnect":
                    raise ClientDisconnect()
                chunk, more = message.get("body", b""), message.get("more_body", False)
                end = size + len(chunk)
                if end > limit:
                    raise too_large(limit)
                if view is None:
                    grown += chunk
                elif end > len(view):
                    raise too_long(len(view))
                else:
                    view[size:end] = chunk
                size = end
        if expected is not None and size != expected:
            raise ApiError(
                400, "bad_length", f"the body has {size} bytes but Content-Length says {expected}", field="body"
            )
    except BaseException as error:
        if view is not None:
            view.release()  # the lease's buffer goes back whole: nothing of a refused body views it
        if isinstance(error, TimeoutError):
            late = f"the body took longer than {timeout_s:g} s"
            raise ApiError(408, "timeout", late, field="body").closing() from None
        if isinstance(error, ClientDisconnect):  # a phone that lost its network: not a bug of ours
            raise ApiError(400, "disconnected", "the client went away before the upload was sent", "body") from None
        raise
    return grown if view is None else view


def _unzstd(body: bytes | bytearray | memoryview, limit: int) -> tuple[bytes, bool]:
    # Fed in small pieces so that a bomb is stopped a few megabytes past the limit.
    reader, pieces, size = zstandard.ZstdDecompressor().decompressobj(), [], 0
    for start in range(0, len(body), ZSTD_PIECE):
        pieces.append(reader.decompress(body[start : start + ZSTD_PIECE]))
        size += len(pieces[-1])
        if size > limit or reader.eof:
            break
    return b"".join(pieces), reader.eof


def _decompress(body: bytearray | memoryview, encoding: str, limit: int) -> bytes | bytearray | memoryview:
    """The body without its content encoding, refusing more than `limit` bytes (zip bombs)."""
    if encoding in ("", "identity"):
        return body
    try:
        if encoding in ("gzip", "x-gzip"):
            inflater = zlib.decompressobj(wbits=16 + zlib.MAX_WBITS)
            data = inflater.decompress(body, limit + 1)
            complete = inflater.eof
        elif encoding == "zstd":
            data, complete = _unzstd(body, limit)
        else:
            raise ApiError(
                415,
                "unsupported_encoding",
                f"Content-Encoding '{encoding}' is not supported; use gzip, zstd or none",
                field="Content-Encoding",
            )
    except (zlib.error, zstandard.ZstdError) as error:
        raise ApiError(
            400, "bad_encoding", f"the body is not valid {encoding}: {error}", field="Content-Encoding"
        ) from None
    if len(data) > limit:
        raise too_large(limit)
    if not complete:
        raise ApiError(400, "bad_encoding", f"the {encoding} stream is truncated", field="Content-Encoding")
    return data


async def _multipart_parts(request: Request, body: bytes | bytearray | memoryview) -> tuple[str | None, bytes]:
    """The 'meta' text (None for a photo part, which needs none) and the 'frame' bytes."""

    async def stream():
        yield bytes(body)

    try:
        form = await MultiPartParser(request.headers, stream(), max_files=1, max_fields=2).parse()
    except MultiPartException as error:
        raise ApiError(
            400, "bad_multipart", f"the multipart body cannot be read: {error.message}", field="body"
        ) from None
    meta, frame = form.get("meta"), form.get("frame")
    if meta is None and isinstance(frame, UploadFile):
        head = await frame.read(SNIFF_BYTES)
        await frame.seek(0)
        if _is_photo(media_type(frame.content_type), head):
            data = await frame.read()
            await form.close()
            return None, data
    if meta is None or frame is None:
        raise ApiError(
            400,
            "bad_multipart",
            "a multipart upload needs a 'meta' part (frame JSON) and a 'frame' part (bytes), or only a 'frame' "
            f"part of type {', '.join(PHOTO_TYPES)} (a photo)",
            field="meta" if meta is None else "frame",
        )
    meta_text = (await meta.read()).decode("utf-8", "replace") if isinstance(meta, UploadFile) else meta
    frame_bytes = await frame.read() if isinstance(frame, UploadFile) else frame.encode("latin-1")
    await form.close()
    return meta_text, frame_bytes


async def receive_frame(
    request: Request, frame_header: str | None, limit: int, timeout_s: float
) -> FrameUpload | PhotoUpload:
    """The frame of a locate or sample request, or a photo without frame JSON; raises `ApiError` or
    `FrameError` on bad input."""
    content_type = media_type(request.headers.get("content-type"))
    if content_type not in (*RAW_TYPES, *PHOTO_TYPES, MULTIPART):
        raise ApiError(
            415,
            "unsupported_media_type",
            f"Content-Type '{content_type or '(none)'}' is not accepted; send "
            f"{', '.join(RAW_TYPES)} with the {FRAME_HEADER} header, {MULTIPART}, or a photo "
            f"({', '.join(PHOTO_TYPES)})",
            field="Content-Type",
        )
    received = await receive_body(request, limit, timeout_s, getattr(request.state, RECEIVE_BUFFER, None))
    body = _decompress(received, request.headers.get("content-encoding", "").strip().lower(), limit)
    data: bytes | bytearray | memoryview
    if content_type == MULTIPART:
        meta_text, data = await _multipart_parts(request, body)
        if meta_text is None:
            return PhotoUpload(data)
    elif not frame_header and _is_photo(content_type, body):
        return PhotoUpload(body)
    elif frame_header:
        meta_text, data = frame_header, body
    else:
        raise ApiError(
            400, "missing_metadata", f"the {FRAME_HEADER} header with the frame JSON is missing", field=FRAME_HEADER
        )
    meta = parse_meta(meta_text)
    if content_type == "image/png" and meta.format is not FrameFormat.png:
        meta = meta.model_copy(update={"format": FrameFormat.png})
    return FrameUpload(meta=meta, data=data)
