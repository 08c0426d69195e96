"""Every API route is guarded: write routes check their key before any body is read."""

import pytest
import time

import httpx
from fastapi.routing import APIRoute

from server.api.config import Settings
from server.api.deps import require_api_key
from server.api.guard import GuardedRoute
from server.api.main import create_app


def api_routes():
    """The app's API routes (newer FastAPI keeps an included router whole, its routes in `original_router`)."""
    app = create_app(Settings())
    included = [
        route for router in (r for r in app.router.routes if hasattr(r, "original_router"))
        for route in router.original_router.routes if isinstance(route, APIRoute)
    ]
    return [route for route in app.router.routes if isinstance(route, APIRoute)] + included


# POST routes that only compute an answer and store nothing: as open as a GET. A survey stores its
# map only with `"store": true`, and then asks for the key itself (tests/server/api/test_surveys_api.py).
COMPUTING = {"/v1/locate", "/v1/calibrations", "/v1/calibrations/views", "/v1/surveys"}


def test_every_v1_route_is_guarded_and_every_write_but_locate_needs_the_key():
    routes = [r for r in api_routes() if r.path.startswith("/v1")]
    assert len(routes) >= 12
    assert all(isinstance(r, GuardedRoute) for r in routes), [r.path for r in routes if not isinstance(r, GuardedRoute)]
    for route in routes:
        keyed = any(getattr(d, "dependency", None) is require_api_key for d in route.dependencies)
        writes = bool(route.methods - {"GET"}) and route.path not in COMPUTING
        assert keyed == writes, (route.path, route.methods)


def test_keyless_writes_with_big_bodies_are_refused_before_the_body(server_url):
    big = b"x" * (3 << 20)  # under the test server's 4 MB frame limit: only the key stops it
    for method, path, content_type in [("POST", "/v1/samples", "application/octet-stream"),
                                       ("PUT", "/v1/maps/active", "application/json"),
                                       ("PUT", "/v1/maps/some", "application/json"),
                                       ("DELETE", "/v1/samples/" + "0" * 32, "application/json")]:
        start = time.perf_counter()
        response = httpx.request(method, server_url + path, content=big, headers={"Content-Type": content_type},
                                 timeout=10)
        assert response.status_code == 401 and response.json()["field"] == "X-API-Key", (path, response.text)
        assert response.headers.get("connection") == "close"
        assert time.perf_counter() - start < 2.0


def test_the_locate_route_s_direct_reader_reads_every_parameter_fastapi_would():
    """/v1/locate is answered by `locate_directly` (server.api.guard.answers_directly), which reads the
    parameters its endpoint and the endpoint's dependencies declare: the same ones FastAPI reads and the
    OpenAPI spec lists, and the endpoint's other arguments are the four the reader passes."""
    import inspect

    from fastapi.dependencies.utils import get_flat_params  # what the OpenAPI spec lists

    from server.api.params import _locate_query, declared_params, frame_upload
    from server.api.routes.locate import locate_frame

    route = next(r for r in api_routes() if r.path == "/v1/locate")
    by_fastapi = {(p.field_info.in_.value, p.alias) for p in get_flat_params(route.dependant)}
    direct = [declared_params(f) for f in (frame_upload, _locate_query, locate_frame)]
    assert {(p.where, p.alias) for params in direct for p in params.values()} == by_fastapi
    assert [name for name in inspect.signature(locate_frame).parameters if name not in direct[2]] == [
        "request", "services", "upload", "query"]


def test_a_route_answered_directly_refuses_route_dependencies_its_reader_would_skip():
    from fastapi import APIRouter, Depends

    from server.api.guard import GuardedRoute
    from server.api.routes.locate import locate_frame

    def audit() -> None: ...

    router = APIRouter(route_class=GuardedRoute)
    with pytest.raises(TypeError, match="cannot have route dependencies"):  # at the app's start, not a request
        router.add_api_route("/v1/locate", locate_frame, methods=["POST"], dependencies=[Depends(audit)])
