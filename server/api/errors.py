"""Every error of the API is a 4xx with the contract's ErrorBody naming the field and the problem.

HTTP status codes exist only in this layer: the stages raise `FrameError` or return refusals,
the store raises `StoreError`, and the handlers here turn them into responses.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException

from server.outcomes import FrameError
from server.store import StoreError
from shared_schemas import ErrorBody

log = logging.getLogger("lumipose.api")

# Declared on every router, so the OpenAPI spec says what each 4xx body looks like.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    status: {"model": ErrorBody, "description": text}
    for status, text in {
        400: "unreadable frame, metadata or body",
        401: "missing or wrong API key",
        404: "unknown map or sample",
        408: "upload too slow",
        413: "upload too large",
        415: "unsupported content type or encoding",
        422: "invalid parameter",
    }.items()
}

STORE_STATUS = {"not_found": 404, "bad_name": 400, "name_mismatch": 400}


class ApiError(Exception):
    def __init__(self, status: int, error: str, message: str, field: str | None = None):
        super().__init__(message)
        self.status, self.body = status, ErrorBody(error=error, field=field, message=message)


def error_response(status: int, error: str, message: str, field: str | None = None) -> JSONResponse:
    return JSONResponse(ErrorBody(error=error, field=field, message=message).model_dump(), status_code=status)


def _location(loc: tuple) -> str | None:
    parts = [str(part) for part in loc if part not in ("body", "query", "header", "path")]
    return ".".join(parts) or None


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(ApiError)
    async def _api_error(request: Request, error: ApiError) -> JSONResponse:
        return JSONResponse(error.body.model_dump(), status_code=error.status)

    @app.exception_handler(FrameError)
    async def _frame_error(request: Request, error: FrameError) -> JSONResponse:
        return error_response(400, "bad_frame", error.message, error.field)

    @app.exception_handler(StoreError)
    async def _store_error(request: Request, error: StoreError) -> JSONResponse:
        return error_response(STORE_STATUS.get(error.code, 400), error.code, error.message, error.field)

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

    @app.exception_handler(Exception)
    async def _bug(request: Request, error: Exception) -> JSONResponse:
        # A bug, never an answer to bad input: log it whole, tell the client little.
        log.exception("unhandled error on %s %s", request.method, request.url.path)
        return error_response(500, "internal_error", f"the server failed on this request ({type(error).__name__})")
