"""A bug in a route is answered as a counted 500 ErrorBody; the app goes on serving."""

import asyncio

import httpx

from server.api.config import Settings
from server.api.main import create_app


def test_an_unhandled_exception_is_a_counted_500_with_an_error_body(tmp_path):
    app = create_app(Settings(data_dir=tmp_path))

    @app.get("/boom")
    async def boom() -> None:
        raise ZeroDivisionError("on purpose")

    async def run() -> tuple[httpx.Response, httpx.Response, str]:
        transport = httpx.ASGITransport(app=app, raise_app_exceptions=True)
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            first = await client.get("/boom")
            after = await client.get("/healthz")
            return first, after, (await client.get("/metrics")).text

    first, after, metrics = asyncio.run(run())
    assert first.status_code == 500
    assert first.json() == {"error": "internal_error", "field": None,
                            "message": "the server failed on this request (ZeroDivisionError)"}
    assert after.status_code == 200
    assert "lumipose_server_errors_total 1.0" in metrics
    assert 'lumipose_requests_total{route="/boom",status="500"} 1.0' in metrics
