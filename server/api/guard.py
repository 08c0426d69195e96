"""Limits before work: a request's key, size and time are checked before its body is read.

FastAPI reads and parses a route's JSON body before it runs the route's dependencies, so a
map sent without its API key used to be received and parsed whole before the 401 (a 200 MB
body held gigabytes). `GuardedRoute` answers first, from the route's own declarations:
- a route that depends on `require_api_key` gets its key checked before anything is read;
- a route that takes a frame (`frame_upload`) or photos (`photos_body`) gets one of `max_frames_in_flight` slots and its
  declared length checked against `max_upload_bytes`; it reads its body itself, streaming,
  within `read_timeout_s` (`server.api.upload`);
- a frame route given its own reader (`answers_directly`: /v1/locate) skips FastAPI's per-request solving of its
  parameters (a fifth of a window upload's time outside the pipeline): the reader reads them as declared;
- any other route gets its body read here, at most `max_body_bytes` with or without a
  Content-Length, within `read_timeout_s`, a JSON body's nesting bounded, then handed on.
A refusal before the body is read closes the connection after the answer.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Coroutine
from typing import Any

import pydantic_core
from fastapi.routing import APIRoute
from starlette.requests import Request
from starlette.responses import Response
from starlette.types import Message, Receive

from server.api.config import Settings
from server.api.deps import api_key_problem, require_api_key
from server.api.errors import ApiError
from server.api.params import board_upload, frame_upload, photos_body
from server.api.upload import RECEIVE_BUFFER, BufferLease, receive_body, too_large

Reader = Callable[[Request], Awaitable[Response]]
_READERS: dict[Callable[..., Any], Reader] = {}


def answers_directly(endpoint: Callable[..., Any], reader: Reader) -> None:
    """`endpoint`'s requests answered by `reader`, which reads the parameters `endpoint` declares (for the
    OpenAPI spec, and as FastAPI would read them) and calls it: a frame route's fast path."""
    _READERS[endpoint] = reader


class GuardedRoute(APIRoute):
    """An API route whose key and body limits are checked before FastAPI reads its body."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()
        needs_key = any(getattr(d, "dependency", None) is require_api_key for d in self.dependencies)
        takes_frame = any(d.call in (frame_upload, board_upload, photos_body) for d in self.dependant.dependencies)
        skipped = [d for d in self.dependencies if getattr(d, "dependency", None) is not require_api_key]
        if self.endpoint in _READERS and skipped:  # its reader would skip them silently: refuse at start instead
            raise TypeError(f"{self.path}: a route answered directly cannot have route dependencies {skipped}")

        async def guarded(request: Request) -> Response:
            services = request.app.state.services
            settings: Settings = services.settings
            if needs_key:
                problem = api_key_problem(settings.api_key, request.headers.get("x-api-key"))
                if problem is not None:
                    raise problem.closing()
            limit = settings.max_upload_bytes if takes_frame else settings.max_body_bytes
            _check_length(request.headers.get("content-length"), limit)
            if takes_frame:

                async def framed(lease: BufferLease) -> Response:
                    setattr(request.state, RECEIVE_BUFFER, lease)  # where `receive_frame` receives the body
                    return await _READERS.get(self.endpoint, handler)(request)

                return await services.frame_slots.run(settings.read_timeout_s, framed)
            body = await _read_json_body(request, limit, settings.read_timeout_s)
            return await handler(Request(request.scope, _replay(body, request.receive)))

        return guarded


def _check_length(declared: str | None, limit: int) -> None:
    if declared is None:
        return
    if not declared.isdigit():
        raise ApiError(
            400, "bad_length", f"Content-Length '{declared[:40]}' is not a number", "Content-Length"
        ).closing()
    if int(declared) > limit:
        raise too_large(limit)


async def _read_json_body(request: Request, limit: int, timeout_s: float) -> bytes:
    body = bytes(await receive_body(request, limit, timeout_s))
    if body[:1] in (b"{", b"["):
        try:  # pydantic's parser stops at a nesting limit; the standard one recurses until it crashes
            pydantic_core.from_json(body)
        except ValueError as error:
            if "recursion limit" in str(error):
                raise ApiError(400, "too_deep", "the JSON body is nested too deeply", field="body") from None
    return body


def _replay(body: bytes, receive: Receive) -> Receive:
    sent = False

    async def replayed() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()  # after the body only the disconnect is left

    return replayed
