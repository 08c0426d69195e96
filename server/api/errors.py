"""Every error of the API is a 4xx with the contract's ErrorBody naming the field and the problem.

HTTP status codes exist only in this layer: the stages raise `FrameError` or return refusals,
the store raises `StoreError`, and the handlers here turn them into responses.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException
from starlette.requests import ClientDisconnect
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from server.outcomes import FrameError
from server.store import INSUFFICIENT_STORAGE, UNAVAILABLE, StoreError
from server.tracking.devices import SessionStoreError
from shared_schemas import ErrorBody

log = logging.getLogger("lumipose.api")

# Declared on every router, so the OpenAPI spec says what each 4xx body looks like.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    status: {"model": ErrorBody, "description": text}
    for status, text in {
        400: "unreadable frame, metadata or body",
        401: "missing or wrong API key",
        404: "unknown map, profile or sample",
        408: "headers or body too slow",
        413: "upload or body too large",
        415: "unsupported content type or encoding",
        422: "invalid parameter",
        507: "the data folder has no room for the write (disk full, quota, file size limit); nothing was changed",
        503: "too many frame uploads held at once (frame routes), or Redis (maps, device sessions) cannot be "
        "reached, or a device's session is busy; try again",
    }.items()
}

STORE_STATUS = {
    "not_found": 404,
    "bad_name": 400,
    "name_mismatch": 400,
    "invalid_request": 422,
    "damaged_map": 409,
    "damaged_profile": 409,
    "damaged_sample": 409,
    "bundled_profile": 409,
    "active_map": 409,
    "fixed_map": 409,
    UNAVAILABLE: 503,
    INSUFFICIENT_STORAGE: 507,
}


class ApiError(Exception):
    def __init__(self, status: int, error: str, message: str, field: str | None = None):
        super().__init__(message)
        self.status, self.body = status, ErrorBody(error=error, field=field, message=message)
        self.headers: dict[str, str] = {}

    def closing(self) -> ApiError:
        """The same error, answered on a connection that then closes (its request body is left unread)."""
        self.headers["connection"] = "close"
        return self


def error_response(status: int, error: str, message: str, field: str | None = None) -> JSONResponse:
    return JSONResponse(ErrorBody(error=error, field=field, message=message).model_dump(), status_code=status)


def _location(loc: tuple) -> str | None:
    parts = [str(part) for part in loc if part not in ("body", "query", "header", "path")]
    return ".".join(parts) or None


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(ApiError)
    async def _api_error(request: Request, error: ApiError) -> JSONResponse:
        return JSONResponse(error.body.model_dump(), status_code=error.status, headers=error.headers)

    @app.exception_handler(FrameError)
    async def _frame_error(request: Request, error: FrameError) -> JSONResponse:
        return error_response(400, "bad_frame", error.message, error.field)

    @app.exception_handler(StoreError)
    async def _store_error(request: Request, error: StoreError) -> JSONResponse:
        return error_response(STORE_STATUS.get(error.code, 400), error.code, error.message, error.field)

    @app.exception_handler(SessionStoreError)
    async def _session_store_error(request: Request, error: SessionStoreError) -> JSONResponse:
        # the store, not the request, is at fault: the same frame may succeed later ('busy': at once)
        return error_response(503, error.code, error.message)

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, error: RequestValidationError) -> JSONResponse:
        first = error.errors()[0]
        field = _location(tuple(first.get("loc", ())))
        message = f"{field}: {first['msg']}" if field else first["msg"]
        return error_response(422, "invalid_request", message, field)

    @app.exception_handler(HTTPException)
    async def _http(request: Request, error: HTTPException) -> JSONResponse:
        code = {404: "not_found", 405: "method_not_allowed"}.get(error.status_code, "http_error")
        return error_response(error.status_code, code, str(error.detail))


class BugCatcher:
    """ASGI middleware: an exception no handler took is a bug, never an answer to bad input.

    It is logged whole and counted (`on_bug`), and the client gets a 500 ErrorBody on a
    connection that stays open (Starlette's outermost handler re-raises after its answer, and
    the server then closes the connection).
    """

    def __init__(self, app: ASGIApp, on_bug: Callable[[], None]) -> None:
        self.app, self.on_bug = app, on_bug

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def noting_start(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, noting_start)
        except ClientDisconnect:
            log.info("client went away during %s %s", scope.get("method"), scope.get("path"))
        except Exception as error:
            log.exception("unhandled error on %s %s", scope.get("method"), scope.get("path"))
            self.on_bug()
            if started:  # too late for an answer of our own
                raise
            response = error_response(
                500, "internal_error", f"the server failed on this request ({type(error).__name__})"
            )
            await response(scope, receive, send)
