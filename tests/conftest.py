"""A real `lumipose serve` (uvicorn) on 127.0.0.1 with its own data folder and an API key."""

from __future__ import annotations

from pathlib import Path

import pytest
import redis

from lumipose_client import Client, read_fixture_files
from simulator.local_server import LocalServer
from tests.redis_server import RedisServer

API_KEY = "test-key"
UPLOAD_LIMIT_MB = 4  # small, so the 'too large' cases are cheap
FIXTURE = Path(__file__).parent / "fixtures" / "bench_1m.json"


@pytest.fixture(scope="session")
def server_url(tmp_path_factory):
    data_dir = tmp_path_factory.mktemp("data")
    with LocalServer("--api-key", API_KEY, "--max-upload-mb", str(UPLOAD_LIMIT_MB), "--log-level", "warning",
                     data_dir=data_dir) as server:
        yield server.url
    assert "Traceback" not in server.log(), server.log()  # no request crashed the server


@pytest.fixture
def client(server_url):
    with Client(server_url, api_key=API_KEY) as lumipose:
        yield lumipose


@pytest.fixture(scope="session")
def fixture_frame():
    return read_fixture_files(FIXTURE)


@pytest.fixture(scope="session")
def redis_server():
    with RedisServer() as server:
        yield server


@pytest.fixture
def redis_url(redis_server):
    """A running Redis, emptied for each test (one server for the session: it starts in milliseconds,
    but the tests that use it start services that read it)."""
    if redis_server.process is None:  # a test stopped it and failed before starting it again
        redis_server.start()
    with redis.Redis.from_url(redis_server.url) as client:
        client.flushall()
    return redis_server.url
