"""The HTTP connection itself: a deadline and a size limit on a request's line and headers.

uvicorn reads a request's headers with no time limit and no size limit of its own: a client
that sends them at a byte a second holds its connection (and a slot of the server) forever.
`GuardedHttpToolsProtocol` answers 408 and closes when the headers are not complete within
`read_timeout_s` of the connection's start (or of the request's first byte on a kept-alive
connection), and 431 when they pass `max_header_bytes`. `configure` is called by `create_app`
in every worker, before it serves.
"""

from __future__ import annotations

import asyncio
import json

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

_limits = {"read_timeout_s": 30.0, "max_header_bytes": 64 * 1024}


def configure(read_timeout_s: float, max_header_bytes: int) -> None:
    _limits.update(read_timeout_s=read_timeout_s, max_header_bytes=max_header_bytes)


class GuardedHttpToolsProtocol(HttpToolsProtocol):
    _head_deadline: asyncio.TimerHandle | None = None
    _head_bytes = 0

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm_head_deadline()

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self._head_bytes = 0
        self._arm_head_deadline()

    def on_url(self, url: bytes) -> None:
        self._count_head(len(url))
        super().on_url(url)

    def on_header(self, name: bytes, value: bytes) -> None:
        self._count_head(len(name) + len(value))
        super().on_header(name, value)

    def on_headers_complete(self) -> None:
        self._disarm_head_deadline()
        super().on_headers_complete()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm_head_deadline()
        super().connection_lost(exc)

    def _arm_head_deadline(self) -> None:
        if self._head_deadline is None:
            self._head_deadline = self.loop.call_later(_limits["read_timeout_s"], self._head_too_slow)

    def _disarm_head_deadline(self) -> None:
        if self._head_deadline is not None:
            self._head_deadline.cancel()
            self._head_deadline = None

    def _count_head(self, size: int) -> None:
        self._head_bytes += size
        if self._head_bytes > _limits["max_header_bytes"] and not self.transport.is_closing():
            self._refuse(431, "Request Header Fields Too Large", "the request line and headers are too large")

    def _head_too_slow(self) -> None:
        self._head_deadline = None
        if not self.transport.is_closing() and (self.cycle is None or self.cycle.response_complete):
            self._refuse(408, "Request Timeout", "the request headers took too long")

    def _refuse(self, status: int, phrase: str, message: str) -> None:
        error = "timeout" if status == 408 else "headers_too_large"
        body = json.dumps({"error": error, "field": "headers", "message": message}).encode()
        head = (
            f"HTTP/1.1 {status} {phrase}\r\ncontent-type: application/json\r\n"
            f"content-length: {len(body)}\r\nconnection: close\r\n\r\n"
        ).encode()
        self.transport.write(head + body)
        self.transport.close()
