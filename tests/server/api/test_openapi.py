"""The exported OpenAPI spec is what the server serves."""

import json

import httpx

from server.api.openapi import OPENAPI_PATH, rendered_openapi


def test_exported_openapi_is_current():
    assert OPENAPI_PATH.read_text() == rendered_openapi(), (
        f"{OPENAPI_PATH} is stale: run `python -m server.api.openapi`")


def test_server_serves_the_same_paths(server_url):
    served = httpx.get(f"{server_url}/openapi.json").json()
    assert set(served["paths"]) == set(json.loads(OPENAPI_PATH.read_text())["paths"])
