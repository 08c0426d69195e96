"""Python client of the Lumipose service (httpx): `Client` (sync) and `AsyncClient`.

    with Client("http://127.0.0.1:8000") as lumipose:
        result = lumipose.locate_fixture("tests/fixtures/bench_1m.json")
        print(result.position_m)

Every 4xx/5xx answer raises `LumiposeError` carrying the server's ErrorBody.
"""

from lumipose_client.client import (
    AnnotatedResult,
    AsyncClient,
    Client,
    EncodedFrame,
    LumiposeError,
    encode_frame,
    read_fixture_files,
)

__all__ = [
    "AnnotatedResult",
    "AsyncClient",
    "Client",
    "EncodedFrame",
    "LumiposeError",
    "encode_frame",
    "read_fixture_files",
]
