"""A real `lumipose serve` (uvicorn) on 127.0.0.1 with its own data folder and an API key."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from lumipose_client import Client, read_fixture_files

API_KEY = "test-key"
UPLOAD_LIMIT_MB = 4  # small, so the 'too large' cases are cheap
FIXTURE = Path(__file__).parent / "fixtures" / "bench_1m.json"


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture(scope="session")
def server_url(tmp_path_factory) -> str:
    port, data_dir = _free_port(), tmp_path_factory.mktemp("data")
    log_path = data_dir.parent / "server.log"
    with open(log_path, "w") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "server.cli", "serve", "--port", str(port), "--data", str(data_dir),
             "--api-key", API_KEY, "--max-upload-mb", str(UPLOAD_LIMIT_MB), "--log-level", "warning"],
            stdout=log, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                if httpx.get(f"{url}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"lumipose serve did not start: {log_path.read_text()}")
            time.sleep(0.1)
        yield url
    finally:
        process.terminate()
        process.wait(timeout=10)
    assert "Traceback" not in log_path.read_text(), log_path.read_text()  # no request crashed the server


@pytest.fixture
def client(server_url):
    with Client(server_url, api_key=API_KEY) as lumipose:
        yield lumipose


@pytest.fixture(scope="session")
def fixture_frame():
    return read_fixture_files(FIXTURE)
