"""The HTTP connection itself: a deadline and a size limit on a request's line and headers, and
no connection kept open for a body nobody reads.

uvicorn reads a request's headers with no time limit and no size limit of its own: a client
that sends them at a byte a second holds its connection (and a slot of the server) forever.
`GuardedHttpToolsProtocol`
- answers 408 and closes when the headers are not complete within `read_timeout_s` of the
  connection's start (or of the request's first byte on a kept-alive connection);
- answers 431 and closes when they pass `max_header_bytes`, counted as they arrive (one
  endless header line too), and the request is never run;
- closes the connection once a response is sent before its request's body has arrived (an
  early refusal, or a route that reads no body): the rest would otherwise trickle in forever;
- closes an event stream (`endless_paths`) at once when the server shuts down;
- hands a body's chunks to the app as httptools parsed them, not copied twice more (a 20 MB frame
  arrives in ~80 of them).
`configure` is called by `create_app` in every worker, before it serves.
"""

from __future__ import annotations

import asyncio
import json

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

_limits = {"read_timeout_s": 30.0, "max_header_bytes": 64 * 1024}
_endless_paths: set[str] = set()  # responses that never complete by themselves (event streams)


def configure(read_timeout_s: float, max_header_bytes: int, endless_paths: tuple[str, ...] = ()) -> None:
    _limits.update(read_timeout_s=read_timeout_s, max_header_bytes=max_header_bytes)
    _endless_paths.update(endless_paths)


class GuardedHttpToolsProtocol(HttpToolsProtocol):
    _head_deadline: asyncio.TimerHandle | None = None
    _in_head = True  # between a message's first byte (or the connection's start) and its headers' end
    _head_bytes = 0  # bytes received while in the head (an unfinished line counts too)
    _head_exact = 0  # the parsed request line and headers
    _body_done = True
    _refused = False

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm_head_deadline()

    def data_received(self, data: bytes) -> None:
        if self._refused:
            return
        if self._in_head:
            self._head_bytes += len(data)
        super().data_received(data)
        # still in the head after all of it was parsed: all of `data` was head
        if self._in_head and self._head_bytes > _limits["max_header_bytes"]:
            self._refuse(431, "Request Header Fields Too Large", "the request line and headers are too large")

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self._body_done = False
        self._arm_head_deadline()

    def on_url(self, url: bytes) -> None:
        self._head_exact += len(url)
        super().on_url(url)

    def on_header(self, name: bytes, value: bytes) -> None:
        self._head_exact += len(name) + len(value)
        super().on_header(name, value)

    def on_headers_complete(self) -> None:
        too_large = self._head_exact > _limits["max_header_bytes"]
        self._in_head, self._head_bytes, self._head_exact = False, 0, 0
        self._disarm_head_deadline()
        if too_large:
            self._refuse(431, "Request Header Fields Too Large", "the request line and headers are too large")
        if self._refused:
            return  # never run a request that was refused
        super().on_headers_complete()

    def on_body(self, body: bytes) -> None:
        if self.cycle is not None and not self.cycle.body:
            # uvicorn appends each chunk to a bytearray and hands on `bytes()` of it: two copies. Onto
            # empty bytes, `+=` keeps the chunk itself and `bytes()` returns it: none (a second
            # chunk before the app reads the first is joined to it, as before).
            self.cycle.body = b""  # type: ignore[assignment]
        super().on_body(body)

    def on_message_complete(self) -> None:
        self._body_done, self._in_head = True, True  # what comes next is the next request's head
        super().on_message_complete()

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self._body_done and not self.pipeline and not self.transport.is_closing():
            self.transport.close()

    def shutdown(self) -> None:
        """A graceful shutdown waits for the answers being sent, but an event stream never ends: close it
        now (the page reconnects to a server that runs) rather than hold the shutdown for its timeout."""
        cycle = self.cycle
        if cycle is not None and not cycle.response_complete and cycle.scope.get("path") in _endless_paths:
            self.transport.close()
            return
        super().shutdown()

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

    def _head_too_slow(self) -> None:
        self._head_deadline = None
        if self._in_head and not self.transport.is_closing():
            self._refuse(408, "Request Timeout", "the request headers took too long")

    def _refuse(self, status: int, phrase: str, message: str) -> None:
        self._refused = True
        if self.cycle is not None and not self.cycle.response_complete:
            # an earlier request on this connection is still being answered: end after that answer
            self.cycle.keep_alive = False
            return
        error = "timeout" if status == 408 else "headers_too_large"
        body = json.dumps({"error": error, "field": "headers", "message": message}).encode()
        head = (
            f"HTTP/1.1 {status} {phrase}\r\ncontent-type: application/json\r\n"
            f"content-length: {len(body)}\r\nconnection: close\r\n\r\n"
        ).encode()
        self.transport.write(head + body)
        self.transport.close()
