"""Frame bodies are received into kept buffers (server.api.upload.ReceiveBuffers): one owner, never lent
while anything views them, given back by refused and aborted uploads too, never mixing two requests' bytes."""

import asyncio
import json
import random
import threading
from concurrent.futures import ThreadPoolExecutor

import httpx
import numpy as np
import pytest
from starlette.requests import Request

from server.api.errors import ApiError
from server.api.upload import BUFFER_STEP, BufferLease, ReceiveBuffers, receive_body
from tests.conftest import API_KEY

FRAME_HEADER = "X-Lumipose-Frame"


def test_a_buffer_is_lent_again_only_once_nothing_views_it():
    buffers = ReceiveBuffers(keep=2)
    first = buffers.take(1000)
    assert len(first) == BUFFER_STEP
    pixels = np.frombuffer(memoryview(first)[:1000], np.uint8).reshape(10, 100)[2:5]  # a frame's view
    buffers.give_back(first)
    assert buffers.take(1000) is not first  # still viewed: the next request gets another
    del pixels
    assert buffers.take(1000) is first


def test_at_most_keep_buffers_stay_the_largest_kept():
    buffers = ReceiveBuffers(keep=2)
    small, middle, large = (buffers.take(size) for size in (1, BUFFER_STEP + 1, 2 * BUFFER_STEP + 1))
    for buffer in (small, middle, large):
        buffers.give_back(buffer)
    assert buffers.free == 2
    assert buffers.take(1) is middle  # the smallest that fits; `small` was dropped
    assert buffers.take(1) is large


def test_many_threads_never_share_a_buffer():
    buffers, in_use, lock, clashes = ReceiveBuffers(keep=4), set(), threading.Lock(), []

    def borrow(seed: int) -> None:
        rng = random.Random(seed)
        for _ in range(200):
            size = rng.randint(1, 3 * BUFFER_STEP)
            buffer = buffers.take(size)
            with lock:
                if id(buffer) in in_use:
                    clashes.append(id(buffer))
                in_use.add(id(buffer))
            view = memoryview(buffer)[:size]
            view[:] = bytes([seed]) * size
            assert view.tobytes() == bytes([seed]) * size  # no other thread wrote meanwhile
            view.release()
            with lock:
                in_use.discard(id(buffer))
            buffers.give_back(buffer)

    with ThreadPoolExecutor(8) as pool:
        list(pool.map(borrow, range(8)))
    assert clashes == [] and buffers.free <= 4


def _request(chunks: list[bytes], declared: int, disconnect: bool = False) -> Request:
    messages = [{"type": "http.request", "body": c, "more_body": i < len(chunks) - 1} for i, c in enumerate(chunks)]
    if disconnect:
        messages[-1]["more_body"] = True
        messages.append({"type": "http.disconnect"})

    async def receive():
        return messages.pop(0)

    scope = {"type": "http", "method": "POST", "path": "/", "headers": [(b"content-length", str(declared).encode())]}
    return Request(scope, receive)


@pytest.mark.parametrize(
    ("chunks", "declared", "disconnect", "status"),
    [
        ([b"a" * 600, b"b" * 450], 1000, False, 400),  # longer than its Content-Length
        ([b"a" * 600, b"b" * 600], 1100, False, 413),  # past the limit while streaming
        ([b"a" * 600], 1000, True, 400),  # the client went away
        ([b"a" * 600], 1000, False, 400),  # shorter than its Content-Length
    ],
)
def test_refused_and_aborted_uploads_give_their_buffer_back(chunks, declared, disconnect, status):
    buffers = ReceiveBuffers(keep=1)
    lease = BufferLease(buffers)
    with pytest.raises(ApiError) as refused:
        asyncio.run(receive_body(_request(chunks, declared, disconnect), 1100, 5.0, lease))
    assert refused.value.status == status
    lease.close()
    lent = buffers.take(1000)  # not viewed by the refused request (its traceback still lives here)
    assert buffers.free == 0 and len(lent) == BUFFER_STEP


def test_a_body_is_received_whole_into_the_lease():
    buffers = ReceiveBuffers(keep=1)
    lease = BufferLease(buffers)
    body = asyncio.run(receive_body(_request([b"ab" * 300, b"c" * 400], 1000), 2000, 5.0, lease))
    assert bytes(body) == b"ab" * 300 + b"c" * 400


def test_concurrent_uploads_of_different_frames_are_stored_unmixed(server_url):
    """Samples of random frames of several sizes, sent at once: each stored frame is the one sent."""
    rng = np.random.default_rng(11)
    sizes = [(64, 48), (96, 64), (80, 60)]
    frames = []
    for n in range(18):
        width, height = sizes[n % len(sizes)]
        meta = {
            "schema": "lumipose.frame/1",
            "width": width,
            "height": height,
            "format": "Y8",
            "camera": {"fx": 60.0, "fy": 60.0, "cx": width / 2, "cy": height / 2},
        }
        frames.append((meta, rng.integers(0, 256, width * height, dtype=np.uint8).tobytes()))

    def store(frame) -> tuple[str, bytes]:
        meta, data = frame
        headers = {"Content-Type": "application/octet-stream", "X-API-Key": API_KEY, FRAME_HEADER: json.dumps(meta)}
        response = httpx.post(f"{server_url}/v1/samples", content=data, headers=headers, timeout=60)
        assert response.status_code == 201, response.text
        return response.json()["id"], data

    with ThreadPoolExecutor(6) as pool:
        stored = list(pool.map(store, frames))
    for sample_id, sent in stored:
        response = httpx.get(f"{server_url}/v1/samples/{sample_id}/frame", timeout=30)
        assert response.status_code == 200 and response.content == sent
        assert httpx.delete(f"{server_url}/v1/samples/{sample_id}", headers={"X-API-Key": API_KEY}).status_code == 204
